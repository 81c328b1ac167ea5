"""One simulation over the ranks of an MPI job (the petsc backend) gives the serial run.

Real processes: ``mpirun -n N python -m vemwear run CONFIG -o OUT --backend petsc``
against ``python -m vemwear run CONFIG -o OUT`` (the default backend), both read back
from ``result.h5`` with h5py. These tests need Open MPI's ``mpirun`` and a Python in
which petsc4py and mpi4py import (Debian's python3 with python3-petsc4py, or conda-forge;
docs/mpi.md); ``.ci/run`` runs them with Debian's python3 (and makes a skip a failure
there with ``VEMWEAR_MPI_TESTS=required``), elsewhere they are skipped.
The refusals that need no PETSc run everywhere.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from functools import cache
from pathlib import Path

import h5py
import numpy as np
import pytest

from conftest import CONFIG_3D as CONFIG_3D_SMALL
from conftest import small_config

MPIRUN = shutil.which("mpirun")
RTOL = 1e-10
#: the arrays of every kept level that must agree
COMPARED = ("wear", "u_nu", "u", "p_soft", "p_rigid", "t", "u_levels")

CONFIG_2D = small_config("mpi 2d", divisions=(16, 8), steps=40, solver={"backend": None})

CONFIG_3D = (  # conftest's 3D data on 6 x 3 x 3 hexahedra, 6 steps, the default backend
    CONFIG_3D_SMALL.replace('title = "3d small"', 'title = "mpi 3d"')
    .replace("divisions = [4, 2, 2]", "divisions = [6, 3, 3]")
    .replace("steps = 8", "steps = 6")
    .replace('[solver]\nbackend = "scipy"\n', "")
    + 'figures = false\nvtk = false\nstore_u = "all"\n'
)


@cache
def _petsc_here() -> bool:
    """Whether petsc4py and mpi4py import in this Python (asked in a child process: MPI
    is not initialized in the test process)."""
    probe = "from vemwear.solvers.backends.petsc import available as a; raise SystemExit(not a())"
    return subprocess.run([sys.executable, "-c", probe], capture_output=True).returncode == 0


def _need_mpi() -> None:
    # .ci/run sets VEMWEAR_MPI_TESTS=required where it installed PETSc: fail, not skip
    missing = pytest.fail if os.environ.get("VEMWEAR_MPI_TESTS") == "required" else pytest.skip
    if MPIRUN is None:
        missing("no mpirun: the MPI tests need Open MPI (docs/mpi.md)")
    if not _petsc_here():
        missing(
            f"petsc4py/mpi4py do not import in {sys.executable}: the MPI tests run with "
            "Debian's python3 and python3-petsc4py (.ci/run, docs/mpi.md)"
        )


def _env() -> dict[str, str]:
    env = dict(os.environ)
    src = str(Path(__file__).resolve().parents[1] / "src")
    env["PYTHONPATH"] = os.pathsep.join(p for p in (src, env.get("PYTHONPATH")) if p)
    env.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
    return env


def _mpirun(n: int, *args: str) -> list[str]:
    assert MPIRUN is not None
    return [MPIRUN, "--allow-run-as-root", "--oversubscribe", "-n", str(n), *args]


def _vemwear(*args: str) -> list[str]:
    return [sys.executable, "-m", "vemwear", "run", *args, "--no-progress"]


def _run(cmd: list[str], timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run(cmd, capture_output=True, text=True, env=_env(), timeout=timeout)


def _arrays(out: Path) -> dict[str, np.ndarray]:
    with h5py.File(out / "result.h5", "r") as f:
        return {k: f[k][()] for k in COMPARED}


def _assert_equal_runs(ref: dict[str, np.ndarray], got: dict[str, np.ndarray]) -> None:
    for k in COMPARED:
        a, b = ref[k], got[k]
        assert a.shape == b.shape, k
        scale = float(np.abs(a).max())
        assert scale > 0, k  # a run with nothing in contact would prove nothing
        assert float(np.abs(a - b).max()) <= RTOL * scale, (k, float(np.abs(a - b).max()))


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, dict]]:
    """The serial runs with the default backend, one per case."""
    _need_mpi()
    root = tmp_path_factory.mktemp("serial")
    runs = {}
    for name, text in (("2d", CONFIG_2D), ("3d", CONFIG_3D)):
        cfg = root / f"{name}.toml"
        cfg.write_text(text)
        done = _run(_vemwear(str(cfg), "-o", str(root / name)))
        assert done.returncode == 0, done.stderr
        runs[name] = (cfg, _arrays(root / name))
    return runs


@pytest.mark.parametrize(
    ("case", "ranks"), [("2d", 1), ("2d", 2), ("2d", 4), ("3d", 1), ("3d", 2), ("3d", 4)]
)
def test_mpi_run_equals_serial(serial, tmp_path: Path, case: str, ranks: int) -> None:
    cfg, ref = serial[case]
    out = tmp_path / "out"
    done = _run(_mpirun(ranks, *_vemwear(str(cfg), "-o", str(out), "--backend", "petsc")))
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.count(": done") == 1  # rank 0 reports, the other ranks say nothing
    _assert_equal_runs(ref, _arrays(out))
    with h5py.File(out / "result.h5", "r") as f:
        assert int(f["completed"][()]) == len(ref["t"])


STOPPER = """\
import importlib, sys
levels = importlib.import_module("vemwear.simulate.levels")
real = levels.run_levels

