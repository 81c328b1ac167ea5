"""Saving a run to disk and reading it back: ``result.npz`` and ``summary.json``.

One job (the two files' format, written and read): a fifth of its length is the table
of arrays below, the one place where each array's name, shape and meaning is stated.

:func:`save_result` writes two files into an output directory.

``result.npz``
    A NumPy archive (read it with :func:`load_result` or ``numpy.load``), holding
    plain arrays only (no pickles). ``L`` is the number of time levels
    (``t_0 = 0, ..., t_N = T``), ``n`` the number of mesh vertices, ``m`` the number
    of contact nodes (the vertices on the closure of Gamma_C that are not on the
    closure of Gamma_D, ordered along Gamma_C).

    The model is written in consistent units: lengths in the unit of the mesh
    coordinates, time in the unit of ``t``, and stresses/pressures in the unit of the
    Lamé coefficients ``lam``, ``eta`` (e.g. m, s and Pa). The paper's examples are
    dimensionless.

    ==========================  =========  ============================================
    array                       shape      meaning
    ==========================  =========  ============================================
    ``t``                       (K,)       the kept time levels ``t_n`` [time]: all L
                                           levels unless ``[output] every > 1``
    ``levels``                  (K,)       the index ``n`` of each kept level in the
                                           run's time grid (``0, 1, ..., L - 1`` when
                                           every level is kept)
    ``points``                  (n, 2)     vertex coordinates of the reference
                                           (undeformed) mesh [length]
    ``cells_offsets``           (C + 1,)   CSR offsets of the ``C`` polygonal cells:
                                           cell ``k`` has the vertices
                                           ``cells_vertices[cells_offsets[k]:``
                                           ``cells_offsets[k + 1]]``
    ``cells_vertices``          (sum n_K,) concatenated counter-clockwise vertex ids
    ``boundary_tags``           (B,)       part code of every boundary edge (1 clamped,
                                           2 traction, 3 contact, then ``part_names``
                                           from 4 on, 0 untagged), in the canonical
                                           order of ``Mesh.boundary_edges``; see
                                           :func:`mesh_from_arrays`
    ``part_names``              (P_b,)     names of the part codes 1, 2, ...
    ``u``                       (S, n, 2)  displacement ``u_h(t_n)`` at the vertices
                                           (the VEM degrees of freedom) at the kept
                                           levels of ``u_levels`` [length]
    ``u_levels``                (S,)       the rows (indices into ``t``) whose
                                           displacement is stored
    ``dofs``                    (S, N)     order k = 2 only: every degree of freedom
                                           (vertex values, edge and cell means,
                                           :mod:`vemwear.vem.dofs2`) at those levels
    ``contact_nodes``           (m,)       vertex ids of the contact nodes
    ``contact_s``               (m,)       arc length along Gamma_C from the start of
                                           the node's chain of contact edges [length]
    ``contact_points``          (m, 2)     coordinates of the contact nodes [length]
    ``contact_normals``         (m, 2)     unit outward normals ``nu_a``
    ``contact_weights``         (m,)       nodal quadrature weights ``omega_a`` (half
                                           the lengths of the adjacent contact edges)
                                           [length]; ``sum(omega * w)`` is the worn
                                           area (volume per unit depth)
    ``g``, ``mu``, ``kappa``    (m,)       layer thickness [length], friction and wear
                                           coefficients at the contact nodes
    ``gap``                     (m,)       initial gap at the contact nodes [length]
    ``contact_part``            (m,)       the contact part of each node (an index
                                           into ``contact_part_names``)
    ``contact_part_names``      (P_c,)     names of the contact parts
    ``forces``                  (K, P, 2)  force resultants on the body: of the layer
                                           of each contact part, then the reaction of
                                           each clamped or prescribed part [force per
                                           unit depth]
    ``force_parts``             (P,)       the parts of the rows of ``forces``
    ``force_kinds``             (P,)       ``contact`` or ``reaction``
    ``wear``                    (K, m)     wear ``w^n`` of the soft layer (the depth of
                                           material removed) [length]; ``w^0 = 0``
    ``u_nu``                    (K, m)     normal displacement ``u_nu(t_n) = u . nu_a``
                                           [length]; the unilateral constraint is
                                           ``u_nu - gap <= g``
    ``penetration``             (K, m)     ``u_nu - gap - wear``: the penetration into the
                                           soft layer, the argument of the normal
                                           compliance ``p`` [length]
    ``p_rigid``                 (K, m)     pressure of the rigid layer, the multiplier
                                           of ``u_nu <= g`` (``>= 0``, zero where
                                           ``u_nu < g``) [stress]
    ``p_soft``                  (K, m)     pressure of the soft layer,
                                           ``p(u_nu - wear)`` [stress]
    ``iterations``              (K,)       solver iterations of each step problem
    ``residuals``               (K, 3)     final scaled KKT residuals of each step, in
                                           the order of ``residual_names``
    ``residual_names``          (3,)       ``equilibrium``, ``feasibility``,
                                           ``complementarity``
    ``completed``               ()         number of finished time levels: ``L`` for a
                                           complete run; fewer for the partial result of
                                           an interrupted run (levels ``>= completed``
                                           are zero and ``u_levels < completed``)
    ``format``                  ()         the format of the arrays,
                                           ``"vemwear-result/2"``
    ``vemwear_version``         ()         version string of the writer
    ==========================  =========  ============================================

    Format 1 (files without ``format``) named ``p_rigid`` ``lam`` and ``p_soft``
    ``p``; :func:`load_result` and :func:`vemwear.post.stream.read_stream` read such
    files under today's names (:func:`upgrade_arrays`).

    A 3D run (on a :class:`~vemwear.mesh.polyhedra.Mesh3D`) stores the same arrays with
    three components where 2D has two (``points`` (n, 3), ``u`` (S, n, 3),
    ``contact_points`` and ``contact_normals`` (m, 3), ``forces`` (K, P, 3)),
    ``contact_s`` the x coordinate of the contact nodes (a surface has no arc length),
    ``contact_weights`` the nodes' shares of the contact faces' areas, and instead of
    ``cells_offsets`` and ``cells_vertices`` the arrays of the mesh type:
    ``face_offsets``, ``face_vertices`` (the faces as vertex loops, CSR),
    ``cell_offsets``, ``cell_faces``, ``cell_face_signs`` (the cells as signed faces,
    CSR); ``boundary_tags`` are then the part codes of the boundary faces, in the
    order of ``Mesh3D.boundary_faces``.

``summary.json``
    A JSON object with the keys ``format`` (``"vemwear-result/2"``), ``vemwear_version``,
    ``created`` (UTC, ISO 8601), ``inputs`` (``problem``: ``Problem.describe()`` with
    ``parts`` the boundary parts that have edges and, with several contact parts, their
    data under ``contacts`` only; ``extra``: whatever the caller passed, e.g. the
    configuration), ``solver``
    (``Result.solver``), ``statistics`` (levels, contact nodes, iteration totals, the
    largest value of each KKT residual), ``timings`` (``Result.timings``, seconds),
    ``outputs`` (key numbers of the solution: maximal wear at the final time and where,
    worn area, maximal ``u_nu``, penetration, pressures ``p_rigid_max`` and
    ``p_soft_max``, and displacement) and
    ``files``, and ``partial`` (false, or true for the finished levels of an interrupted
    run, with ``completed``, ``levels`` and the ``reason``). Non-finite numbers are written
    as ``null``.

A partial result (:attr:`Result.is_partial`) is saved the same way; its statistics and
outputs cover the finished levels only. :func:`result_from_arrays` turns the arrays of
``result.npz`` back into a :class:`~vemwear.simulate.Result` of a given problem, e.g. to
resume an interrupted run with ``simulate(problem, resume=result)``.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .. import __version__
from ..mesh.polyhedra import Mesh3D
from ..mesh.polymesh import Mesh
from ..util.atomic import atomic_file

if TYPE_CHECKING:
    from ..simulate.loop import Result

__all__ = [
    "NPZ_NAME",
    "SUMMARY_NAME",
    "jsonable",
    "load_result",
    "load_summary",
    "mesh_from_arrays",
    "result_arrays",
    "result_from_arrays",
    "save_result",
    "summarize",
    "upgrade_arrays",
]

#: The cell arrays of a 3D mesh in ``result.npz`` (instead of ``cells_offsets`` and
#: ``cells_vertices``), named as the attributes of :class:`~vemwear.mesh.polyhedra.Mesh3D`.
MESH3D_ARRAYS = (
    "face_offsets",
    "face_vertices",
    "cell_offsets",
    "cell_faces",
    "cell_face_signs",
)

#: File names written by :func:`save_result`.
NPZ_NAME = "result.npz"
SUMMARY_NAME = "summary.json"
#: The format of ``result.npz``, ``result.h5`` and ``summary.json``: 2 names the
#: pressures ``p_rigid`` and ``p_soft`` as the API does.
FORMAT = "vemwear-result/2"
#: The arrays of format 1 that format 2 renamed: old name -> name.
RENAMED_V1 = {"lam": "p_rigid", "p": "p_soft"}
_KNOWN_FORMATS = ("vemwear-result/1", FORMAT)


def array_format(data: Mapping[str, Any]) -> str:
    """The format of a result's arrays: their ``format`` (format 1 had none).

    Raises
    ------
    ValueError
        If the arrays are of a format this version does not know (a newer vemwear).
    """
    fmt = str(np.asarray(data["format"]).item()) if "format" in data else "vemwear-result/1"
    if fmt not in _KNOWN_FORMATS:
        raise ValueError(
            f"saved result: format {fmt!r} is newer than this vemwear {__version__} reads "
            f"(up to {FORMAT!r}); update vemwear"
        )
    return fmt


def upgrade_arrays(data: Mapping[str, Any]) -> dict[str, Any]:
    """A result's arrays under today's names (the arrays are not copied): format 1's
    ``lam`` and ``p`` become ``p_rigid`` and ``p_soft``, and ``format`` is set.

    Raises
    ------
    ValueError
        If the arrays are of a newer format (:func:`array_format`).
    """
    if array_format(data) == FORMAT:
        return dict(data)
    out = {RENAMED_V1.get(k, k): v for k, v in data.items()}
    out["format"] = np.array(FORMAT, dtype=str)
    return out


def static_mesh_arrays(mesh: Mesh | Mesh3D) -> dict[str, NDArray[Any]]:
    """The arrays of a mesh in ``result.npz`` (:func:`mesh_from_arrays` reads them)."""
    if isinstance(mesh, Mesh3D):
        cells = {k: np.asarray(getattr(mesh, k), dtype=np.int64) for k in MESH3D_ARRAYS}
        cells["cell_face_signs"] = cells["cell_face_signs"].astype(np.int8)
    else:
        cells = {
            "cells_offsets": np.asarray(mesh.cell_offsets, dtype=np.int64),
            "cells_vertices": np.asarray(mesh.cell_vertices, dtype=np.int64),
        }
    return {
        "points": np.asarray(mesh.points, dtype=np.float64),
        **cells,
        "boundary_tags": np.asarray(mesh.boundary_tags, dtype=np.int8),
        "part_names": np.array(mesh.part_names, dtype=str),
    }


def static_arrays(problem: Any, plan: Any) -> dict[str, NDArray[Any]]:
    """The arrays of ``result.npz`` that do not depend on the solution: the kept levels
    (``plan``, a :class:`~vemwear.simulate.stream.StoragePlan`: ``t`` and ``levels`` of
    the kept rows, ``u_levels`` the rows with a displacement), the mesh, the contact
    nodes and their data."""
    cb = problem.contact
    nodal = problem.nodal
    return {
        "t": np.asarray(problem.time.t, dtype=np.float64)[plan.levels],
        "levels": np.asarray(plan.levels, dtype=np.int64),
        **static_mesh_arrays(problem.mesh),
        "u_levels": np.searchsorted(plan.levels, plan.u_levels).astype(np.int64),
        "contact_nodes": np.asarray(cb.nodes, dtype=np.int64),
        "contact_s": np.asarray(cb.s, dtype=np.float64),
        "contact_points": np.asarray(cb.points, dtype=np.float64),
        "contact_normals": np.asarray(cb.normals, dtype=np.float64),
        "contact_weights": np.asarray(cb.weights, dtype=np.float64),
        "g": np.asarray(nodal["g"], dtype=np.float64),
        "mu": np.asarray(nodal["mu"], dtype=np.float64),
        "kappa": np.asarray(nodal["kappa"], dtype=np.float64),
        "gap": np.asarray(nodal["gap"], dtype=np.float64),
        "contact_part": np.asarray(cb.part, dtype=np.int64),
        "contact_part_names": np.array(cb.part_names, dtype=str),
        "force_parts": np.array([n for n, _ in problem.discrete.force_parts], dtype=str),
        "force_kinds": np.array([k for _, k in problem.discrete.force_parts], dtype=str),
        "residual_names": np.array(("equilibrium", "feasibility", "complementarity"), dtype=str),
        "format": np.array(FORMAT, dtype=str),
        "vemwear_version": np.array(__version__, dtype=str),
    }


class _AllLevels:
    """The storage plan of a result: its ``levels``, displacements at no level (the
    result's own ``u_levels`` are rows already)."""

    def __init__(self, result: Result) -> None:
        self.levels = np.asarray(result.levels, dtype=np.int64)
        self.u_levels = np.zeros(0, dtype=np.int64)


def result_arrays(result: Result) -> dict[str, NDArray[Any]]:
    """The arrays stored in ``result.npz`` (see the module docstring), by name."""
    out = static_arrays(result.problem, _AllLevels(result))
    out.update(
        t=np.asarray(result.t, dtype=np.float64),
        points=np.asarray(result.points, dtype=np.float64),
        u=np.asarray(result.u, dtype=np.float64),
        u_levels=np.asarray(result.u_levels, dtype=np.int64),
        contact_nodes=np.asarray(result.contact_nodes, dtype=np.int64),
        contact_s=np.asarray(result.contact_s, dtype=np.float64),
        contact_points=np.asarray(result.contact_points, dtype=np.float64),
        wear=np.asarray(result.wear, dtype=np.float64),
        u_nu=np.asarray(result.u_nu, dtype=np.float64),
        penetration=np.asarray(result.penetration, dtype=np.float64),
        p_rigid=np.asarray(result.p_rigid, dtype=np.float64),
        p_soft=np.asarray(result.p_soft, dtype=np.float64),
        iterations=np.asarray(result.iterations, dtype=np.int64),
        residuals=np.asarray(result.residuals, dtype=np.float64),
        residual_names=np.array(result.RESIDUAL_NAMES, dtype=str),
        completed=np.array(int(result.completed), dtype=np.int64),
    )
    if result.dofs is not None:
        out["dofs"] = np.asarray(result.dofs, dtype=np.float64)
    if result.forces is not None:
        out["forces"] = np.asarray(result.forces, dtype=np.float64)
    return out


def jsonable(x: Any) -> Any:
    """Convert NumPy scalars/arrays, paths and tuples to JSON data; non-finite -> None."""
    if isinstance(x, Mapping):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, set, frozenset)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, np.generic):
        return jsonable(x.item())
    if isinstance(x, bool) or x is None or isinstance(x, (int, str)):
        return x
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, os.PathLike):
        return os.fspath(x)
    if callable(x):
        return getattr(x, "__name__", type(x).__name__)
    return str(x)


