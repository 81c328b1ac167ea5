"""The standard files of one run: result arrays, summary, figures and the ParaView series."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..simulate import Result

__all__ = ["FIGURE_NAMES", "FIGURE_NAMES_3D", "FIGURE_NAMES_ADAPTIVE", "write_outputs"]

#: File names of the figures written by :func:`write_outputs`.
FIGURE_NAMES = {
    "contact_profiles": "contact_profiles.png",
    "displacement": "displacement.png",
    "deformed": "deformed.png",
    "time_history": "time_history.png",
    "forces": "forces.png",
}
#: File names of the figures of a 3D run (:mod:`vemwear.post.maps3d`).
FIGURE_NAMES_3D = {
    "contact_maps": "contact_maps.png",
    "contact_line": "contact_line.png",
    "time_history": "time_history.png",
    "forces": "forces.png",
}
#: File names of the figures of an adaptive run (:mod:`vemwear.post.adaptive`).
FIGURE_NAMES_ADAPTIVE = {"contact_profiles": "contact_profiles.png", "meshes": "meshes.png"}


def write_outputs(
    result: Result,
    outdir: str | os.PathLike[str],
    *,
    times: Sequence[float] = (),
    figures: bool = True,
    vtk: bool = True,
    paraview: str = "xdmf",
    extra: dict[str, Any] | None = None,
    between: Callable[[], None] | None = None,
    timings: dict[str, float] | None = None,
) -> dict[str, list[str]]:
    """Write the standard output of one run into an existing directory.

    ``result.npz`` and ``summary.json`` (:func:`vemwear.post.save_result`), the figures
    (contact profiles at ``times``, displacement and deformed mesh at the final level,
    time history; see :data:`FIGURE_NAMES`) and the ParaView series of the stored
    displacements (``solution.xdmf`` + ``solution.h5``, or ``solution.pvd`` +
    ``solution/*.vtu``). A 3D run has the figures of :data:`FIGURE_NAMES_3D` (maps of
    ``w`` and ``u_nu - w`` over the contact face at ``times``, profiles along its middle
    line, time history, forces) and always the PVD series of polyhedral VTU files
    (:mod:`vemwear.post.vtk3d`: XDMF has no polyhedra that meshio or every ParaView
    reader handles).

    Parameters
    ----------
    result : Result
        The finished run.
    outdir : path
        Directory to write into (normally the temporary one of
        :func:`vemwear.runner.atomic_output_dir`).
    times : sequence of float
        Times of the contact-profile figure (levels of the time grid); default: T.
    figures, vtk : bool
        Whether to write the figures and the ParaView series.
    paraview : {"xdmf", "pvd"}
        Format of the ParaView series.
    extra : dict, optional
        Stored under ``inputs.extra`` in ``summary.json``.
    between : callable, optional
        Called after each file (a safe point where a caller's stop request is raised).
    timings : dict, optional
        Receives the seconds of the parts: ``outputs_data`` (``result.npz`` and
        ``summary.json``), ``outputs_figures`` and ``outputs_vtk``.

    Returns
    -------
    dict
        ``{"data": [...], "figures": [...], "vtk": [...]}``: names relative to ``outdir``.
    """
    from .. import post

    step = between or (lambda: None)
    out = Path(outdir)
    written: dict[str, list[str]] = {"data": [], "figures": [], "vtk": []}
    parts = timings if timings is not None else {}
    tick = time.perf_counter()
    post.save_result(result, out, extra=extra)
    parts["outputs_data"] = time.perf_counter() - tick
    written["data"] += ["result.npz", "summary.json"]
    step()
    if result.problem.dim == 3:
        return _outputs3d(result, out, written, times, figures, vtk, parts)
    tick = time.perf_counter()
    if figures:
        from .forces import plot_forces

        _use_agg()
        last = len(result.t) - 1
        tl = list(times) if len(times) else [float(result.t[-1])]
        for draw in (
            lambda: post.plot_contact_profiles(result, tl, out / FIGURE_NAMES["contact_profiles"]),
            lambda: post.plot_displacement(result, last, out / FIGURE_NAMES["displacement"]),
            lambda: post.plot_deformed(result, last, out / FIGURE_NAMES["deformed"]),
            lambda: post.plot_time_history(result, out / FIGURE_NAMES["time_history"]),
            lambda: plot_forces(result, out / FIGURE_NAMES["forces"]),
        ):
            draw()
            step()
        written["figures"] += list(FIGURE_NAMES.values())
    parts["outputs_figures"], tick = time.perf_counter() - tick, time.perf_counter()
    if vtk and paraview == "xdmf":
        from .xdmf import write_xdmf_series

        xdmf = write_xdmf_series(result, out)
        written["vtk"] += [xdmf.name, xdmf.with_suffix(".h5").name]
    elif vtk:
        pvd = post.write_vtk_series(result, out)
        written["vtk"] += [os.path.relpath(pvd, out), pvd.stem]
    parts["outputs_vtk"] = time.perf_counter() - tick
    return written


def _outputs3d(
    result: Result,
    out: Path,
    written: dict[str, list[str]],
    times: Sequence[float],
    figures: bool,
    vtk: bool,
    parts: dict[str, float],
) -> dict[str, list[str]]:
    """The figures and the ParaView series of a 3D run."""
    tick = time.perf_counter()
    if figures:
        _use_agg()
        from .. import post
        from .forces import plot_forces
        from .maps3d import plot_contact_line, plot_contact_maps

        tl = list(times) if len(times) else [float(result.t[-1])]
        plot_contact_maps(result, tl, out / FIGURE_NAMES_3D["contact_maps"])
        plot_contact_line(result, tl, out / FIGURE_NAMES_3D["contact_line"])
        post.plot_time_history(result, out / FIGURE_NAMES_3D["time_history"])
        plot_forces(result, out / FIGURE_NAMES_3D["forces"])
        written["figures"] += list(FIGURE_NAMES_3D.values())
    parts["outputs_figures"], tick = time.perf_counter() - tick, time.perf_counter()
    if vtk:
        from .vtk3d import write_vtk_series3d

        pvd = write_vtk_series3d(result, out)
        written["vtk"] += [os.path.relpath(pvd, out), pvd.stem]
    parts["outputs_vtk"] = time.perf_counter() - tick
    return written


def _use_agg() -> None:
    """Select the non-interactive Agg backend unless the user chose one."""
    if "MPLBACKEND" in os.environ:
        return
    import matplotlib

    matplotlib.use("Agg")
