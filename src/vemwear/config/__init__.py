"""Configuration files: the TOML schema, its validation and the problem it describes.

``load_config(path)`` reads a file and returns a :class:`Config` (the
:class:`~vemwear.simulate.Problem`, the solver and output options); any invalid input
is a one-line :class:`ConfigError` naming the file and the key. The schema is
:mod:`vemwear.config.schema` (``config_json_schema()`` is its JSON Schema, printed by
``vemwear schema``); the format is documented in ``docs/config.md``.

Only :class:`ConfigError` is imported eagerly; the rest (pydantic, the library) when
first used.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .errors import ConfigError

if TYPE_CHECKING:
    from .build import Config, OutputOptions, load_config, parse_config
    from .overrides import apply_overrides
    from .reference import config_json_schema, update_reference

__all__ = [
    "Config",
    "ConfigError",
    "OutputOptions",
    "apply_overrides",
    "config_json_schema",
    "load_config",
    "parse_config",
    "update_reference",
]
_WHERE = {
    "apply_overrides": "overrides",
    "config_json_schema": "reference",
    "update_reference": "reference",
}


def __getattr__(name: str) -> Any:
    if name in __all__:
        from importlib import import_module

        return getattr(import_module(f".{_WHERE.get(name, 'build')}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