def _max(a: NDArray[Any]) -> float:
    return float(np.max(a)) if np.size(a) else float("nan")


def summarize(result: Result) -> dict[str, Any]:
    """Statistics and key outputs of a run (the ``statistics`` and ``outputs`` of the summary).

    Parameters
    ----------
    result : Result
        A finished run.

    Returns
    -------
    dict
        ``{"statistics": {...}, "outputs": {...}}`` with plain Python numbers.
    """
    # the kept rows of the finished levels (all of them for a complete run)
    c = int(np.searchsorted(np.asarray(result.levels), int(result.completed)))
    it = np.asarray(result.iterations)[:c]
    res = np.asarray(result.residuals)[:c]
    names = tuple(result.RESIDUAL_NAMES)
    L = len(result.problem.time.t)
    stats: dict[str, Any] = {
        "levels": L,
        "steps": L - 1,
        "kept_levels": len(result.t),
        "contact_nodes": len(result.contact_nodes),
        "iterations_total": int(it.sum()),
        "iterations_max": int(it.max(initial=0)),
        "iterations_mean": float(it.mean()) if it.size else 0.0,
        "max_residual": {n: _max(res[:, i]) for i, n in enumerate(names)},
    }
    last = max(c - 1, 0)  # the last finished level
    m = len(result.contact_nodes)
    wear_T = np.asarray(result.wear[last]) if c else np.zeros(m)
    pen = np.asarray(result.penetration)[:c]
    u_nu = np.asarray(result.u_nu)[:c]
    weights = np.asarray(result.problem.contact.weights)
    # the largest squared length of u at each kept level, a level at a time: no (S, n)
    # temporary (273 MB at 1/512 with 65 levels)
    usq = np.array([_max(np.einsum("ij,ij->i", x, x)) for x in np.asarray(result.u)])
    a = int(np.argmax(wear_T)) if wear_T.size else 0
    nodal = result.problem.nodal
    active = np.asarray(nodal["g"] + nodal["gap"]) - np.asarray(result.u_nu[last])
    g_scale = float(np.max(np.abs(result.problem.nodal["g"]), initial=1.0))
    outputs: dict[str, Any] = {
        "t_final": float(result.t[last]),
        "wear_max_final": _max(wear_T),
        "wear_max_final_at": np.asarray(result.contact_points[a]).tolist() if wear_T.size else None,
        "wear_area_final": float(np.dot(weights, wear_T)),
        "u_nu_max": _max(u_nu),
        "u_nu_max_final": _max(u_nu[-1]) if c else float("nan"),
        "penetration_max": _max(pen),
        "penetration_max_final": _max(pen[-1]) if c else float("nan"),
        "p_rigid_max": _max(np.asarray(result.p_rigid)[:c]),
        "p_soft_max": _max(np.asarray(result.p_soft)[:c]),
        "displacement_max": float(np.sqrt(_max(usq))),
        "displacement_max_final": float(np.sqrt(_max(usq[-1]))) if len(usq) else float("nan"),
        "nodes_in_contact_final": int(np.sum(pen[-1] > 0)) if c else 0,
        "nodes_on_rigid_layer_final": int(np.sum(active <= 1e-9 * g_scale)),
    }
    cb = result.problem.contact
    if len(cb.part_names) > 1:  # per contact part: its own wear
        outputs["contact_parts"] = {
            name: {
                "wear_max_final": _max(wear_T[cb.part == i]),
                "wear_area_final": float(np.dot(weights[cb.part == i], wear_T[cb.part == i])),
            }
            for i, name in enumerate(cb.part_names)
        }
    if result.forces is not None and c:
        from .forces import force_table

        outputs["forces_final"] = force_table(result)
    ties = result.problem.constraints.ties
    if ties is not None and len(result.u):  # each rigid part's motion at the kept levels
        motions = [ties.motions(np.asarray(u)) for u in result.u]
        outputs["rigid_parts"] = {
            pc.part: {
                "translation_final": motions[-1][0][i].tolist(),
                **(
                    {
                        "centre": ties.centres[i].tolist(),
                        "rotation_final": motions[-1][1][i].tolist(),
                    }
                    if pc.turns
                    else {}
                ),
                "t": [float(result.t[n]) for n in result.u_levels],
                "translation": [m[0][i].tolist() for m in motions],
                **({"rotation": [m[1][i].tolist() for m in motions]} if pc.turns else {}),
            }
            for i, pc in enumerate(ties.parts)
        }
    return {"statistics": stats, "outputs": outputs}


