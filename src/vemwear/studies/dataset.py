"""The result of a study: one xarray Dataset, written as ``OUTDIR/study.nc``.

The file follows the CF conventions 1.10 (``Conventions``, ``history``; ``units`` and
``long_name`` on every numeric variable and coordinate, ``long_name`` on the others;
no ``_FillValue`` on coordinates; counts as integers). vemwear's numbers carry the
configuration's consistent units (docs/config.md, 'Units'), so a ``units`` attribute
names the kind of unit (``"1"`` for dimensionless numbers and counts, ``"s"`` for wall
time, ``"length"``, ``"stress"``, ... in the configuration's units otherwise).

Dimensions: for a ``grid`` design each axis is a dimension named by its key path made
an identifier (``contact.kappa`` -> ``contact_kappa``: :func:`axis_name`; the key path
is its attribute ``config_key``, the list of names ``attrs["axis_variables"]``), so that
``ds.sel(contact_kappa=2.0)`` works, with the axis values as its coordinate; for
``zip``, ``lhs`` and ``sobol`` designs the runs are a dimension ``run`` and each axis is
a coordinate along it. Axis values that are arrays (``mesh.divisions = [16, 8]``)
become strings (``"[16, 8]"``).

Variables per run (NaN for a failed run):

``max_wear``        max of the wear w at the final time T [length]
``worn_volume``     ``sum(omega_a * w_a)`` at T, the worn area (volume per unit depth)
``max_p_soft``      max of the soft-layer pressure ``p_soft`` over every level and node
                    [stress]
``max_p_rigid``     max of the rigid-layer pressure ``p_rigid`` [stress]
``iterations``      solver iterations summed over the steps (an integer; -1 for a
                    failed run)
``wall_time``       seconds the run took on its worker (NaN for runs of an earlier
                    execution whose record is lost)
``status``          ``done`` or ``failed``; ``error`` the failure's message
``run_id``          the run's directory under ``OUTDIR/runs``

An ``[adapt]`` run gives its levels on the contact nodes of all its meshes (each level
piecewise linear along Gamma_C on its own mesh: :func:`~vemwear.post.adaptive_stream.
contact_arrays`), so its maxima are those of its meshes' nodes and ``worn_volume`` that
of its final mesh.

Profiles along Gamma_C over time, ``(..., time, s)``: ``wear``, ``u_nu``, ``p_soft``; force
resultants ``forces`` ``(..., time, part, component)``. When the runs have different
meshes they are interpolated (linearly) onto a common arc-length grid (as many points
as the finest run, from the smallest to the largest arc length); when their time
levels differ, onto the union of their levels (NaN beyond a run's final time). Where
the contact nodes do not have increasing arc lengths (several contact parts) the
profile dimension is ``node``, with ``s`` as a coordinate along it, and runs with
other meshes leave the profiles out (the attribute ``profiles`` says why).

Attributes: the study file's and base configuration's text, the vemwear version,
the design and the counts of this execution.
"""

from __future__ import annotations

import json
import re
import shlex
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .design import Study
from .execute import Execution
from .layout import RUNS_DIR

__all__ = ["SCALARS", "STUDY_NC", "axis_name", "build_dataset", "run_arrays", "write_dataset"]

