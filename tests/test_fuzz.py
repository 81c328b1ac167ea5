"""Property-based tests (hypothesis): random meshes and data, random configurations.

1. Random small polygonal meshes (squares, triangles, distorted quadrilaterals,
   Voronoi cells, squares with hanging nodes, perturbed vertices) with random valid data
   either give a result whose KKT residuals are within the tolerance, with finite
   fields, ``u_nu <= g`` and wear ``w >= 0`` non-decreasing in time, or raise a clean
   vemwear error (:class:`ConvergenceError` or a ``ValueError`` with a message).
2. Mutations of a valid configuration (deleted keys, wrong types, negative and
   non-finite numbers, random strings and tables, unknown keys) give a ``Config`` or a
   one-line :class:`ConfigError`, never another exception.
3. Random strings are either accepted or rejected (:class:`ExpressionError`) by the
   expression parser; generated valid expressions evaluate elementwise over arrays.

The example counts keep the file well under a minute on two cores.
"""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import small_config
from vemwear.config import Config, ConfigError, parse_config
from vemwear.config.expr import ExpressionError, parse_expression
from vemwear.contact import LinearCompliance, TableCompliance
from vemwear.mesh import (
    distorted_quads,
    perturb_vertices,
    rectangle_squares,
    rectangle_triangles,
    rectangle_voronoi,
    squares_with_hanging_nodes,
    tag_rectangle,
)
from vemwear.simulate import Problem, SolverOptions, TimeGrid, simulate
from vemwear.solvers import ConvergenceError
from vemwear.vem import Material


def fast(n: int) -> settings:
    """Reproducible, no deadline (the first example imports and compiles a lot), n examples."""
    return settings(
        max_examples=n,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        derandomize=True,
        database=None,
    )


# ---------------------------------------------------------------------------- meshes + data
@st.composite
def meshes(draw: st.DrawFn) -> Any:
    family = draw(
        st.sampled_from(["squares", "triangles", "distorted", "voronoi", "hanging", "perturbed"])
    )
    lx = draw(st.floats(0.5, 3.0))
    ly = draw(st.floats(0.5, 2.0))
    nx, ny = draw(st.integers(2, 5)), draw(st.integers(1, 3))
    seed = draw(st.integers(0, 10_000))
    if family == "squares":
        m = rectangle_squares((lx, ly), (nx, ny))
    elif family == "triangles":
        m = rectangle_triangles(
            (lx, ly), (nx, ny), diagonal=draw(st.sampled_from(["right", "left", "alternate"]))
        )
    elif family == "distorted":
        m = distorted_quads(
            (lx, ly), (nx, max(ny, 2)), amplitude=draw(st.floats(0.0, 0.24)), seed=seed
        )
    elif family == "voronoi":
        m = rectangle_voronoi((lx, ly), n_cells=draw(st.integers(3, 16)), seed=seed)
    elif family == "hanging":
        m = squares_with_hanging_nodes(
            (lx, ly),
            (nx, max(ny, 2)),
            pattern=draw(st.sampled_from(["checkerboard", "random", "bottom", "corner"])),
            seed=seed,
        )
    else:
        base = rectangle_squares((lx, ly), (nx, max(ny, 2)))
        h = min(lx / nx, ly / max(ny, 2))
        m = perturb_vertices(base, draw(st.floats(0.0, 0.24)) * h, seed=seed)
    return tag_rectangle(m)


@st.composite
def problems(draw: st.DrawFn) -> Problem:
    mesh = draw(meshes())
    steps = draw(st.integers(1, 4))
    T = draw(st.floats(0.1, 1.0))
    if draw(st.booleans()):
        c = draw(st.floats(0.01, 2.0))
        law: Any = LinearCompliance(c)
    else:
        r1 = draw(st.floats(0.001, 0.1))
        p1 = draw(st.floats(0.0, 0.1)) * r1  # a soft start, then a slope in [0.01, 2]
        law = TableCompliance((0.0, r1, 2 * r1), (0.0, p1, p1 + draw(st.floats(0.01, 2.0)) * r1))
    angle = draw(st.floats(0.0, 2 * math.pi))
    speed = draw(st.floats(0.1, 2.0))
    g = draw(st.floats(0.01, 0.5))
    g_slope = draw(st.floats(-0.5, 0.5)) * g / max(float(mesh.points[:, 0].max()), 1e-9)
    return Problem(
        mesh=mesh,
        material=Material(draw(st.floats(0.5, 10.0)), draw(st.floats(0.5, 10.0))),
        time=TimeGrid.uniform(T, steps),
        f1=(draw(st.floats(-0.2, 0.2)), draw(st.floats(-0.3, 0.05))),
        f2=(draw(st.floats(-0.05, 0.05)), draw(st.floats(-0.05, 0.05))),
        p=law,
        g=lambda x, g=g, s=g_slope: g + s * x[:, 0],  # stays in [g/2, 3g/2] > 0
        mu=draw(st.floats(0.0, 1.0)),
        kappa=draw(st.floats(0.0, 20.0)),
        v_star=(speed * math.cos(angle), speed * math.sin(angle)),
        stabilization=draw(st.sampled_from(["paper", "eta", "trace"])),
    )