def _described(problem: Any) -> dict[str, Any]:
    """``Problem.describe()`` as ``summary.json`` shows it: ``parts`` lists the boundary
    parts that have edges (not the paper's empty defaults); with several contact parts
    the single-part entries ``p, g, mu, kappa, v_star, gap`` (defaults the problem does
    not use) are left out, each part's data being under ``contacts``. The fingerprint of
    a run keeps the whole ``describe()``."""
    d = problem.describe()
    d["parts"] = list(problem.mesh.parts)
    if problem.contacts:
        for key in ("p", "g", "mu", "kappa", "v_star", "gap"):
            d.pop(key, None)
    return d


def _summary(
    result: Result, extra: dict[str, Any] | None, reason: str | None = None
) -> dict[str, Any]:
    s = summarize(result)
    partial: dict[str, Any] = {"partial": bool(result.is_partial or reason is not None)}
    if partial["partial"]:
        partial.update(
            completed=int(result.completed),
            levels=len(result.problem.time.t),
            reason=reason or "interrupted",
        )
    return {
        "format": FORMAT,
        **partial,
        "vemwear_version": __version__,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "inputs": {"problem": _described(result.problem), "extra": extra or {}},
        "solver": dict(result.solver),
        "statistics": s["statistics"],
        "timings": dict(result.timings),
        "outputs": s["outputs"],
        "files": {"arrays": NPZ_NAME},
    }