STUDY_NC = "study.nc"
#: The scalar summaries per run.
SCALARS = (
    "max_wear",
    "worn_volume",
    "max_p_soft",
    "max_p_rigid",
    "iterations",
    "wall_time",
)
#: (long_name, units) of every variable and coordinate (units: the kind of unit in
#: the configuration's consistent units; "1" for dimensionless numbers and counts).
_CF: dict[str, tuple[str, str]] = {
    "max_wear": ("max of the wear w at the final time T", "length"),
    "worn_volume": ("sum of omega_a w_a at T: worn area (volume per unit depth)", "length2"),
    "max_p_soft": ("max of the soft-layer pressure p_soft over t and s", "stress"),
    "max_p_rigid": ("max of the rigid-layer pressure p_rigid over t and s", "stress"),
    "iterations": ("solver iterations summed over the steps (-1: failed run)", "1"),
    "wall_time": ("seconds of the run on its worker", "s"),
    "status": ("status of the run: done or failed", ""),
    "error": ("error of a failed run", ""),
    "run_id": ("directory of the run under OUTDIR/runs", ""),
    "wear": ("wear w of the soft layer", "length"),
    "u_nu": ("normal displacement u_nu at the contact nodes", "length"),
    "p_soft": ("soft-layer pressure p(u_nu - w)", "stress"),
    "forces": ("force resultant on each boundary part (per unit depth in 2D)", "force"),
    "time": ("time", "time (the unit of [time] T)"),
    "s": ("arc length along Gamma_C", "length"),
    "run": ("run index in the design", "1"),
    "part": ("boundary part", ""),
    "component": ("force component", ""),
}
#: Units of the configuration keys that studies vary most (others: "see config_key").
_KEY_UNITS = {
    "contact.kappa": "1/stress",
    "contact.mu": "1",
    "contact.g": "length",
    "contact.p.c": "stress/length",
    "material.lam": "stress",
    "material.eta": "stress",
    "time.T": "time",
    "time.steps": "1",
    "mesh.divisions": "1",
}


def axis_name(key: str) -> str:
    """The variable name of an axis: its key path made a Python identifier
    (``contact.kappa`` -> ``contact_kappa``), for ``ds.sel(contact_kappa=...)``."""
    name = re.sub(r"\W", "_", key)
    return name if name and not name[0].isdigit() else f"_{name}"


def _coord(values: list[Any]) -> NDArray[Any]:
    if all(isinstance(v, bool | int | float) for v in values):
        return np.asarray(values)
    return np.asarray([v if isinstance(v, str) else json.dumps(v) for v in values], dtype=str)


#: Arrays of result.npz the Dataset does not use: the mesh and the displacements (the
#: bulk of a run's file).
_SKIP = ("u", "dofs", "points", "boundary_tags")
_SKIP_PREFIXES = ("cell_", "face_")


def _wanted(name: str) -> bool:
    return name not in _SKIP and not name.startswith(_SKIP_PREFIXES)


def run_arrays(result: Any) -> dict[str, NDArray[Any]]:
    """The arrays of a run's ``result.npz`` that the Dataset uses, from its in-memory
    result (a task hands them back, so the client does not read the file), or from the
    contact arrays of an ``[adapt]`` run (:func:`~vemwear.post.adaptive_stream.
    contact_arrays`)."""
    from ..post.results import result_arrays

    arrays = result if isinstance(result, Mapping) else result_arrays(result)
    return {k: v for k, v in arrays.items() if _wanted(k)}


def _load(out: Path, rid: str) -> dict[str, NDArray[Any]] | None:
    """A finished run's arrays under today's names (a run of an earlier execution may
    have written format 1), or None if its file cannot be read."""
    from ..post.adaptive_stream import contact_arrays, is_adaptive, read_groups
    from ..post.results import NPZ_NAME, upgrade_arrays
    from ..post.stream import STREAM_NAME

    rundir = out / RUNS_DIR / rid
    try:
        if not (rundir / NPZ_NAME).is_file() and is_adaptive(rundir / STREAM_NAME):
            return run_arrays(contact_arrays(read_groups(rundir / STREAM_NAME)))
        with np.load(rundir / NPZ_NAME, allow_pickle=False) as z:
            return upgrade_arrays({k: z[k] for k in z.files if _wanted(k)})
    except (OSError, ValueError, KeyError):
        return None


def _union(ts: list[NDArray[np.float64]]) -> NDArray[np.float64]:
    """The sorted union of time grids, values closer than 1e-12 T merged."""
    allt = np.sort(np.concatenate(ts))
    tol = 1e-12 * max(float(np.abs(allt).max(initial=0.0)), 1.0)
    keep = np.concatenate([[True], np.diff(allt) > tol])
    return np.asarray(allt[keep], dtype=np.float64)


