"""Overrides of configuration data by dotted key paths, checked against the schema.

``apply_overrides(data, {"time.steps": 8, "mesh.divisions": [8, 4]})`` returns a copy
of the configuration data (a dict as read by :func:`tomllib.load`) with those keys set,
for small test runs of the shipped examples and for parameter sweeps. Every path is
checked against the schema (:mod:`vemwear.config.schema`) before it is set: a
section or key the schema does not have is a one-line :class:`ConfigError` naming the
path, with a did-you-mean. The schema's unions are resolved by the data as they are
(``[mesh]`` by its ``generator``, ``[time]`` by which of ``steps``, ``dt``, ...;
``[contact] p`` by its ``type``), after the overrides before them, so
``{"mesh.generator": "voronoi", "mesh.n_cells": 64}`` works in this order. The values
themselves are validated later, by :func:`vemwear.config.parse_config`.
"""

from __future__ import annotations

import copy
import types
from collections.abc import Mapping
from typing import Annotated, Any, Union, get_args, get_origin

from pydantic import BaseModel, Discriminator, Tag

from .errors import ConfigError, key_path, suggest
from .schema import ConfigFile

__all__ = ["apply_overrides"]

_MISSING = object()


def apply_overrides(data: Mapping[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of configuration ``data`` with the keys of ``overrides`` set.

    Parameters
    ----------
    data : mapping
        Configuration data (the parsed TOML document); not modified.
    overrides : mapping of str to object
        Dotted key paths (``"time.steps"``, ``"contact.p.c"``, ``"mesh.divisions"``)
        and their new values, applied in order (tuples become arrays, as in TOML).
        Missing tables on the way are created.

    Returns
    -------
    dict
        The new data (a deep copy).

    Raises
    ------
    ConfigError
        For a path the schema does not have (``overrides: 'time.stesp': [time] has no
        key 'stesp'; did you mean 'steps'?``), an empty path, or a path through a value
        that is not a table.
    """
    out: dict[str, Any] = copy.deepcopy(dict(data))
    for path, value in overrides.items():
        keys = path.split(".") if isinstance(path, str) else []
        if not keys or not all(keys):
            raise ConfigError(f"overrides: {path!r} is not a dotted key path like 'time.steps'")
        _check_path(out, keys, path)
        node = out
        for i, k in enumerate(keys[:-1]):
            nxt = node.setdefault(k, {})
            if not isinstance(nxt, dict):
                where = ".".join(keys[: i + 1])
                raise ConfigError(f"overrides: {path!r}: {where!r} is a value, not a table")
            node = nxt
        node[keys[-1]] = _toml(value)
    return out


def _toml(value: Any) -> Any:
    """A deep copy with tuples as lists (TOML arrays), so ``(8, 4)`` works like ``[8, 4]``."""
    if isinstance(value, list | tuple):
        return [_toml(v) for v in value]
    if isinstance(value, dict):
        return {k: _toml(v) for k, v in value.items()}
    return copy.deepcopy(value)


def _check_path(data: dict[str, Any], keys: list[str], path: str) -> None:
    """Raise a ConfigError unless the schema has ``keys`` (for the data as it is)."""
    types_: list[Any] = [ConfigFile]
    value: Any = data
    for i, key in enumerate(keys):
        forms: list[str] = []
        models = [m for tp in types_ for m in _models(tp, value, forms)]
        where = key_path(keys[:i]) or "the configuration"
        if not models:
            raise ConfigError(f"overrides: {path!r}: {where} is a value, not a table")
        fields = {n: f for m in models for n, f in _fields(m).items()}
        if key not in fields:
            form = f" in its {forms[0]!r} form" if len(forms) == 1 else ""
            raise ConfigError(
                f"overrides: {path!r}: {where}{form} has no key {key!r}"
                + suggest(key, list(fields))
            )
        types_ = [f for m in models for n, f in _field_types(m).items() if n == key]
        value = value.get(key, _MISSING) if isinstance(value, dict) else _MISSING


def _fields(model: type[BaseModel]) -> dict[str, Any]:
    return {f.alias or n: f for n, f in model.model_fields.items()}


def _field_types(model: type[BaseModel]) -> dict[str, Any]:
    """Each key's annotation, with the field's discriminator put back around it."""
    out = {}
    for key, f in _fields(model).items():
        disc = [m for m in f.metadata if isinstance(m, Discriminator)]
        out[key] = Annotated[f.annotation, disc[0]] if disc else f.annotation
    return out


def _models(tp: Any, value: Any, forms: list[str]) -> list[type[BaseModel]]:
    """The models (tables) an annotation allows for ``value``: the member of a tagged
    union that its discriminator picks for ``value`` (its tag appended to ``forms``),
    or every table form if it picks none (the value is missing or not yet valid)."""
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return [tp]
    origin = get_origin(tp)
    if origin is Annotated:
        inner, *meta = get_args(tp)
        disc = next((m for m in meta if isinstance(m, Discriminator)), None)
        if disc is not None and callable(disc.discriminator) and value is not _MISSING:
            tag = disc.discriminator(value)
            picked = [a for a in get_args(inner) if _tag(a) == tag]
            if picked and tag != "<error>":
                forms.append(str(tag).strip("<>"))
                return _models(picked[0], value, forms)
        return _models(inner, value, forms)
    if origin in (Union, types.UnionType):
        return [m for a in get_args(tp) for m in _models(a, value, forms)]
    return []


def _tag(tp: Any) -> str | None:
    if get_origin(tp) is Annotated:
        return next((m.tag for m in get_args(tp)[1:] if isinstance(m, Tag)), None)
    return None
