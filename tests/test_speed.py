"""What a run does besides its levels: the smallness estimate from the run's own
factorization, every phase in ``summary.json``, the 3D element matrices by their
low-rank form, and the imports of the run path."""

from __future__ import annotations

import json
import time
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


#: The phases of a run in ``summary.json``: each second of the run in one of them.
PHASES = ("config", "plan", "assembly", "setup", "smallness", "time_loop", "outputs")


def test_summary_timings_add_up_to_the_wall_time(tmp_path: Path) -> None:
    """The phases of a 3D run (the configuration with its mesh, the plan, assembly,
    set-up, estimate, levels, outputs with figures and ParaView files) add up to the
    wall time of ``run_config``, and ``run`` is that wall time up to the last file."""
    from vemwear import run_config

    cfg = tmp_path / "c.toml"
    cfg.write_text(VORONOI_3D.replace("[output]", "[output]\nfigures = true\nvtk = true"))
    tick = time.perf_counter()
    outcome = run_config(cfg, tmp_path / "out", progress=False)
    wall = time.perf_counter() - tick
    tm = json.loads((tmp_path / "out" / "summary.json").read_text())["timings"]
    assert tm == pytest.approx(outcome.result.timings, rel=1e-12)
    assert all(tm[k] > 0.0 for k in PHASES)
    assert 0.5 * wall <= sum(tm[k] for k in PHASES) <= 1.05 * wall
    assert sum(tm[k] for k in PHASES) <= tm["run"] <= wall
    assert tm["total"] == pytest.approx(tm["assembly"] + tm["setup"] + tm["time_loop"])
    # the outputs' parts: reading the levels back, result.npz + summary, figures, ParaView
    parts = [tm[f"outputs_{k}"] for k in ("read", "data", "figures", "vtk")]
    assert all(v > 0.0 for v in parts)
    assert 0.9 * tm["outputs"] <= sum(parts) <= tm["outputs"]


def test_a_reused_factorization_is_not_reported_again() -> None:
    """A second run of the same problem in the process reuses the assembly and the
    factorization: its timings say so (0 s), the first run's give what it spent."""
    from vemwear.simulate import simulate

    pr = parse_config(tomllib.loads(VORONOI_3D)).problem
    first = simulate(pr, SolverOptions(backend="scipy"), store="final").timings
    second = simulate(pr, SolverOptions(backend="scipy"), store="final").timings
    assert first["assembly"] > 0.0 and first["setup"] > 0.0
    assert second["assembly"] == 0.0 and second["setup"] == 0.0
    assert second["total"] == second["time_loop"]


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


LAZY_IN_A_RUN = (
    *("matplotlib", "certifi", "meshio", "xarray", "dask", "pandas", "pyamg", "scipy.spatial"),
    # the library's modules of the other kinds of runs and of the outputs turned off
    *("vemwear.simulate.adaptive_time", "vemwear.runner.adaptive", "vemwear.post.adaptive"),
    *("vemwear.simulate.mesh_change", "vemwear.simulate.wear_estimate"),
    *("vemwear.simulate.cycles", "vemwear.runner.cycles", "vemwear.studies"),
    *("vemwear.post.plots", "vemwear.post.maps", "vemwear.post.vtk", "vemwear.post.xdmf"),
)


def _imported(code: str, *args: str) -> set[str]:
    """The top-level and listed modules a fresh interpreter holds after ``code``."""
    import subprocess
    import sys

    probe = (
        code + "\nimport sys\nprint('MODULES:', *(m for m in sys.modules if m in "
        f"{(*LAZY_IN_A_RUN, 'numpy', 'scipy', 'pydantic', 'h5py')!r}))"
    )

    def held(source: str, *argv: str) -> set[str]:
        out = subprocess.run(
            [sys.executable, "-c", source, *argv], capture_output=True, text=True, check=True
        )
        return set(out.stdout.strip().splitlines()[-1].split()[1:])

    # what the interpreter holds before any code runs (a site hook of the installation,
    # e.g. a ``.pth`` file that imports certifi) is not the library's doing
    return held(probe, *args) - held(probe.replace(code, "pass", 1))