def patched(*args, **kwargs):
    def stop(n, _solution):
        if n == {level}:
            raise KeyboardInterrupt
    kwargs["callback"] = stop
    return real(*args, **kwargs)

levels.run_levels = patched
from vemwear.cli.main import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize("resume_ranks", [None, 4])
def test_two_rank_run_stopped_resumes_on_other_ranks(
    serial, tmp_path: Path, resume_ranks: int | None
) -> None:
    """Stopped on two ranks, resumed in one process (no mpirun) or on four ranks, whose
    partition of the cells is another: the run ends as the serial one."""
    cfg, ref = serial["2d"]
    script = tmp_path / "stopper.py"
    script.write_text(STOPPER.format(level=20))
    out = tmp_path / "out"
    cmd = [sys.executable, str(script), "run", str(cfg), "-o", str(out), "--no-progress"]
    stopped = _run(_mpirun(2, *cmd, "--backend", "petsc"))
    assert stopped.returncode == 130, stopped.stdout + stopped.stderr
    assert "vemwear: interrupted; the 20 finished time levels" in stopped.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and summary["completed"] == 20
    again = _vemwear(str(cfg), "-o", str(out), "--resume", "--backend", "petsc")
    resumed = _run(again if resume_ranks is None else _mpirun(resume_ranks, *again))
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert resumed.stdout.count("resumed from level") == 1
    _assert_equal_runs(ref, _arrays(out))


def test_mpirun_without_petsc_backend_is_refused(tmp_path: Path) -> None:
    """Two ranks and the default backend: one line, exit 2, nothing written (whether or
    not PETSc is installed)."""
    if MPIRUN is None:
        pytest.skip("no mpirun: the MPI tests need Open MPI (docs/mpi.md)")
    cfg = tmp_path / "c.toml"
    cfg.write_text(CONFIG_2D)
    out = tmp_path / "out"
    done = _run(_mpirun(2, *_vemwear(str(cfg), "-o", str(out))), timeout=120)
    assert done.returncode == 2, done.stdout + done.stderr
    lines = [ln for ln in done.stderr.splitlines() if ln.startswith("vemwear: error:")]
    assert len(lines) == 1, done.stderr
    assert "2 MPI ranks" in lines[0] and "--backend petsc" in lines[0]
    assert not out.exists()