@fast(50)
@given(pr=problems(), method=st.sampled_from(["newton", "newton", "newton-full"]))
def test_random_problems_solve_or_fail_cleanly(pr: Problem, method: str) -> None:
    opts = SolverOptions(method=method, tol=1e-10, backend="scipy")
    try:
        r = simulate(pr, opts)
    except (ConvergenceError, ValueError) as exc:
        assert str(exc).strip(), "an error without a message"
        assert type(exc).__module__.startswith("vemwear") or isinstance(exc, ValueError)
        return
    assert not r.is_partial
    for name in ("u", "wear", "u_nu", "p_rigid", "p_soft", "residuals"):
        assert np.all(np.isfinite(getattr(r, name))), name
    assert np.all(r.residuals <= opts.tol), r.residuals.max(axis=0)
    assert np.all(r.wear >= 0)
    assert np.all(np.diff(r.wear, axis=0) >= 0), "wear must not decrease"
    g = pr.nodal["g"]
    assert np.all(r.u_nu <= g + 10 * opts.tol * g.max())  # the unilateral constraint
    assert np.all(r.p_rigid >= -opts.tol * max(1.0, float(np.abs(r.p_rigid).max())))
    assert np.all(r.p_soft >= 0)
    # the clamped vertices do not move and are no contact nodes
    cl = pr.mesh.part_vertices("clamped")
    assert np.all(r.u[:, cl] == 0) and not set(cl.tolist()) & set(r.contact_nodes.tolist())


# ---------------------------------------------------------------------------- configurations
BASE = small_config(
    "fuzz",
    divisions=(4, 2),
    steps=4,
    boundary={"traction": ["top", "right"]},
    vem={"stabilization": "paper"},
    loads={"f2": [0.0, 0.0]},
    solver={"tol": 1e-10},
    output={"times": [0.5, 1.0]},
)
VARIANTS = {  # other valid forms, so that mutations reach their checks too
    "contact.g": [{"along": "x", "at": [0.0, 2.0], "values": [0.1, 0.05]}, "0.1 + 0.01*x"],
    "contact.mu": [{"at": [0.0, 1.0], "values": [0.0, 0.3]}, "0.2*(1 + sin(pi*x))"],
    "contact.v_star": [
        {"t": [0.0, 1.0], "values": [[1.0, 0.0], [2.0, 0.5]]},
        ["1 + 0.5*sin(2*pi*t)", "0"],
    ],
    "contact.p": [{"type": "table", "r": [0.0, 0.1, 0.2], "p": [0.0, 0.01, 0.1]}],
    "loads.f1": [["0", "-0.06*(1 + x)"]],
    "time": [
        {"dt": [0.25, 0.25, 0.5]},
        {"T": 1.0, "pattern": [0.125, 0.375]},
        {"levels": [0.0, 0.5, 1.0]},
    ],
    "boundary": [
        {"clamped": "left", "contact": "bottom", "traction": "rest"},
        {
            "clamped": {"from": [0.0, 0.0], "to": [0.0, 1.0]},
            "contact": [{"from": [0.0, 0.0], "to": [2.0, 0.0]}],
            "traction": ["top", "right"],
        },
    ],
}
WORDS = [
    "",
    "rest",
    "left",
    "bottom",
    "top",
    "right",
    "file",
    "linear",
    "table",
    "x",
    "s",
    "newton",
    "uzawa",
    "triangles",
    "hexagons",
    "distorted_quads",
    "nan",
    "1/0",
    "x**x",
    "sin(t)",
    "-1",
    "0.1 + t",
    "log(x)",
    "__import__('os')",
    "a" * 80,
    "\u00e9\u00df",
]


