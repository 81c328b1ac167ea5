"""Parameter studies and calibration on Dask: ``vemwear sweep`` and ``vemwear fit``.

A client of the library at the level of :mod:`vemwear.paper` (docs/architecture.md):
each run is a configuration run through :mod:`vemwear.runner` into its own output
directory, as a task on a Dask distributed cluster (an embedded ``LocalCluster`` by
default, or any cluster through a ``distributed.Client``).

- :func:`sweep`: a study file (base configuration, axes over dotted config keys, a
  grid, zip, Latin hypercube or Sobol design) -> one :class:`xarray.Dataset`
  (``OUTDIR/study.nc``), figures and a report (:mod:`~vemwear.studies.design`,
  :mod:`~vemwear.studies.execute`, :mod:`~vemwear.studies.tasks`,
  :mod:`~vemwear.studies.layout`, :mod:`~vemwear.studies.dataset`,
  :mod:`~vemwear.studies.plots`).
- :func:`fit`: calibrate kappa (and mu, c, g) against measured wear profiles by
  bounded least squares, the finite-difference Jacobian's runs in parallel
  (:mod:`~vemwear.studies.fitting`).

The format and the use on clusters are in docs/studies.md. Dask and xarray are imported
only when a study runs, so that the ``vemwear`` command starts fast.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..util.lazy import lazy_names

if TYPE_CHECKING:
    from .design import RunSpec, Study, StudyError, load_study
    from .fitting import FitResult, fit, read_measured
    from .sweeps import sweep

_WHERE = {
    "RunSpec": "design",
    "Study": "design",
    "StudyError": "design",
    "load_study": "design",
    "FitResult": "fitting",
    "fit": "fitting",
    "read_measured": "fitting",
    "sweep": "sweeps",
}
__all__ = [
    "FitResult",
    "RunSpec",
    "Study",
    "StudyError",
    "fit",
    "load_study",
    "read_measured",
    "sweep",
]


__getattr__, __dir__ = lazy_names(__name__, {k: f".{v}" for k, v in _WHERE.items()})
