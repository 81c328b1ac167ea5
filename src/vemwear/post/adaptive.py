"""ParaView output of an adaptive run (docs/method.md, section 11): every level on the
mesh it was computed on.

:func:`write_adaptive_series` writes one ``.vtu`` per owned level of every segment of
:func:`~vemwear.simulate.adaptive_time.simulate_adaptive`, each with its own mesh and the
fields of :func:`~vemwear.post.vtk.level_fields`, plus the cell data ``level`` (the
refinement level of every cell) and ``cell_id``, and one ``.pvd`` collection of all of
them in time order, so ParaView plays the run with the mesh changing under it.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import meshio
import numpy as np
from numpy.typing import NDArray

from ..mesh.io import to_meshio
from ..util.atomic import write_atomic
from ..vem.projection import Projection
from .vtk import _block_order, _pvd_text, level_fields

if TYPE_CHECKING:
    from ..simulate.adaptive_time import Segment

__all__ = ["write_adaptive_series"]


def write_adaptive_series(
    segments: list[Segment], outdir: str | os.PathLike[str], name: str = "adaptive"
) -> Path:
    """Write the levels of an adaptive run as one ParaView series.

    Parameters
    ----------
    segments : list of Segment
        The run (:func:`~vemwear.simulate.adaptive_time.simulate_adaptive`).
    outdir : path
        Output directory; created if missing.
    name : str
        Base name: ``outdir/<name>/<name>_NNNN.vtu`` per level ``NNNN``, and
        ``outdir/<name>.pvd``, written last, atomically; stale ``.vtu`` files of the
        series are removed.

    Returns
    -------
    Path
        The ``.pvd`` file.
    """
    if not name or os.sep in name or (os.altsep and os.altsep in name):
        raise ValueError(f"vtk: series name must be a plain file name, got {name!r}")
    if not segments:
        raise ValueError("vtk: an adaptive run without segments")
    out = Path(outdir)
    sub = out / name
    sub.mkdir(parents=True, exist_ok=True)
    width = max(4, len(str(segments[-1].last)))
    entries: list[tuple[float, str]] = []
    for k, seg in enumerate(segments):
        mesh = seg.problem.mesh
        res = seg.result
        base = to_meshio(mesh, with_boundary=False)
        order = _block_order(mesh)
        proj = Projection(mesh)
        final = k == len(segments) - 1
        for lv in range(seg.first, seg.last + 1 if final else seg.last):
            point_data, cells = level_fields(res, lv, proj)
            cells = {**cells, "level": seg.tree.level.astype(np.float64)}
            cell_data: dict[str, list[NDArray[Any]]] = {
                key: [v[ids] for ids in order] for key, v in cells.items()
            }
            cell_data["cell_id"] = [ids.astype(np.int64) for ids in order]
            fname = f"{name}_{lv:0{width}d}.vtu"
            m = meshio.Mesh(base.points, base.cells, point_data=point_data, cell_data=cell_data)
            meshio.write(sub / fname, m, file_format="vtu")
            entries.append((float(res.t[lv]), f"{name}/{fname}"))
    written = {Path(f).name for _t, f in entries}
    pattern = re.compile(re.escape(name) + r"_\d+\.vtu")
    for stale in sub.iterdir():
        if stale.is_file() and pattern.fullmatch(stale.name) and stale.name not in written:
            stale.unlink()
    pvd = out / f"{name}.pvd"
    write_atomic(pvd, _pvd_text(entries))
    return pvd
