"""What a run does besides its levels: the smallness estimate from the run's own
factorization, every phase in ``summary.json``, the 3D element matrices by their
low-rank form, and the imports of the run path."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from conftest import CONFIG_3D, small_config
from vemwear.cli.main import main
from vemwear.config import parse_config
from vemwear.mesh.registry3d import generate_mesh3d
from vemwear.simulate import SolverOptions
from vemwear.vem.local import Material
from vemwear.vem.local3d import cell_geometry, element_matrices3d

VORONOI_3D = CONFIG_3D.replace(
    'generator = "hexahedra"', 'generator = "voronoi3d"\nn_cells = 40\nseed = 3'
).replace("divisions = [4, 2, 2]\n", "")


def _shift_invert_ratio(system) -> float:
    """``max ||v||^2_Gc / a_h(v, v)`` by the generalized eigenproblem on all free dofs
    (ARPACK in shift-invert mode with SuperLU): the way the estimate used to be made."""
    W = sp.diags(system.weights)
    Mc = (system.N.T @ W @ system.N + system.Tau.T @ W @ system.Tau).tocsc()
    return float(spla.eigsh(Mc, k=1, M=system.K.tocsc(), which="LA")[0][0])


@pytest.mark.parametrize(
    "text",
    [
        small_config("2d k = 1", divisions=(8, 4)),
        small_config("2d k = 2", divisions=(8, 4), vem={"order": 2}),
        CONFIG_3D,
        VORONOI_3D,
    ],
    ids=["2d", "2d-k2", "hexahedra", "voronoi3d"],
)
@pytest.mark.parametrize("method", ["newton", "uzawa"])
def test_smallness_from_the_runs_factorization(text: str, method: str) -> None:
    """The estimate from the Schur block of the step solver (or a Schur factorization
    of its own, for solvers without one) is the generalized eigenvalue."""
    pr = parse_config(tomllib.loads(text)).problem
    d = pr.discrete
    solver = d.step_solver(SolverOptions(method=method, backend="scipy"))
    est = d.smallness_estimate(solver)
    ref = _shift_invert_ratio(d.system)
    assert est["c0_sq_over_C1"] == pytest.approx(ref, rel=1e-9)
    assert est["ratio"] == pytest.approx(
        pr.law.lipschitz * float(np.abs(d.mu).max()) * ref, rel=1e-9
    )
    assert d.timings["smallness"] > 0.0


def test_summary_timings_name_every_phase(tmp_path: Path, capsys) -> None:
    """``summary.json`` gives the assembly and the set-up where they were spent (before
    the time loop, for the smallness estimate), not the time to look them up."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(VORONOI_3D)
    out = tmp_path / "out"
    assert main(["run", str(cfg), "-o", str(out), "--no-progress"]) == 0
    capsys.readouterr()
    tm = json.loads((out / "summary.json").read_text())["timings"]
    assert {"assembly", "setup", "smallness", "time_loop", "total"} <= set(tm)
    # 40 polyhedra take milliseconds to assemble; looking the matrix up takes microseconds
    assert tm["assembly"] > 1e-3
    assert tm["total"] == pytest.approx(tm["assembly"] + tm["setup"] + tm["time_loop"])


@pytest.mark.parametrize("family", ["hexahedra", "tetrahedra", "voronoi3d", "prisms"])
@pytest.mark.parametrize("stabilization", ["paper", "trace"])
def test_element_matrices3d_stabilization_is_the_product(family: str, stabilization: str) -> None:
    """The stabilization from the rank-12 form of P is ``(I - P)^T (I - P)``, and P is a
    projector that reproduces linear fields."""
    if family in ("voronoi3d", "prisms"):
        mesh = generate_mesh3d(family, cells=32, seed=1)
    else:
        mesh = generate_mesh3d(family, divisions=(4, 2, 2))
    cg = cell_geometry(mesh)
    mat = Material(4.0, 4.0)
    for n, (ids, slots) in cg.groups().items():
        X = mesh.points[cg.vertices[slots]]
        K, B, P = element_matrices3d(X, cg.q[slots], cg.volume[ids], mat, stabilization)
        IP = np.eye(3 * n) - P
        stab = K - cg.volume[ids][:, None, None] * np.matmul(
            B.transpose(0, 2, 1), np.einsum("ij,mjk->mik", _voigt(mat), B)
        )
        S = np.matmul(IP.transpose(0, 2, 1), IP)
        s = np.einsum("mii->m", stab) / np.einsum("mii->m", S)
        np.testing.assert_allclose(stab, s[:, None, None] * S, atol=1e-12 * np.abs(K).max())
        np.testing.assert_allclose(np.matmul(P, P), P, atol=1e-12)
        lin = np.einsum("ab,mib->mia", [[1.0, 2.0, 0.5], [-1.0, 0.3, 2.0], [0.0, 1.0, -2.0]], X)
        v = (lin + np.array([0.1, -0.2, 0.3])).reshape(len(ids), 3 * n)
        np.testing.assert_allclose(np.einsum("mij,mj->mi", P, v), v, atol=1e-12)


def _voigt(mat: Material) -> np.ndarray:
    from vemwear.vem.local3d import elasticity_matrix

    return elasticity_matrix(mat)