def _scalars() -> st.SearchStrategy[Any]:
    return st.one_of(
        st.integers(-5, 50),
        st.floats(allow_nan=True, allow_infinity=True),
        st.floats(-10.0, 10.0),
        st.booleans(),
        st.sampled_from(WORDS),
        st.text(max_size=12),
    )


def _values() -> st.SearchStrategy[Any]:
    return st.recursive(
        _scalars(),
        lambda inner: st.one_of(
            st.lists(inner, max_size=4),
            st.dictionaries(
                st.sampled_from(
                    ["type", "c", "r", "p", "t", "values", "at", "along", "from", "to", "x"]
                ),
                inner,
                max_size=3,
            ),
        ),
        max_leaves=6,
    )


def _paths(d: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out: list[tuple[Any, ...]] = []
    if isinstance(d, dict):
        for k, v in d.items():
            out.append((*prefix, k))
            out += _paths(v, (*prefix, k))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            out.append((*prefix, i))
            out += _paths(v, (*prefix, i))
    return out


def _get(d: Any, path: tuple[Any, ...]) -> Any:
    for k in path:
        d = d[k]
    return d


@st.composite
def mutated_configs(draw: st.DrawFn) -> dict[str, Any]:
    data = tomllib.loads(BASE)
    for key, options in VARIANTS.items():
        if draw(st.booleans()):
            *head, last = key.split(".")
            _get(data, tuple(head))[last] = copy.deepcopy(draw(st.sampled_from(options)))
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(data)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent, last = _get(data, path[:-1]), path[-1]
        what = draw(st.sampled_from(["delete", "replace", "negate", "scale", "add", "wrap"]))
        old = parent[last]
        if what == "delete":
            del parent[last]
        elif what == "replace":
            parent[last] = draw(_values())
        elif what == "negate" and isinstance(old, int | float) and not isinstance(old, bool):
            parent[last] = -old
        elif what == "scale" and isinstance(old, int | float) and not isinstance(old, bool):
            parent[last] = old * draw(st.sampled_from([0, 1e-300, 1e300, 3, 0.5]))
        elif what == "add" and isinstance(old, dict):
            old[draw(st.sampled_from(["muu", "kapa", "T", "x", "type", "file"]))] = draw(_scalars())
        elif what == "wrap":
            parent[last] = [old]
    return data


@fast(300)
@given(data=mutated_configs())
def test_mutated_configs_give_config_or_config_error(
    data: dict[str, Any], tmp_path_factory: Any
) -> None:
    base_dir = tmp_path_factory.getbasetemp()
    try:
        cfg = parse_config(data, source="fuzz.toml", base_dir=base_dir)
    except ConfigError as exc:
        msg = str(exc)
        assert msg.startswith("fuzz.toml: ") and "\n" not in msg and len(msg) < 2000, msg
        return
    assert isinstance(cfg, Config) and isinstance(cfg.problem, Problem)
    assert np.all(cfg.problem.nodal["g"] > 0) and np.all(cfg.problem.nodal["mu"] >= 0)


def test_base_and_variants_are_valid(tmp_path: Path) -> None:
    parse_config(tomllib.loads(BASE), source="fuzz.toml", base_dir=tmp_path)
    for key, options in VARIANTS.items():
        for opt in options:
            data = tomllib.loads(BASE)
            *head, last = key.split(".")
            _get(data, tuple(head))[last] = copy.deepcopy(opt)
            parse_config(data, source="fuzz.toml", base_dir=tmp_path)


# ---------------------------------------------------------------------------- expressions
@fast(300)
@given(
    text=st.one_of(
        st.text(max_size=40),
        st.text(alphabet="xyt0123456789.+-*/()^%, sincoexplgqrtabmp_[]:'\"", max_size=30),
    )
)
def test_expression_parser_accepts_or_rejects_cleanly(text: str) -> None:
    try:
        e = parse_expression(text, ("x", "y", "t"), where="[fuzz] e")
    except ExpressionError as exc:
        assert str(exc).startswith("[fuzz] e"), str(exc)
        return
    x = np.linspace(-2.0, 2.0, 7)
    v = e(x=x, y=x[::-1], t=0.5)
    assert v.shape == x.shape and v.dtype == np.float64


_LEAVES = st.one_of(
    st.sampled_from(["x", "y", "t", "pi"]), st.floats(-5, 5).map(lambda f: f"{f:.3g}")
)


def _expr_text() -> st.SearchStrategy[str]:
    def extend(inner: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
        return st.one_of(
            st.tuples(inner, st.sampled_from(["+", "-", "*", "/", "**"]), inner).map(
                lambda a: f"({a[0]} {a[1]} {a[2]})"
            ),
            inner.map(lambda a: f"-{a}"),
            st.tuples(
                st.sampled_from(["sin", "cos", "tan", "exp", "log", "sqrt", "abs"]), inner
            ).map(lambda a: f"{a[0]}({a[1]})"),
            st.tuples(st.sampled_from(["min", "max"]), inner, inner).map(
                lambda a: f"{a[0]}({a[1]}, {a[2]})"
            ),
        )

    return st.recursive(_LEAVES, extend, max_leaves=8)


def _scalar_eval(text: str, x: float, y: float, t: float) -> float:
    """Reference: the same expression with Python floats (no NumPy), NaN on math errors."""
    import ast
    import operator

    ops = {
        ast.Add: operator.add,
        ast.Sub: operator.sub,
        ast.Mult: operator.mul,
        ast.Div: operator.truediv,
        ast.Pow: operator.pow,
    }
    fns = {
        "sin": math.sin,
        "cos": math.cos,
        "tan": math.tan,
        "exp": math.exp,
        "log": math.log,
        "sqrt": math.sqrt,
        "abs": abs,
    }
    env = {"x": x, "y": y, "t": t, "pi": math.pi}

    def ev(n: ast.AST) -> float:
        if isinstance(n, ast.Constant):
            return float(n.value)
        if isinstance(n, ast.Name):
            return env[n.id]
        if isinstance(n, ast.UnaryOp):
            return -ev(n.operand)
        if isinstance(n, ast.BinOp):
            r = ops[type(n.op)](ev(n.left), ev(n.right))
            if isinstance(r, complex):
                raise ValueError
            return float(r)
        assert isinstance(n, ast.Call) and isinstance(n.func, ast.Name)
        args = [ev(a) for a in n.args]
        if n.func.id in ("min", "max"):
            if any(math.isnan(a) for a in args):
                return math.nan
            return (min if n.func.id == "min" else max)(args)
        return float(fns[n.func.id](args[0]))

    try:
        return ev(ast.parse(text, mode="eval").body)
    except (ValueError, ZeroDivisionError, OverflowError):
        return math.nan


@fast(150)
@given(text=_expr_text())
def test_valid_expressions_evaluate_elementwise(text: str) -> None:
    try:
        e = parse_expression(text, ("x", "y", "t"), where="e")
    except ExpressionError as exc:  # only a constant that is not a finite number
        assert "is not a finite number" in str(exc), str(exc)
        assert not math.isfinite(_scalar_eval(text, 0.0, 0.0, 0.0)) or "e+" in text
        return
    xs = np.array([-1.5, -0.25, 0.0, 0.3, 1.0, 2.5])
    ys = np.array([0.5, -2.0, 1.0, 0.0, 3.0, -0.7])
    got = e(x=xs, y=ys, t=0.75)
    assert got.shape == xs.shape
    want = np.array(
        [_scalar_eval(text, float(a), float(b), 0.75) for a, b in zip(xs, ys, strict=True)]
    )
    fin = np.isfinite(want) & (np.abs(want) < 1e100)
    np.testing.assert_allclose(got[fin], want[fin], rtol=1e-9, atol=1e-12)


def test_configs_are_data_never_code() -> None:
    """No eval/exec/compile of text anywhere in the package (expressions use ast + a whitelist)."""
    import re

    root = Path(__file__).resolve().parents[1] / "src" / "vemwear"
    pattern = re.compile(r"(?<![\w.])(eval|exec|compile|__import__)\s*\(")
    hits = []
    for f in sorted(root.rglob("*.py")):
        for i, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1):
            code = line.split("#", 1)[0]
            if pattern.search(code):
                hits.append(f"{f.relative_to(root)}:{i}: {line.strip()}")
    assert hits == [], "\n".join(hits)
    # the TOML reader cannot run code either: expressions are checked, not evaluated
    with pytest.raises(ExpressionError, match="only the functions"):
        parse_expression("__import__('os').system('true')", ("x",), "g")
