"""One-line error messages of configuration files: ``FILE: [section] key <problem>``.

:func:`from_validation` turns the first error of a pydantic ``ValidationError`` into a
:class:`ConfigError` (key path, did-you-mean for unknown keys and choices, the unit
hint for values like ``"4 GPa"``, the offending value); :func:`at` and
:func:`from_library` do the same for the ``ValueError`` of a library object (the
physics is checked there), attaching its message to the key it names.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pydantic import ValidationError
    from pydantic_core import PydanticCustomError

__all__ = ["ConfigError", "at", "error", "from_library", "from_validation"]


class ConfigError(ValueError):
    """Invalid input: the message names the file, the key path and the problem."""


_KINDS = {bool: "a boolean", int: "an integer", float: "a float", str: "a string"}
_KINDS.update({list: "an array", dict: "a table"})
_UNIT = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*[A-Za-z%\u00b5]")
_EXPECTED = {
    "float_type": "a number",
    "int_type": "an integer",
    "string_type": "a string",
    "bool_type": "true or false",
    "list_type": "an array",
    "model_type": "a table",
    "dict_type": "a table",
}
_TOML_KINDS = ("number", "string", "array", "table")
#: Prefixes of library messages naming the object, dropped (the key path says it).
_PREFIXES = ("material: ", "compliance: ", "time grid: ", "solver: ")


def kind(v: Any) -> str:
    """``'a float'``, ``'an array'``, ... (the TOML type of a value)."""
    return _KINDS.get(type(v), f"a {type(v).__name__}")


def show(v: Any) -> str:
    """A short ``repr`` of a value."""
    s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."


def got(v: Any) -> str:
    """``'got a string ('4 GPa'); units are not accepted: ...'``."""
    hint = ""
    if isinstance(v, str) and _UNIT.match(v):
        hint = "; units are not accepted: write plain numbers in consistent units "
        hint += "(docs/config.md, 'Units')"
    return f"got {kind(v)} ({show(v)}){hint}"


def suggest(word: str, valid: Sequence[str], fmt: str = "{!r}") -> str:
    """``'; did you mean 'mu'?'`` or the list of valid words."""
    close = difflib.get_close_matches(word, list(valid), n=1, cutoff=0.6)
    if close:
        return f"; did you mean {fmt.format(close[0])}?"
    return f"; valid keys: {', '.join(valid)}" if valid else ""


def error(message: str) -> PydanticCustomError:
    """A validation error with a finished message (attached to the key path)."""
    from pydantic_core import PydanticCustomError

    return PydanticCustomError("config", "{message}", {"message": message})


def _join(where: str, message: str) -> str:
    if not where:
        return message
    return where + ("" if message[:1] in (" ", ":", ".", "[") else " ") + message


def key_path(loc: Sequence[str | int]) -> str:
    """``('contact', 'g', 'values', 1)`` -> ``'[contact] g.values[1]'`` (union tags dropped)."""
    parts = [x for x in loc if not (isinstance(x, str) and x.startswith("<"))]
    if not parts:
        return ""
    out, spaced = (parts[0] if parts[0] == "title" else f"[{parts[0]}]"), False
    for k in parts[1:]:
        out += f"[{k}]" if isinstance(k, int) else ("." if spaced else " ") + k
        spaced = spaced or isinstance(k, str)
    return out


def from_validation(exc: ValidationError, source: str) -> ConfigError:
    """The first error of a pydantic validation as a one-line :class:`ConfigError`."""
    e = exc.errors(include_url=False)[0]
    t, v, ctx, loc = e["type"], e.get("input"), e.get("ctx") or {}, tuple(e["loc"])
    if t == "config":
        msg = str(ctx["message"])
    elif t == "missing":
        *loc, key = loc  # type: ignore[assignment]
        msg = f"missing required key {key!r}" if loc else f"missing required section [{key}]"
        form = str(loc[-1])[1:-1] if loc and str(loc[-1]).startswith("<") else ""
        msg += f" (needed with {form!r})" if form and form not in _TOML_KINDS else ""
    elif t in _EXPECTED:
        msg = f"must be {_EXPECTED[t]}, {got(v)}"
    elif t == "finite_number":
        msg = f"must be a finite number, got {v}"
    elif t == "literal_error":
        choices = re.findall(r"'([^']*)'", str(ctx.get("expected", "")))
        msg = f"must be one of {', '.join(map(repr, choices))}, got {show(v)}"
        if isinstance(v, str) and difflib.get_close_matches(v, choices, n=1, cutoff=0.6):
            msg += suggest(v, choices)
    elif t in ("too_short", "too_long"):
        n = ctx.get("min_length") if t == "too_short" else ctx.get("max_length")
        least = "at least" if t == "too_short" else "at most"
        msg = f"must have {least} {n} entries, got {ctx.get('actual_length')} ({show(v)})"
    else:  # a pydantic message, e.g. a range
        msg = f"{e['msg'][0].lower()}{e['msg'][1:]}, got {show(v)}"
    return ConfigError(f"{source}: {_join(key_path(loc), msg)}")


def from_library(
    exc: Exception, source: str, section: str, keys: Mapping[str, Any] = {}, key: str = ""
) -> ConfigError:
    """A library ``ValueError`` as a :class:`ConfigError` at the key it names.

    Parameters
    ----------
    exc : Exception
        The error; its object prefix (``"time grid: "``, ...) is dropped.
    source : str
        The file name.
    section : str
        E.g. ``"[contact]"``.
    keys : mapping
        The section's keys and raw values: a message that starts with one of these
        keys is attached to it, showing its value (``g = '0.1 - x'``) unless it is a
        number, long, or shown by the message.
    key : str
        The key of any other message (attached as ``[section] key: message``).
    """
    msg = str(exc)
    for prefix in _PREFIXES:
        msg = msg.removeprefix(prefix)
    m = re.match(r"(\w+)([ :].*)", msg)
    if m and m.group(1) in keys:
        name, msg = m.groups()
        value = keys[name]
        shown = not isinstance(value, int | float) and " got " not in msg and len(repr(value)) <= 60
        where = f"{section} {name}" + (f" = {show(value)}" if shown else "")
        return ConfigError(f"{source}: {_join(where, msg.lstrip(' '))}")
    where = f"{section} {key}" if key else section
    return ConfigError(f"{source}: {where}{': ' if key else ' '}{msg}")


@contextmanager
def at(source: str, section: str, keys: Mapping[str, Any] = {}, key: str = "") -> Iterator[None]:
    """Re-raise a library ``ValueError`` of the block with :func:`from_library`."""
    try:
        yield
    except ConfigError:
        raise
    except ValueError as exc:
        raise from_library(exc, source, section, keys, key) from None