def save_result(
    result: Result,
    outdir: str | os.PathLike[str],
    extra: dict[str, Any] | None = None,
    *,
    compress: bool = False,
    partial: str | None = None,
) -> list[Path]:
    """Write ``result.npz`` and ``summary.json`` into ``outdir``.

    Both files are first written to temporary names in ``outdir`` and renamed only
    when both are complete, so an interrupted or failed write never leaves a
    truncated ``result.npz`` or ``summary.json`` (an older pair is replaced as a whole
    or not at all, up to the two renames).

    Parameters
    ----------
    result : Result
        The run to save.
    outdir : path
        Output directory; created (with parents) if missing.
    extra : dict, optional
        JSON-friendly data stored under ``inputs.extra`` in the summary, e.g. the
        configuration the run was made from. NumPy values and paths are converted.
    compress : bool
        Use ``numpy.savez_compressed`` (smaller, slower) instead of ``numpy.savez``.
    partial : str, optional
        Why the run stopped, for the finished levels of an interrupted run: the summary
        then says ``"partial": true`` with this ``reason`` (a result with
        ``is_partial`` is always marked partial; the default reason is "interrupted").

    Returns
    -------
    list of Path
        ``[outdir / "result.npz", outdir / "summary.json"]``.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    arrays = result_arrays(result)
    summary = jsonable(_summary(result, extra, partial))
    targets = [out / NPZ_NAME, out / SUMMARY_NAME]
    with atomic_file(targets[0], durable=True) as npz, atomic_file(targets[1], durable=True) as js:
        with open(npz, "wb") as fh:
            (np.savez_compressed if compress else np.savez)(fh, **arrays)  # type: ignore[arg-type]
        text = json.dumps(summary, indent=2, allow_nan=False) + "\n"
        js.write_text(text, encoding="utf-8")
    return targets


def _npz_path(path: str | os.PathLike[str]) -> Path:
    p = Path(path)
    if p.is_dir():
        p = p / NPZ_NAME
    if not p.exists():
        raise FileNotFoundError(f"result file not found: {p}")
    return p


def load_result(path: str | os.PathLike[str]) -> dict[str, NDArray[Any]]:
    """Read the arrays of a saved run.

    Parameters
    ----------
    path : path
        The ``result.npz`` file or the directory holding it.

    Returns
    -------
    dict of str to ndarray
        Every array of the archive (see the module docstring), fully loaded in memory,
        under today's names (an archive of format 1 is read with ``lam`` and ``p`` as
        ``p_rigid`` and ``p_soft``). 0-d string arrays (``vemwear_version``) stay 0-d
        arrays; use ``.item()``.

    Raises
    ------
    ValueError
        If the archive is of a newer format than this vemwear reads.
    """
    p = _npz_path(path)
    with np.load(p, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    try:
        return upgrade_arrays(arrays)
    except ValueError as exc:
        raise ValueError(f"{p}: {exc}") from None


def load_summary(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read ``summary.json`` (given the file or its directory)."""
    p = Path(path)
    if p.is_dir():
        p = p / SUMMARY_NAME
    with open(p, encoding="utf-8") as fh:
        return json.load(fh)