def test_petsc_backend_without_petsc4py_names_the_way_to_get_it(tmp_path: Path) -> None:
    if _petsc_here():
        pytest.skip("petsc4py imports here: the refusal is for a Python without it")
    cfg = tmp_path / "c.toml"
    cfg.write_text(CONFIG_2D)
    out = tmp_path / "out"
    done = _run(_vemwear(str(cfg), "-o", str(out), "--backend", "petsc"), timeout=120)
    assert done.returncode == 2, done.stdout + done.stderr
    assert "python3-petsc4py" in done.stderr and "conda-forge" in done.stderr
    assert not out.exists()


def test_sigterm_to_mpirun_saves_the_finished_levels(serial, tmp_path: Path) -> None:
    """mpirun forwards SIGTERM to every rank: rank 0 saves its finished levels (the
    workers wait for it) and says how to resume."""
    cfg = tmp_path / "long.toml"
    cfg.write_text(CONFIG_2D.replace("steps = 40", "steps = 200000"))
    out = tmp_path / "out"
    cmd = _mpirun(2, *_vemwear(str(cfg), "-o", str(out), "--backend", "petsc"))
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env())
    deadline = time.monotonic() + 120
    while not (out / "result.h5").exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    time.sleep(2.0)  # some levels solved
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    text = err.decode()
    assert "vemwear: terminated (SIGTERM); stopping" in text
    assert "finished time levels (of 200001) are saved" in text
    assert "continue with: mpirun -n 2 vemwear run" in text and "--resume --backend petsc" in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and summary["reason"] == "terminated (SIGTERM)"
    assert 0 < summary["completed"] < 200001
    assert (out / "checkpoint.npz").exists()


BACKEND_CHECK = """\
import numpy as np
from vemwear.paper import ex52
from vemwear.solvers.backends import schur_factorize
from vemwear.solvers.backends.petsc import PetscSchur, serve, session

with session() as root:
    if not root:
        serve()
    else:
        s = ex52.problem(0.2, 2.0, divisions=(256, 128), steps=1).discrete.system
        K, last = s.K, s.contact_dofs.ravel()
        ref = schur_factorize(K, last, s.dof_points, "scipy")
        got = PetscSchur(K, last)
        B = np.random.default_rng(1).normal(size=(K.shape[0], 3))
        X = got.solve(B)
        print("S_inv", np.abs(got.S_inv - ref.S_inv).max() / np.abs(ref.S_inv).max())
        print("solve", np.abs(X - ref.solve(B)).max() / np.abs(ref.solve(B)).max())
"""


def test_schur_block_and_solves_on_two_ranks_at_a_larger_size(tmp_path: Path) -> None:
    """512 contact dofs: MUMPS's Schur block on two ranks has its lower triangle partly
    filled with leftovers (not zero), so the triangle is told by a product with S."""
    _need_mpi()
    script = tmp_path / "check.py"
    script.write_text(BACKEND_CHECK)
    done = _run(_mpirun(2, sys.executable, str(script)))
    assert done.returncode == 0, done.stdout + done.stderr
    errors = dict(line.split() for line in done.stdout.splitlines())
    assert float(errors["S_inv"]) < RTOL and float(errors["solve"]) < RTOL, errors


ASSEMBLY_CHECK = """\
import dataclasses, json, sys
import numpy as np
from vemwear.config.build import load_config
from vemwear.solvers.backends import schur_factorize
from vemwear.solvers.backends.petsc import serve, session

with session() as root:
    if not root:
        serve()
    else:
        cfg = load_config(sys.argv[1])
        d = cfg.problem.discrete
        s = d.system
        if sys.argv[2] == "rows":  # the run's own factorization
            factor = d.step_solver(dataclasses.replace(cfg.solver, backend="petsc")).factor
        else:
            from vemwear.solvers.backends.petsc import PetscSchur

            cd = s.contact_cols if s.contact_dofs is None else s.contact_dofs.ravel()
            factor = PetscSchur(s.K, cd[cd >= 0], assembly=s.assembly, partition=sys.argv[2])
        ref = schur_factorize(s.K, factor.last, s.dof_points, "scipy")
        B = np.random.default_rng(1).normal(size=(s.K.shape[0], 2))
        X, Y = factor.solve(B), ref.solve(B)
        print(json.dumps({
            **factor.assembly_report,
            "n_cells": d.problem.mesh.n_cells,
            "n": s.K.shape[0],
            "S_inv": float(np.abs(factor.S_inv - ref.S_inv).max() / np.abs(ref.S_inv).max()),
            "solve": float(np.abs(X - Y).max() / np.abs(Y).max()),
        }))
"""


