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

from typing import TYPE_CHECKING

from ..util.lazy import lazy_names
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
    "Config": ".build",
    "OutputOptions": ".build",
    "load_config": ".build",
    "parse_config": ".build",
    "apply_overrides": ".overrides",
    "config_json_schema": ".reference",
    "update_reference": ".reference",
}
__getattr__, __dir__ = lazy_names(__name__, _WHERE)