def _interp(x_new: NDArray[Any], x: NDArray[Any], a: NDArray[Any], axis: int) -> NDArray[Any]:
    """Linear interpolation of ``a`` along ``axis`` (NaN outside ``x``); exact copy when
    the grids agree."""
    if x.shape == x_new.shape and np.allclose(x, x_new, rtol=0, atol=1e-12):
        return np.asarray(a, dtype=np.float64)
    if x.size == 1:
        shape = list(a.shape)
        shape[axis] = x_new.size
        out = np.full(shape, np.nan)
        hit = np.isclose(x_new, x[0])
        idx: list[Any] = [slice(None)] * a.ndim
        idx[axis] = hit
        out[tuple(idx)] = np.take(a, [0], axis=axis)
        return out
    from scipy.interpolate import interp1d

    f = interp1d(x, a, axis=axis, bounds_error=False, fill_value=np.nan, assume_sorted=True)
    return np.asarray(f(x_new), dtype=np.float64)


def _arc_grid(results: Mapping[str, Mapping[str, NDArray[Any]]]) -> tuple[Any, str, str]:
    """The common arc-length grid, its dimension name and a note (empty if fine)."""
    ss = [np.asarray(r["contact_s"], dtype=np.float64) for r in results.values()]
    first = ss[0]
    same = all(s.shape == first.shape and np.allclose(s, first, atol=1e-12) for s in ss)
    increasing = all(s.size >= 2 and np.all(np.diff(s) > 0) for s in ss)
    if same:
        return first, ("s" if increasing else "node"), ""
    if not increasing:
        return None, "s", "left out: runs with other meshes and several contact parts"
    lo, hi = min(float(s[0]) for s in ss), max(float(s[-1]) for s in ss)
    return np.linspace(lo, hi, max(s.size for s in ss)), "s", "interpolated onto a common grid"


def build_dataset(study: Study, execution: Execution, out: str | Path) -> Any:
    """The study's Dataset from the runs' arrays (``execution.arrays``, else read from
    their outputs in ``out``) and their records.

    Returns
    -------
    xarray.Dataset
    """
    import xarray as xr

    from .. import __version__

    out = Path(out)
    grid = study.kind == "grid"
    names = {k: axis_name(k) for k in study.keys}
    dims: tuple[str, ...] = tuple(names.values()) if grid else ("run",)
    shape = study.shape
    coords: dict[str, Any] = {}

    def axis_attrs(k: str) -> dict[str, str]:
        return {
            "long_name": f"configuration key {k}",
            "config_key": k,
            "units": _KEY_UNITS.get(k, f"the configuration's unit of {k}"),
        }

    if grid:
        coords = {names[k]: (names[k], _coord(v), axis_attrs(k)) for k, v in study.axes.items()}
    else:
        coords = {"run": ("run", np.arange(len(study.runs)))}
        for k in study.keys:
            coords[names[k]] = ("run", _coord([r.params[k] for r in study.runs]), axis_attrs(k))

    def where(index: int) -> tuple[int, ...]:
        return tuple(int(i) for i in np.unravel_index(index, shape))

    scal = {name: np.full(shape, np.nan) for name in SCALARS}
    text = {n: np.full(shape, "", dtype=object) for n in ("status", "error", "run_id")}
    results: dict[str, dict[str, NDArray[Any]]] = {}
    for r in study.runs:
        at = where(r.index)
        rec = execution.records.get(r.id, {})
        res = None
        if rec.get("status") == "done":
            res = execution.arrays.get(r.id) or _load(out, r.id)
        status = "done" if res is not None else "failed"
        text["status"][at], text["run_id"][at] = status, r.id
        text["error"][at] = rec.get("error") or ("" if res is not None else "no result")
        scal["wall_time"][at] = float(rec.get("wall_time", np.nan))
        if res is None:
            continue
        results[r.id] = res
        wT = np.asarray(res["wear"][-1], dtype=np.float64)
        scal["max_wear"][at] = float(wT.max(initial=0.0))
        scal["worn_volume"][at] = float(np.dot(res["contact_weights"], wT))
        scal["max_p_soft"][at] = float(np.max(res["p_soft"], initial=0.0))
        scal["max_p_rigid"][at] = float(np.max(res["p_rigid"], initial=0.0))
        scal["iterations"][at] = float(np.sum(res["iterations"]))
    iters = np.where(np.isnan(scal["iterations"]), -1, scal["iterations"]).astype(np.int64)
    data: dict[str, Any] = {n: (dims, v) for n, v in scal.items() if n != "iterations"}
    data["iterations"] = (dims, iters)
    data.update({n: (dims, v.astype(str)) for n, v in text.items()})
    created = datetime.now(UTC).isoformat(timespec="seconds")
    source = str(study.path.resolve()) if study.path is not None else "study data"
    attrs: dict[str, Any] = {
        "Conventions": "CF-1.10",
        "history": f"{created}: vemwear {__version__} sweep {shlex.quote(source)}",
        "source": f"vemwear {__version__}: VEM contact with wear, one run per design point",
        "title": study.title,
        "design": study.kind,
        "axes": json.dumps(study.keys),
        "axis_variables": json.dumps(list(names.values())),
        "study_file": str(study.path.resolve()) if study.path is not None else "",
        "study": study.text,
        "base_config_file": str(study.base_path.resolve()),
        "base_config": study.base_text,
        "vemwear_version": __version__,
        "created": created,
        "runs": len(study.runs),
        "runs_computed": execution.computed,
        "runs_skipped": execution.skipped,
        "runs_failed": execution.failed,
        "profiles": "",
    }
    if study.kind in ("lhs", "sobol"):
        attrs.update(samples=study.samples, seed=study.seed)
    if results:
        _profiles(study, results, dims, shape, where, data, coords, attrs)
    ds = xr.Dataset(data, coords=coords, attrs=attrs)
    for name in ds.variables:
        long_name, units = _CF.get(str(name), ("", ""))
        if long_name and "long_name" not in ds[name].attrs:
            ds[name].attrs["long_name"] = long_name
        if units and "units" not in ds[name].attrs:
            ds[name].attrs["units"] = units
    return ds