def mesh_from_arrays(data: Mapping[str, NDArray[Any]]) -> Mesh | Mesh3D:
    """Rebuild the :class:`~vemwear.mesh.Mesh` or, from the arrays of a 3D run
    (``face_offsets`` ...), the :class:`~vemwear.mesh.polyhedra.Mesh3D` (with its
    boundary parts) from saved arrays.

    Parameters
    ----------
    data : mapping
        The output of :func:`load_result`.
    """
    tags = data.get("boundary_tags")
    names = [tuple(str(n) for n in data["part_names"])] if "part_names" in data else []
    if "face_offsets" in data:
        return Mesh3D(
            np.asarray(data["points"]),
            np.asarray(data["face_offsets"]),
            np.asarray(data["face_vertices"]),
            np.asarray(data["cell_offsets"]),
            np.asarray(data["cell_faces"]),
            np.asarray(data["cell_face_signs"]),
            None if tags is None else np.asarray(tags),
            *names,
        )
    return Mesh(
        np.asarray(data["points"]),
        np.asarray(data["cells_offsets"]),
        np.asarray(data["cells_vertices"]),
        None if tags is None else np.asarray(tags),
        *([tuple(str(n) for n in data["part_names"])] if "part_names" in data else []),
    )


def result_from_arrays(
    problem: Any,
    data: Mapping[str, NDArray[Any]],
    *,
    solver: Mapping[str, Any] | None = None,
    copy: bool = True,
) -> Result:
    """Rebuild a :class:`~vemwear.simulate.Result` of ``problem`` from saved arrays.

    Used to resume an interrupted run: ``simulate(problem, ..., resume=result)`` goes on
    from the first unfinished level and gives the same numbers as an uninterrupted run.

    Parameters
    ----------
    problem : Problem
        The problem the arrays were computed for (same mesh, contact nodes and time grid).
    data : mapping
        The output of :func:`load_result` (a complete or a partial result); arrays of
        format 1 (``lam``, ``p``) are read too.
    solver : mapping, optional
        Stored as ``Result.solver`` (e.g. the ``solver`` of ``summary.json``).
    copy : bool
        Copy the arrays (default); ``False`` hands arrays read for this call over to
        the result (the displacements of a large run are hundreds of MB).

    Returns
    -------
    Result
        With ``completed`` from the arrays (``len(t)`` if the file has none).

    Raises
    ------
    ValueError
        If an array is missing or the arrays do not fit the problem (another time grid,
        mesh or set of contact nodes); the message names the array.
    """
    from ..simulate.loop import Result

    data = upgrade_arrays(data)
    need = (
        "t",
        "points",
        "u",
        "u_levels",
        "contact_nodes",
        "contact_s",
        "contact_points",
        "wear",
        "u_nu",
        "p_rigid",
        "p_soft",
        "iterations",
        "residuals",
    )
    missing = [k for k in need if k not in data]
    if missing:
        raise ValueError(f"saved result: missing arrays {', '.join(missing)}")
    t = np.asarray(data["t"], dtype=np.float64)
    n_grid = len(problem.time.t)
    levels = np.asarray(data.get("levels", np.arange(len(t))), dtype=np.int64)
    L = len(levels)
    if (
        t.shape != (L,)
        or (L and (levels.min() < 0 or levels.max() >= n_grid))
        or not np.array_equal(t, problem.time.t[levels])
    ):
        raise ValueError(
            f"saved result: the time levels differ from the problem's "
            f"({len(t)} saved, {n_grid} in the problem)"
        )
    pts = np.asarray(data["points"], dtype=np.float64)
    if pts.shape != problem.mesh.points.shape or not np.array_equal(pts, problem.mesh.points):
        raise ValueError("saved result: the mesh vertices differ from the problem's mesh")
    cn = np.asarray(data["contact_nodes"], dtype=np.int64)
    if not np.array_equal(cn, problem.contact.nodes):
        raise ValueError("saved result: the contact nodes differ from the problem's")
    m, n = len(cn), len(pts)
    d = int(pts.shape[1])
    shapes = {
        "wear": (L, m),
        "u_nu": (L, m),
        "p_rigid": (L, m),
        "p_soft": (L, m),
        "iterations": (L,),
        "residuals": (L, 3),
        "contact_s": (m,),
        "contact_points": (m, d),
    }
    for k, shape in shapes.items():
        if np.shape(data[k]) != shape:
            raise ValueError(
                f"saved result: array {k!r} has shape {np.shape(data[k])}, expected {shape}"
            )
    u = np.asarray(data["u"], dtype=np.float64)
    u_levels = np.asarray(data["u_levels"], dtype=np.int64)
    if u.ndim != 3 or u.shape[1:] != (n, d) or u.shape[0] != len(u_levels):
        raise ValueError(
            f"saved result: array 'u' has shape {u.shape}, expected ({len(u_levels)}, {n}, {d})"
        )
    completed = int(data["completed"]) if "completed" in data else n_grid
    if (
        not 0 <= completed <= n_grid
        or np.any((u_levels < 0) | (u_levels >= L))
        or np.any(levels[u_levels] >= completed)
    ):
        raise ValueError(
            f"saved result: inconsistent 'completed' = {completed} "
            f"(levels {L}, stored displacement levels {u_levels.tolist()[:5]})"
        )

    def own(a: NDArray[Any]) -> NDArray[Any]:
        return a.copy() if copy else a

    return Result(
        problem=problem,
        t=own(t),
        points=own(pts),
        u=own(u),
        contact_nodes=own(cn),
        contact_s=own(np.asarray(data["contact_s"], dtype=np.float64)),
        contact_points=own(np.asarray(data["contact_points"], dtype=np.float64)),
        wear=own(np.asarray(data["wear"], dtype=np.float64)),
        u_nu=own(np.asarray(data["u_nu"], dtype=np.float64)),
        p_rigid=own(np.asarray(data["p_rigid"], dtype=np.float64)),
        p_soft=own(np.asarray(data["p_soft"], dtype=np.float64)),
        iterations=own(np.asarray(data["iterations"], dtype=np.int64)),
        residuals=own(np.asarray(data["residuals"], dtype=np.float64)),
        u_levels=own(u_levels),
        completed=completed,
        solver=dict(solver or {}),
        levels=own(levels),
        forces=own(np.asarray(data["forces"], dtype=np.float64)) if "forces" in data else None,
        dofs=own(np.asarray(data["dofs"], dtype=np.float64)) if "dofs" in data else None,
    )