@pytest.mark.parametrize(
    ("case", "ranks", "partition"),
    [
        ("2d", 2, "rows"),
        ("2d", 3, "rows"),
        ("2d k=2", 2, "rows"),
        ("3d", 2, "rows"),
        ("3d", 4, "rows"),
        ("2d", 3, "metis"),
        ("2d k=2", 2, "metis"),
        ("3d", 4, "slabs"),
    ],
)
def test_each_rank_assembles_the_cells_of_its_part(
    tmp_path: Path, case: str, ranks: int, partition: str
) -> None:
    """The distributed matrix is the sum of the ranks' own cells: every rank assembled
    some cells and owns some rows, each cell and each row once, and the factorization of
    that matrix gives the serial Schur block and solves ("rows": the run's own
    factorization; "metis", "slabs": the rows renumbered to the parts)."""
    _need_mpi()
    if partition == "metis":
        pytest.importorskip("pymetis")  # the extra 'mpi', installed by .ci/run
    text = {
        "2d": CONFIG_2D,
        "2d k=2": small_config("mpi k=2", divisions=(16, 8), steps=2, vem={"order": 2}),
        "3d": CONFIG_3D,
    }[case]
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    script = tmp_path / "check.py"
    script.write_text(ASSEMBLY_CHECK)
    done = _run(_mpirun(ranks, sys.executable, str(script), str(cfg), partition))
    assert done.returncode == 0, done.stdout + done.stderr
    got = json.loads(done.stdout.strip().splitlines()[-1])
    assert got["partitioner"] == partition
    cells, rows = got["cells"], got["rows"]
    assert len(cells) == ranks and sum(cells) == got["n_cells"]
    assert min(cells) >= 0.75 * got["n_cells"] / ranks  # balanced (54 cells: 12 to 15)
    assert len(rows) == ranks and sum(rows) == got["n"] and min(rows) > 0
    assert got["S_inv"] < RTOL and got["solve"] < RTOL, got


OPERATOR_CHECK = """\
import json, sys
import numpy as np
from vemwear.config.build import load_config
from vemwear.solvers.backends.petsc import serve, session

with session() as root:
    if not root:
        serve()
    else:
        d = load_config(sys.argv[1]).problem.discretize(distributed=True)
        s = d.system
        ref = load_config(sys.argv[1]).problem.discrete  # the serial one, whole K
        r = ref.system
        X = np.random.default_rng(2).normal(size=(r.K.shape[0], 3))
        scale = r.K_norm * np.abs(X).max()
        cols = r.contact_cols
        print(json.dumps({
            "operator": type(s.K).__name__,
            "row_sums": float(np.abs(s.K_row_sums - r.K_row_sums).max() / r.K_norm),
            "row_sums_bitwise": bool(np.array_equal(s.K_row_sums, r.K_row_sums)),
            "row_sums_contact_bitwise": bool(
                np.array_equal(s.K_row_sums[cols], r.K_row_sums[cols])
            ),
            "diagonal": float(np.abs(s.K.diagonal() - r.K.diagonal()).max() / r.K_norm),
            "c_ncp_bitwise": bool(np.array_equal(s.c_ncp, r.c_ncp)),
            "rows_bitwise": bool(
                np.array_equal(s.K.rows(cols).toarray(), r.K[cols].toarray())
            ),
            "K_fc_bitwise": bool(np.array_equal(d._K_fc.toarray(), ref._K_fc.toarray())),
            "block": float(np.abs(s.K @ X - r.K @ X).max() / scale),
            "vector": float(np.abs(s.K @ X[:, 0] - r.K @ X[:, 0]).max() / scale),
        }))
"""


