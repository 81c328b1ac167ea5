"""``vemwear.study``: another name of :mod:`vemwear.studies` (``sweep``, ``fit``, ...).

Names are looked up in :mod:`vemwear.studies` on first use, so importing this module
imports neither Dask nor xarray.
"""

from __future__ import annotations

from . import studies as _studies
from .util.lazy import lazy_names

__all__ = list(_studies.__all__)
__getattr__, __dir__ = lazy_names(__name__, dict.fromkeys(__all__, _studies.__name__))