def test_import_vemwear_loads_no_numerical_library() -> None:
    assert _imported("import vemwear") == set()


def test_a_run_imports_no_library_it_does_not_use(tmp_path: Path) -> None:
    """``vemwear run`` without figures, ParaView output, a mesh file, ``[adapt]`` or
    cycle jumps: no plotting, mesh-file, study, multigrid or point-location library is
    imported (nor certifi, which matplotlib loads), and none of the library's modules of
    adaptive or cycle-jump runs, studies, figures or ParaView files."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(small_config("lazy", divisions=(8, 4), steps=4))
    code = (
        "import sys\nfrom vemwear.cli.main import main\n"
        "assert main(['run', sys.argv[1], '-o', sys.argv[2], '--no-progress']) == 0"
    )
    held = _imported(code, str(cfg), str(tmp_path / "out"))
    assert {"numpy", "scipy", "h5py"} <= held  # the run ran and streamed its levels
    assert not held & set(LAZY_IN_A_RUN)


@pytest.mark.parametrize("given", [None, "logfire"])
def test_the_command_turns_pydantic_plugins_off_unless_told(given: str | None) -> None:
    """The ``vemwear`` process spares pydantic's search of plugins (the entry points of
    every installed distribution) at its first validation; a value set stays."""
    import os
    import subprocess
    import sys

    code = (
        "import os, sys\nfrom vemwear.cli.main import entry\nsys.argv = ['vemwear', '--version']\n"
        "try:\n    entry()\nexcept SystemExit:\n"
        "    print('PLUGINS:', os.environ.get('PYDANTIC_DISABLE_PLUGINS'))"
    )
    env = {k: v for k, v in os.environ.items() if k != "PYDANTIC_DISABLE_PLUGINS"}
    if given is not None:
        env["PYDANTIC_DISABLE_PLUGINS"] = given
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    assert out.stdout.strip().splitlines()[-1] == f"PLUGINS: {given or '__all__'}"


@pytest.mark.parametrize("family", ["hexahedra", "tetrahedra", "voronoi3d", "prisms"])
def test_coupled_vertices_is_the_block_count_of_k(family: str) -> None:
    """The plan's count of coupled vertices is the number of nonzero 3 x 3 blocks per
    block row of the assembled stiffness, on a sample and on every vertex."""
    from vemwear.runner.plan import coupled_vertices
    from vemwear.vem.local3d import stiffness3d

    if family in ("voronoi3d", "prisms"):
        mesh = generate_mesh3d(family, cells=60, seed=2)
    else:
        mesh = generate_mesh3d(family, divisions=(6, 3, 3))
    K = stiffness3d(mesh, Material(4.0, 4.0)).tocsr()
    blocks = sp.csr_matrix(K[0::3, 0::3])
    blocks.data[:] = 1.0  # numerical zeros (none here) would still be stored entries
    assert coupled_vertices(mesh) == pytest.approx(blocks.nnz / mesh.n_points, rel=1e-12)
    one = coupled_vertices(mesh, sample=1)  # vertex 0 alone
    assert one == K[0].nnz / 3


def test_plan_counts_the_dense_contact_block() -> None:
    """The dense Schur block on the d m contact dofs is in the estimate: 20 (d m)^2
    bytes (it outgrows the factorization on prisms, whose contact side is the whole
    base mesh)."""
    from vemwear.runner.plan import estimate

    kw = dict(levels=17, points=20_005, cells=8000, kept=17, stored_u=1, paraview=False)
    small = estimate(contact=2, dim=3, coupled=33.0, base=1e8, **kw).memory
    large = estimate(contact=4001, dim=3, coupled=33.0, base=1e8, **kw).memory
    rows = 17 * 7 * 8 * (4001 - 2)  # the kept contact rows, twice
    assert large - small == pytest.approx(20.0 * ((3 * 4001) ** 2 - 36) + 2 * rows)