@pytest.mark.parametrize(
    ("case", "ranks"), [("2d", 1), ("2d", 2), ("2d", 4), ("2d k=2", 2), ("3d", 1), ("3d", 4)]
)
def test_the_stiffness_kept_by_the_ranks_reads_as_the_serial_one(
    tmp_path: Path, case: str, ranks: int
) -> None:
    """K kept by the ranks, as rank 0's operator: its rows at the contact dofs, K_fc, the
    diagonal at the contact dofs (the complementarity scale) are bitwise the serial
    ones; its absolute row sums (the KKT residuals' scales), summed by the ranks on
    their rows, are bitwise on one rank and at the contact dofs, within 1e-14 of
    |K| elsewhere (an interface row adds the parts of two ranks); its products with a
    vector and a block agree to 1e-14 of |K| |x|."""
    _need_mpi()
    text = {
        "2d": CONFIG_2D,
        "2d k=2": small_config("mpi k=2", divisions=(16, 8), steps=2, vem={"order": 2}),
        "3d": CONFIG_3D,
    }[case]
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    script = tmp_path / "check.py"
    script.write_text(OPERATOR_CHECK)
    done = _run(_mpirun(ranks, sys.executable, str(script), str(cfg)))
    assert done.returncode == 0, done.stdout + done.stderr
    got = json.loads(done.stdout.strip().splitlines()[-1])
    assert got["operator"] == "PetscStiffness"
    for bitwise in ("row_sums_contact_bitwise", "c_ncp_bitwise", "rows_bitwise", "K_fc_bitwise"):
        assert got[bitwise], (bitwise, got)
    if ranks == 1:
        assert got["row_sums_bitwise"], got
    assert got["row_sums"] <= 1e-14 and got["diagonal"] <= 1e-14, got
    assert got["block"] <= 1e-14 and got["vector"] <= 1e-14, got


HELD_CHECK = """\
import json, sys
import scipy.sparse as sp
from vemwear import run_config
from vemwear.config.build import load_config

outcome = run_config(sys.argv[1], sys.argv[2], backend="petsc", progress=False)
if outcome.rank == 0:
    d = outcome.config.problem.discrete
    s = d.system
    held = {}
    for name, obj in (("discrete", d), ("system", s), ("K", s.K)):
        for key, value in vars(obj).items():
            if sp.issparse(value):
                held[f"{name}.{key}"] = int(value.nnz)
    print(json.dumps({
        "operator": type(s.K).__name__,
        "K_full": "K_full" in vars(d),
        "held": held,
        "rows_at": [int(x) for x in s.K._at],
        "contact_cols": [int(x) for x in s.contact_cols],
        "K_nnz": int(load_config(sys.argv[1]).problem.discrete.system.K.nnz),
    }))
"""


def test_rank_0_of_an_mpi_run_holds_no_whole_stiffness(tmp_path: Path) -> None:
    """An MPI run (two ranks, 64 x 32 squares): rank 0's discretization holds K as the
    ranks' operator, whose rows on rank 0 are those of the contact dofs alone; no
    sparse matrix it holds has a tenth of K's entries."""
    _need_mpi()
    cfg = tmp_path / "c.toml"
    cfg.write_text(small_config("mpi held", divisions=(64, 32), steps=2))
    script = tmp_path / "held.py"
    script.write_text(HELD_CHECK)
    done = _run(_mpirun(2, sys.executable, str(script), str(cfg), str(tmp_path / "out")))
    assert done.returncode == 0, done.stdout + done.stderr
    got = json.loads(done.stdout.strip().splitlines()[-1])
    assert got["operator"] == "PetscStiffness" and not got["K_full"]
    assert got["rows_at"] == got["contact_cols"]
    assert "K._rows" in got["held"] and "discrete._K_fc" in got["held"]
    assert max(got["held"].values()) < 0.1 * got["K_nnz"], got


