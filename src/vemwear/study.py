"""``vemwear.study``: another name of :mod:`vemwear.studies` (``sweep``, ``fit``, ...).

Names are looked up in :mod:`vemwear.studies` on first use, so importing this module
imports neither Dask nor xarray.
"""

from __future__ import annotations

from typing import Any

from . import studies as _studies

__all__ = list(_studies.__all__)


def __getattr__(name: str) -> Any:
    return getattr(_studies, name)
