"""vemwear against GetFEM (benchmarks/bench_getfem.py) at small sizes: the same wear.

On triangles and on tetrahedra the lowest-order virtual element space is the P1 space,
so GetFEM's P1 solution of the same model with the same nodal contact quadrature has
vemwear's wear up to round-off. The benchmark runs both codes in child processes on one
mesh; these tests read its numbers back and skip when no Python can import getfem
(Debian: ``apt-get install python3-getfem``).
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_getfem.py"


def _bench():
    spec = importlib.util.spec_from_file_location("bench_getfem", SCRIPT)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


GETFEM_PYTHON = _bench().getfem_python()
needs_getfem = pytest.mark.skipif(GETFEM_PYTHON is None, reason="no Python imports getfem")


def _compare(tmp_path, *args: str) -> dict:
    out = tmp_path / "numbers.json"
    cmd = [sys.executable, str(SCRIPT), *args, "--repeat", "1", "--json", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(out.read_text())


@needs_getfem
def test_wear_agrees_with_getfem_on_triangles(tmp_path):
    numbers = _compare(tmp_path, "--sizes", "8", "--steps", "8")
    row = numbers["8x4"]
    assert row["dofs"] == 2 * 9 * 5 and row["levels"] == 9
    gf_its, vem_its = row["its"].split("/")
    assert gf_its == vem_its
    assert row["wmax"] > 0.01  # the body wears
    assert row["rel_nodal"] <= 1e-10 and row["rel_max"] <= 1e-10


@needs_getfem
def test_wear_agrees_with_getfem_on_tetrahedra(tmp_path):
    numbers = _compare(tmp_path, "--3d", "--sizes", "4", "6", "--steps", "6")
    for label, nodes in (("4x2x2", 5 * 3 * 3), ("6x3x3", 7 * 4 * 4)):
        row = numbers[label]
        assert row["dofs"] == 3 * nodes and row["levels"] == 7
        gf_its, vem_its = row["its"].split("/")
        assert gf_its == vem_its
        assert row["wmax"] > 0.01
        assert row["rel_nodal"] <= 1e-10 and row["rel_max"] <= 1e-10, label


def test_contact_nodes_are_matched_by_their_coordinates(tmp_path):
    """The agreement finds vemwear's contact nodes among GetFEM's (which also has the
    clamped ones) in any order, and refuses nodes GetFEM does not have."""
    import numpy as np

    bench = _bench()
    x_g = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.0], [2.0, 0.0]])
    w_g = np.array([0.0, 0.2, 0.1, 0.4])
    np.savez(tmp_path / "g.npz", x=x_g, w=w_g)
    np.savez(tmp_path / "v.npz", x=x_g[[3, 2, 1]], w=np.array([0.4, 0.1, 0.2 + 4e-9]))
    wmax, rel_max, rel_nodal = bench._agreement(str(tmp_path / "v.npz"), str(tmp_path / "g.npz"))
    assert wmax == 0.4 and rel_max == 0.0 and rel_nodal == pytest.approx(1e-8)
    np.savez(tmp_path / "v.npz", x=np.array([[0.25, 0.0]]), w=np.array([0.1]))
    with pytest.raises(SystemExit, match="contact nodes of the two codes differ"):
        bench._agreement(str(tmp_path / "v.npz"), str(tmp_path / "g.npz"))


def test_without_getfem_the_script_says_so_and_exits_0(tmp_path):
    missing = tmp_path / "no-python"
    for extra in ((), ("--3d",)):
        cmd = [sys.executable, str(SCRIPT), *extra, "--getfem-python", str(missing)]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr
        assert f"GetFEM is not importable (tried {missing})" in proc.stdout