REFUSALS = """\
import json, sys
from vemwear.config.build import load_config
from vemwear.solvers.backends import factorize, schur_factorize

d = load_config(sys.argv[1]).problem.discretize(distributed=True)
s = d.system
said = {}
for name, call in (
    ("smallness", lambda: d.smallness_estimate()),
    ("pardiso", lambda: schur_factorize(s.K, s.contact_cols, s.dof_points, "scipy")),
    ("factorize", lambda: factorize(s.K)),
    ("rows", lambda: s.K.rows([s.K.shape[0] - 1])),  # a dof at the top
    ("resultants", lambda: d.resultants_run([], [], None)),  # no step solver
):
    try:
        call()
        said[name] = None
    except ValueError as exc:
        said[name] = str(exc)
print(json.dumps(said))
"""


def test_what_needs_the_whole_stiffness_is_refused_in_one_line(tmp_path: Path) -> None:
    """With K kept by the ranks (here one process, no mpirun), what would need the
    whole matrix on rank 0 is refused with one line naming the way: the smallness
    estimate without the run's step solver, a factorization by another backend, the
    rows that rank 0 does not hold, the reactions without the run's step solver."""
    _need_mpi()
    cfg = tmp_path / "c.toml"
    cfg.write_text(CONFIG_2D)
    script = tmp_path / "refusals.py"
    script.write_text(REFUSALS)
    done = _run([sys.executable, str(script), str(cfg)])
    assert done.returncode == 0, done.stdout + done.stderr
    said = json.loads(done.stdout.strip().splitlines()[-1])
    assert "give the run's step solver" in said["smallness"]
    assert "factorized by the petsc backend, not 'scipy'" in said["pardiso"]
    assert "condensed Newton (method 'newton') only" in said["factorize"]
    assert "kept by the MPI ranks, not on rank 0" in said["rows"]
    assert "give the step solver whose factorization solves with it" in said["resultants"]
    assert all("\n" not in line for line in said.values())


CONFIG_LOAD_CONTROL = small_config(  # a pad on rollers, held vertically by contact alone
    "mpi load control",
    divisions=(16, 8),
    steps=6,
    boundary={
        "clamped": None,
        "traction": "top",
        "displacement": [{"name": "rollers", "on": ["left", "right"], "ux": 0.0}],
    },
    loads={"f1": [0.0, 0.0], "f2": [0.0, -0.06]},
    contact={"mu": 0.0},
    solver={"backend": None},
    output={"store_u": "all"},
)


def test_load_control_on_two_ranks_equals_serial(tmp_path: Path) -> None:
    """Load control keeps the whole K on rank 0 (its anchored matrix is made from it,
    docs/mpi.md) and its rows are sent to the ranks: the run on two ranks is the
    serial one."""
    _need_mpi()
    cfg = tmp_path / "c.toml"
    cfg.write_text(CONFIG_LOAD_CONTROL)
    done = _run(_vemwear(str(cfg), "-o", str(tmp_path / "serial")))
    assert done.returncode == 0, done.stdout + done.stderr
    out = tmp_path / "mpi"
    done = _run(_mpirun(2, *_vemwear(str(cfg), "-o", str(out), "--backend", "petsc")))
    assert done.returncode == 0, done.stdout + done.stderr
    _assert_equal_runs(_arrays(tmp_path / "serial"), _arrays(out))


def test_other_commands_under_mpirun_are_refused(tmp_path: Path) -> None:
    if MPIRUN is None:
        pytest.skip("no mpirun: the MPI tests need Open MPI (docs/mpi.md)")
    cfg = tmp_path / "c.toml"
    cfg.write_text(CONFIG_2D)
    cmd = _mpirun(2, sys.executable, "-m", "vemwear", "check", str(cfg))
    done = _run(cmd, timeout=120)
    assert done.returncode == 2, done.stdout + done.stderr
    lines = [ln for ln in done.stderr.splitlines() if ln.startswith("vemwear: error:")]
    assert lines == [
        "vemwear: error: started as 2 MPI ranks: only `vemwear run` (with the petsc backend) "
        "runs on several ranks; run this command without mpirun"
    ]
    assert "valid" not in done.stdout