def _profiles(
    study: Study,
    results: dict[str, dict[str, NDArray[Any]]],
    dims: tuple[str, ...],
    shape: tuple[int, ...],
    where: Any,
    data: dict[str, Any],
    coords: dict[str, Any],
    attrs: dict[str, Any],
) -> None:
    """Add the profiles and forces, on common grids, to ``data`` and ``coords``."""
    t = _union([np.asarray(r["t"], dtype=np.float64) for r in results.values()])
    coords["time"] = ("time", t)
    s, sdim, note = _arc_grid(results)
    attrs["profiles"] = note
    by_id = {r.id: r for r in study.runs}
    if s is not None:
        if sdim == "node":
            coords["s"] = ("node", s)
        else:
            coords["s"] = ("s", s)
        for name in ("wear", "u_nu", "p_soft"):
            arr = np.full((*shape, t.size, s.size), np.nan)
            for rid, res in results.items():
                a = _interp(s, res["contact_s"], res[name], axis=1)
                arr[where(by_id[rid].index)] = _interp(t, res["t"], a, axis=0)
            data[name] = ((*dims, "time", sdim), arr)
    parts = [tuple(str(x) for x in r.get("force_parts", ())) for r in results.values()]
    if parts and parts[0] and all(p == parts[0] for p in parts):
        coords["part"] = ("part", np.asarray(parts[0], dtype=str))
        dim = next(iter(results.values()))["forces"].shape[-1]
        coords["component"] = ("component", np.asarray(["x", "y", "z"][:dim], dtype=str))
        arr = np.full((*shape, t.size, len(parts[0]), 2), np.nan)
        for rid, res in results.items():
            arr[where(by_id[rid].index)] = _interp(t, res["t"], res["forces"], axis=0)
        data["forces"] = ((*dims, "time", "part", "component"), arr)


def write_dataset(ds: Any, path: str | Path) -> Path:
    """Write ``ds`` as netCDF-4 (engine ``h5netcdf``), atomically."""
    from ..util.atomic import atomic_file

    path = Path(path)
    # no _FillValue on coordinates (CF); the scalars keep NaN for a failed run
    encoding = {str(c): {"_FillValue": None} for c in ds.coords}
    with atomic_file(path) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf", encoding=encoding)
    return path
