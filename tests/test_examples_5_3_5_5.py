"""Examples 5.3 and 5.5 (and the ``vemwear paper`` report) at small sizes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from vemwear.cli.main import main
from vemwear.paper import EXAMPLES, ex53, ex55, ex55_study
from vemwear.post.compare import Comparison, convergence_orders
from vemwear.simulate import SolverOptions, simulate


# ----------------------------------------------------------------------------- Example 5.3
def test_ex53_time_grids() -> None:
    g = ex53.time_grids(64)
    assert list(g) == ["k64", "alt128", "k32", "k16"]
    assert [gr.n_steps for _l, gr in g.values()] == [64, 64, 32, 16]
    alt = g["alt128"][1]
    np.testing.assert_allclose(alt.k[:4], [1 / 128, 3 / 128, 1 / 128, 3 / 128])
    assert alt.T == 1.0 and alt.k.max() == pytest.approx(3 / 128)
    with pytest.raises(ValueError):
        ex53.time_grids(10)


def test_ex53_wear_curves_close_and_first_order_in_k() -> None:
    """The four w(T) of Example 5.3 are close, and differ as a first-order method in k.

    The wear update (3.22) is the left rectangle rule: w_k(T) = w(T) + C k + o(k). With
    the uniform steps 1/64, 1/32, 1/16 the differences to the 1/64 run are then C/64 and
    3 C/64 (ratio 3), and the relative differences are of the order of k_max times
    |C| / max w: at the paper's size they are 0.35 % (1/32) and 1.05 % (1/16). We assert
    every pairwise relative difference < 3 % (three times the expected largest one, for a
    coarser mesh than the paper's) and the ratio within [2.5, 3.5].
    """
    probs = ex53.problems(divisions=(16, 8))
    res = {n: simulate(p, store="final") for n, p in probs.items()}
    rows = ex53.differences(res)
    assert len(rows) == 6
    assert max(r["rel"] for r in rows) < 0.03
    d = {(r["a"], r["b"]): r["max_abs"] for r in rows}
    ratio = d[("k64", "k16")] / d[("k64", "k32")]
    assert 2.5 < ratio < 3.5
    # the alternating grid (mean step 1/64, largest 3/128) is closer to k = 1/64 than 1/32 is
    assert d[("k64", "alt128")] < d[("k64", "k32")]
    assert "| uniform k = 1/64 |" in ex53.differences_markdown(rows, ex53.GRID_LABELS)
    assert ex53.differences_csv(rows).count("\n") == 7


def test_ex53_run_writes_outputs(tmp_path: Path) -> None:
    ex = ex53.run(tmp_path, divisions=(8, 4), base_steps=8, vtk=False)
    for f in (
        "fig6.png",
        "wear_differences.md",
        "wear_differences.csv",
        "example_5_3.md",
        "k64/result.npz",
        "alt128/summary.json",
        "k16/result.npz",
    ):
        assert (tmp_path / f).is_file(), f
    assert set(ex.results) == {"k64", "alt128", "k32", "k16"}
    assert ex.details["max_rel_diff"] < 0.2
    assert "Pairwise differences" in (tmp_path / "example_5_3.md").read_text()


# ----------------------------------------------------------------------------- Example 5.5
def test_ex55_sizes_and_times() -> None:
    assert ex55.check_sizes([8, 4], 16) == ((4, 8), 16)
    for bad in ([3], [4, 4], [32]):
        with pytest.raises(ValueError):
            ex55.check_sizes(bad, 16)
    t = ex55.common_times([2, 4])
    np.testing.assert_allclose(t, [0, 0.25, 0.5, 0.75, 1.0])


def test_contact_problem_orders_near_one() -> None:
    """Errors of h = k = 1/4, 1/8, 1/16 against the reference h = k = 1/32.

    The paper's estimate is O(h + k) and its Tables 1-2 show orders 0.84-1.12. We
    assert that the errors decrease and (a) the orders at t = T lie in [0.5, 1.7] and
    (b) the mean order over h = 1/4 -> 1/16, log2(e_4 / e_16) / 2, lies in [0.6, 1.6],
    for displacement and wear, at t = T and for the maximum over time. The bands are
    wide because (i) the reference is only twice finer than h = 1/16, which inflates the
    last order (measured: about 1.4 for the wear); (ii) the maximum over time levels
    can move from one level to another between meshes, which makes single orders of the
    maximum irregular (0.47-1.37 measured), hence only their mean is tested; (iii) these
    coarse meshes are pre-asymptotic (the paper's orders also vary by 0.05).
    """
    ns = (4, 8, 16)
    ref = simulate(ex55.problem(32), store=ex55.common_times(ns))
    cmp = Comparison(ref)
    hs = {n: cmp.errors(simulate(ex55.problem(n))) for n in ns}
    for q in ("displacement", "wear"):
        for how in ("T", "max"):
            e = [hs[n].at_T(q) if how == "T" else hs[n].max(q) for n in ns]
            assert e[0] > e[1] > e[2] > 0, (q, how, e)
            mean = np.log2(e[0] / e[2]) / 2
            assert 0.6 <= mean <= 1.6, (q, how, e, mean)
            if how == "T":
                o = convergence_orders(e)
                assert np.all((o >= 0.5) & (o <= 1.7)), (q, o)


def test_ex55_run_writes_outputs_and_uses_cache(tmp_path: Path) -> None:
    out, cache = tmp_path / "out", tmp_path / "cache"
    out.mkdir()
    ex = ex55.run(out, levels=(2, 4), reference=8, cache=cache, vtk=False)
    for f in (
        "table1.md",
        "table2.md",
        "errors.csv",
        "convergence.png",
        "example_5_5.md",
        "h2/result.npz",
        "h4/summary.json",
    ):
        assert (out / f).is_file(), f
    assert not ex.details["reference_info"]["cached"]
    metas = list(cache.glob("ex55_reference_h8_*.json"))
    assert len(metas) == 1 and len(list(cache.glob("*.npz"))) == 1
    meta = json.loads(metas[0].read_text())
    assert meta["inputs"]["reference"] == 8 and meta["stored_times"] == [0, 0.25, 0.5, 0.75, 1]
    t1 = (out / "table1.md").read_text()
    assert "7.0581e-02" in t1  # the paper's number (h = 1/4) beside ours
    assert "1.1153e-01" in (out / "table2.md").read_text()
    csv = (out / "errors.csv").read_text().splitlines()
    assert len(csv) == 3 and csv[0].startswith("inv_h,h,k,u_H1,u_H1_order,u_H1_max")
    # the second run reuses the reference and gives the same tables
    out2 = tmp_path / "out2"
    out2.mkdir()
    ex2 = ex55.run(out2, levels=(2, 4), reference=8, cache=cache, figures=False, vtk=False)
    assert ex2.details["reference_info"]["cached"]
    assert ex2.details["tables"]["u_H1"]["errors"] == ex.details["tables"]["u_H1"]["errors"]
    # other inputs (the solver tolerance), another cache entry
    out3 = tmp_path / "out3"
    out3.mkdir()
    ex3 = ex55.run(
        out3,
        levels=(2,),
        reference=8,
        cache=cache,
        figures=False,
        vtk=False,
        solver=SolverOptions(tol=1e-9),
    )
    assert not ex3.details["reference_info"]["cached"]
    assert len(list(cache.glob("*.json"))) == 2


def test_ex55_wear_error_study_small(tmp_path: Path) -> None:
    """The space / time split of the wear error (docs/paper.md, Table 2) at a small size:
    the h = k runs of the study are those of the tables; the time part dominates; the
    first step's error follows (k - k_ref) rho(0) / 2; the rates decay no faster than
    alpha L_p (u_nu does not decrease)."""
    ex = ex55.run(tmp_path, levels=(2, 4), reference=8, cache=None, figures=False, study=True)
    st = ex.details["study"]
    assert [r["full"] for r in st["rows"]] == ex.details["tables"]["w_L2"]["errors"]
    for r in st["rows"]:
        assert r["time"] > 3.0 * r["space"] > 0, r
        assert r["first_step"] == pytest.approx(r["first_step_predicted"], rel=0.15), r
        assert np.isnan(r["paper"])  # the paper's numbers need the 1/256 reference
    rates = st["rates"]
    assert 0.3 < rates["rho0"] < rates["rho_max"] <= rates["rho_bound"] * (1 + 1e-9)
    assert "space only" in (tmp_path / "table2_study.md").read_text()
    assert "table2_study.md" in ex.files
    with pytest.raises(ValueError, match="unknown runs"):
        ex55_study.wear_error_study(levels=(2,), reference=8, runs=("bogus",))


def test_cli_example_55_and_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    cache = tmp_path / "user-cache"  # the user's cache directory (platformdirs)
    monkeypatch.setenv("VEMWEAR_CACHE_DIR", str(cache))
    out = tmp_path / "ex55"
    rc = main(
        [
            "example",
            "5.5",
            "-o",
            str(out),
            "--reference-h",
            "1/8",
            "--levels",
            "2,4",
            "--no-progress",
        ]
    )
    assert rc == 0
    printed = capsys.readouterr().out
    assert "Table 1" in printed and "7.0581e-02" in printed
    assert (out / "table1.md").is_file()
    # the cache is in the user's cache directory, never beside OUTDIR
    assert list(cache.glob("ex55_reference_h8_*.npz"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ex55", "user-cache"]
    size = sum(f.stat().st_size for f in cache.iterdir())
    assert main(["clean", "--cache"]) == 0
    assert capsys.readouterr().out == (
        f"vemwear: cache {cache}: {size / 1e6:.1f} MB in 2 file(s) removed\n"
    )
    assert not cache.exists()
    assert (
        main(["example", "5.5", "-o", str(tmp_path / "x"), "--reference-h", "8", "--levels", "3"])
        == 2
    )
    assert main(["example", "5.3", "-o", str(tmp_path / "y"), "--levels", "4"]) == 2
    assert main(["example", "5.5", "-o", str(tmp_path / "z"), "--levels", "a"]) == 2
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


# ----------------------------------------------------------------------------- vemwear paper
def test_paper_report_small(tmp_path: Path) -> None:
    from vemwear.paper.report import run_paper

    # per-run figures are slow; Example 5.3 at this size and 5.5 keep theirs
    sizes = {
        "5.2": {"divisions": (8, 4), "steps": 4, "figures": False},
        "5.3": {"divisions": (8, 4), "base_steps": 4},
        "5.4": {
            "divisions": (8, 4),
            "n_cells": 32,
            "steps": 4,
            "study_cells": None,
            "figures": False,
        },
        "5.5": {"levels": (4,), "reference": 8},
    }
    out = tmp_path / "paper"
    out.mkdir()
    pr = run_paper(out, cache=tmp_path / "cache", sizes=sizes)
    text = pr.report.read_text()
    assert "Total wall time" in text
    for name in ("5.2", "5.3", "5.5"):
        assert (out / f"example_{name.replace('.', '_')}").is_dir()
        assert f"Example {name}" in text
    if "5.4" in EXAMPLES:
        assert "5.4" in pr.runs and "## Example 5.4" in text
    assert "7.0581e-02" in text and "1.1153e-01" in text
    # every figure is linked
    for png in out.rglob("*.png"):
        assert str(png.relative_to(out)) in text, png


# ----------------------------------------------------------------------------- the driver
def test_driver_rejects_unknown_parameters_before_any_run(tmp_path: Path) -> None:
    with pytest.raises(TypeError, match=r"unknown parameter\(s\) base_step; it takes"):
        ex53.run(tmp_path, base_step=8)
    with pytest.raises(ValueError, match="multiple of 4"):
        ex53.run(tmp_path, base_steps=6)
    with pytest.raises(ValueError, match="must divide the reference"):
        ex55.run(tmp_path, levels=(3,), reference=8)
    assert list(tmp_path.iterdir()) == []


def test_available_examples_imports_no_example_and_no_numerics() -> None:
    import subprocess
    import sys

    code = (
        "import sys, vemwear.paper as p; d = p.available_examples(); "
        "assert list(d) == ['5.2', '5.3', '5.4', '5.5', '3d', 'hertz'], d; "
        "assert all(v.startswith(('Example 5.', 'Example 3d', 'Example hertz')) "
        "for v in d.values()), d; "
        "bad = [m for m in ('numpy', 'vemwear.paper.ex52', 'vemwear.simulate') "
        "if m in sys.modules]; assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_every_example_is_data_for_the_one_driver() -> None:
    from vemwear.paper import DESCRIPTIONS, load_example
    from vemwear.paper.spec import Example

    for name in EXAMPLES:
        ex = load_example(name).EXAMPLE
        assert isinstance(ex, Example) and ex.name == name
        assert ex.description == DESCRIPTIONS[name] and ex.paper_section is not None
        assert ex.headlines, name  # pinned in tests/test_paper_numbers.py
        names = [f.name for f in ex.outputs]
        assert len(names) == len(set(names)) and ex.report_name not in names
