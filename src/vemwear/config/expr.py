"""Safe arithmetic expressions for data given as strings in configuration files.

A configuration file is data, never code: nothing in it is evaluated by Python.
Strings such as ``"1 + 0.5*sin(2*pi*t)"`` or ``"-0.06*(1 + x)"`` are parsed with
:func:`ast.parse` into a syntax tree that is checked against a whitelist and then
evaluated by a small interpreter over NumPy arrays (vectorized: ``x``, ``y`` and
``t`` may be arrays of any broadcastable shapes).

Allowed (the whole language):

- numbers: ``2``, ``0.5``, ``1e-3`` (integers are read as floats);
- the names of the key (a subset of ``t``, ``x``, ``y``) and the constant ``pi``;
- ``+ - * / **``, unary ``-`` and ``+``, parentheses;
- the functions ``sin cos tan exp log sqrt abs`` (one argument) and ``min max``
  (two or more arguments, elementwise).

Anything else (attribute access, subscripts, calls of other names, keyword
arguments, lambdas, comprehensions, comparisons, strings, ``%``, ``//``, ``^``, ...)
is rejected by :func:`parse_expression` with an :class:`ExpressionError` naming the
key and the offending part. Values that are not finite where they are used (e.g.
``log(x)`` at ``x = 0``) are reported by the caller, which knows the points.
"""

from __future__ import annotations

import ast
import difflib
import functools
import math
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "CONSTANTS",
    "FUNCTIONS",
    "MAX_LENGTH",
    "Expression",
    "ExpressionError",
    "parse_expression",
]

#: Longest accepted expression (characters) and largest syntax tree (nodes).
MAX_LENGTH = 1000
MAX_NODES = 400
MAX_DEPTH = 100

#: Functions of one argument, applied elementwise.
FUNCTIONS: dict[str, Callable[[NDArray[np.float64]], NDArray[np.float64]]] = {
    "sin": np.sin,
    "cos": np.cos,
    "tan": np.tan,
    "exp": np.exp,
    "log": np.log,
    "sqrt": np.sqrt,
    "abs": np.abs,
}
#: Functions of two or more arguments, elementwise.
REDUCTIONS: dict[str, Callable[[Any, Any], NDArray[np.float64]]] = {
    "min": np.minimum,
    "max": np.maximum,
}
#: Named constants.
CONSTANTS: dict[str, float] = {"pi": math.pi}

_BINOPS: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: np.add,
    ast.Sub: np.subtract,
    ast.Mult: np.multiply,
    ast.Div: np.true_divide,
    ast.Pow: np.power,
}
_REJECTED_OPS: dict[type[ast.operator], str] = {
    ast.BitXor: "'^' is not a power; write '**'",
    ast.Mod: "'%' is not allowed",
    ast.FloorDiv: "'//' is not allowed; write '/'",
    ast.MatMult: "'@' is not allowed",
    ast.LShift: "'<<' is not allowed",
    ast.RShift: "'>>' is not allowed",
    ast.BitOr: "'|' is not allowed",
    ast.BitAnd: "'&' is not allowed",
}
_WHAT: dict[type[ast.AST], str] = {
    ast.Attribute: "attribute access",
    ast.Subscript: "a subscript",
    ast.Lambda: "a lambda function",
    ast.ListComp: "a comprehension",
    ast.SetComp: "a comprehension",
    ast.DictComp: "a comprehension",
    ast.GeneratorExp: "a comprehension",
    ast.Compare: "a comparison",
    ast.BoolOp: "'and' / 'or'",
    ast.IfExp: "a conditional expression",
    ast.List: "a list",
    ast.Tuple: "a tuple",
    ast.Set: "a set",
    ast.Dict: "a dictionary",
    ast.NamedExpr: "an assignment",
    ast.Starred: "a starred argument",
    ast.JoinedStr: "a string",
    ast.FormattedValue: "a string",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
    ast.Slice: "a slice",
}
_UNIT_LIKE = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*[A-Za-z%]\w*\s*$")


class ExpressionError(ValueError):
    """An expression string that is not in the allowed language; the message names the key."""


def _allowed_text(names: Iterable[str]) -> str:
    ns = ", ".join(sorted(names))
    return (
        f"allowed: numbers, the names {ns + ', ' if ns else ''}pi, + - * / ** and "
        "the functions sin cos tan exp log sqrt abs min max"
    )


@dataclass(frozen=True, eq=False)
class Expression:
    """A checked arithmetic expression, evaluated elementwise over NumPy arrays.

    Create it with :func:`parse_expression`.

    Attributes
    ----------
    text : str
        The expression as written.
    names : frozenset of str
        The variables it uses (a subset of the names allowed for its key).
    """

    text: str
    names: frozenset[str]
    _tree: ast.expr = field(repr=False)
    _value: float | None = field(default=None, repr=False)

    @property
    def is_constant(self) -> bool:
        """True if the expression uses no variable."""
        return not self.names

    def __call__(self, **env: ArrayLike) -> NDArray[np.float64]:
        """Evaluate with the given variables (arrays broadcast against each other).

        Parameters
        ----------
        **env : array_like
            Values of the variables, e.g. ``x=points[:, 0], y=points[:, 1]``. Every
            variable the expression uses must be given; others are ignored except for
            the shape of the result.

        Returns
        -------
        ndarray of float
            The values, of the broadcast shape of all given variables (a constant
            expression is broadcast too). Non-finite values are returned as they are.
        """
        missing = self.names - env.keys()
        if missing:
            raise ExpressionError(
                f"expression {self.text!r} needs the variables {', '.join(sorted(missing))}"
            )
        arrays = {k: np.asarray(v, dtype=float) for k, v in env.items()}
        shape = np.broadcast_shapes(*(a.shape for a in arrays.values())) if arrays else ()
        if self._value is not None:
            return np.full(shape, self._value)
        with np.errstate(all="ignore"):
            out = np.asarray(_evaluate(self._tree, arrays), dtype=float)
        return np.broadcast_to(out, shape).copy() if out.shape != shape else out

    def __str__(self) -> str:
        return self.text


def parse_expression(
    text: str, names: Iterable[str] = ("t", "x", "y"), where: str = "expression"
) -> Expression:
    """Parse and check an expression string.

    Parameters
    ----------
    text : str
        The expression, e.g. ``"0.1 + 0.01*x"``.
    names : iterable of str
        The variables allowed for this key (a subset of ``t``, ``x``, ``y``).
    where : str
        The key path, used in error messages (e.g. ``"config.toml: [contact] g"``).

    Returns
    -------
    Expression

    Raises
    ------
    ExpressionError
        If the string is empty, too long, not valid syntax, or uses anything outside
        the allowed language; the message names ``where`` and the offending part.
    """
    allowed = frozenset(names)
    head = f"{where} = {_short(text)}"
    if not isinstance(text, str):
        raise ExpressionError(f"{where} must be a string expression, got {type(text).__name__}")
    if not text.strip():
        raise ExpressionError(f"{where} is an empty expression")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"{where}: expression longer than {MAX_LENGTH} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        hint = ""
        if _UNIT_LIKE.match(text):
            hint = (
                "; units are not accepted: write plain numbers in consistent units (docs/config.md)"
            )
        raise ExpressionError(
            f"{head} is not a valid expression ({exc.msg}"
            f"{f' at column {exc.offset}' if exc.offset else ''}){hint}; "
            f"{_allowed_text(allowed)}"
        ) from None
    except (ValueError, RecursionError, MemoryError) as exc:  # null bytes, deep nesting
        raise ExpressionError(f"{head} is not a valid expression ({exc})") from None
    used: set[str] = set()
    counter = [0]
    _check(tree.body, text, allowed, used, head, counter, 0)
    value = None
    if not used:  # constant: fold once, checking that it is finite
        with np.errstate(all="ignore"):
            value = float(np.asarray(_evaluate(tree.body, {}), dtype=float))
        if not math.isfinite(value):
            raise ExpressionError(f"{head} is not a finite number (it evaluates to {value})")
    return Expression(text=text, names=frozenset(used), _tree=tree.body, _value=value)


def _short(text: Any) -> str:
    s = repr(text)
    return s if len(s) <= 80 else s[:77] + "..."


def _segment(text: str, node: ast.AST) -> str:
    seg = ast.get_source_segment(text.strip(), node)
    return f" ({_short(seg)})" if seg else ""


def _check(
    node: ast.AST,
    text: str,
    allowed: frozenset[str],
    used: set[str],
    head: str,
    counter: list[int],
    depth: int,
) -> None:
    """Reject every node outside the language (recursively, children after their parent)."""
    counter[0] += 1
    if counter[0] > MAX_NODES:
        raise ExpressionError(f"{head} is too complex (more than {MAX_NODES} terms)")
    if depth > MAX_DEPTH:
        raise ExpressionError(f"{head} is nested too deeply (more than {MAX_DEPTH} levels)")

    def sub(child: ast.AST) -> None:
        _check(child, text, allowed, used, head, counter, depth + 1)

    if isinstance(node, ast.Constant):
        v = node.value
        if isinstance(v, str | bytes):
            raise ExpressionError(
                f"{head}: a string is not allowed in an expression"
                f"{_segment(text, node)}; {_allowed_text(allowed)}"
            )
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise ExpressionError(
                f"{head}: the constant {v!r} is not allowed in an "
                f"expression; {_allowed_text(allowed)}"
            )
        try:
            float(v)
        except OverflowError:
            raise ExpressionError(f"{head}: the number {_short(str(v))} is too large") from None
        return
    if isinstance(node, ast.Name):
        if node.id in allowed or node.id in CONSTANTS:
            if node.id in allowed:
                used.add(node.id)
            return
        if node.id in FUNCTIONS or node.id in REDUCTIONS:
            raise ExpressionError(
                f"{head}: the function {node.id!r} must be called, e.g. {node.id}(x)"
            )
        if node.id in ("t", "x", "y"):
            raise ExpressionError(
                f"{head}: the variable {node.id!r} cannot be used here (this key depends on "
                f"{', '.join(sorted(allowed)) if allowed else 'no variable'} only)"
            )
        close = difflib.get_close_matches(node.id, [*allowed, *CONSTANTS], n=1, cutoff=0.6)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ExpressionError(f"{head}: unknown name {node.id!r}{hint}; {_allowed_text(allowed)}")
    if isinstance(node, ast.BinOp):
        op = type(node.op)
        if op not in _BINOPS:
            raise ExpressionError(
                f"{head}: {_REJECTED_OPS.get(op, 'operator not allowed')}"
                f"{_segment(text, node)}; {_allowed_text(allowed)}"
            )
        sub(node.left)
        sub(node.right)
        return
    if isinstance(node, ast.UnaryOp):
        if not isinstance(node.op, ast.USub | ast.UAdd):
            raise ExpressionError(
                f"{head}: the operator {type(node.op).__name__} is not "
                f"allowed{_segment(text, node)}; {_allowed_text(allowed)}"
            )
        sub(node.operand)
        return
    if isinstance(node, ast.Call):
        f = node.func
        if not isinstance(f, ast.Name):
            raise ExpressionError(
                f"{head}: only the functions sin cos tan exp log sqrt abs "
                f"min max can be called{_segment(text, node)}"
            )
        if f.id not in FUNCTIONS and f.id not in REDUCTIONS:
            close = difflib.get_close_matches(f.id, [*FUNCTIONS, *REDUCTIONS], n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ExpressionError(
                f"{head}: unknown function {f.id!r}{hint}; only sin cos tan "
                "exp log sqrt abs min max can be called"
            )
        if node.keywords:
            raise ExpressionError(
                f"{head}: keyword arguments are not allowed{_segment(text, node)}"
            )
        if any(isinstance(a, ast.Starred) for a in node.args):
            raise ExpressionError(
                f"{head}: starred arguments are not allowed{_segment(text, node)}"
            )
        n = len(node.args)
        if f.id in FUNCTIONS and n != 1:
            raise ExpressionError(
                f"{head}: {f.id} takes exactly 1 argument, got {n}{_segment(text, node)}"
            )
        if f.id in REDUCTIONS and n < 2:
            raise ExpressionError(
                f"{head}: {f.id} takes 2 or more arguments, got {n}{_segment(text, node)}"
            )
        for a in node.args:
            sub(a)
        return
    what = next(
        (w for t, w in _WHAT.items() if isinstance(node, t)), f"the construct {type(node).__name__}"
    )
    raise ExpressionError(
        f"{head}: {what} is not allowed in an expression"
        f"{_segment(text, node)}; {_allowed_text(allowed)}"
    )


def _evaluate(node: ast.expr, env: dict[str, NDArray[np.float64]]) -> Any:
    """Evaluate a checked tree (only the node kinds accepted by :func:`_check`)."""
    if isinstance(node, ast.Constant):
        return np.float64(cast(float, node.value))
    if isinstance(node, ast.Name):
        if node.id in env:
            return env[node.id]
        return np.float64(CONSTANTS[node.id])
    if isinstance(node, ast.BinOp):
        return _BINOPS[type(node.op)](_evaluate(node.left, env), _evaluate(node.right, env))
    if isinstance(node, ast.UnaryOp):
        v = _evaluate(node.operand, env)
        return np.negative(v) if isinstance(node.op, ast.USub) else v
    if isinstance(node, ast.Call):
        name = node.func.id  # type: ignore[attr-defined]
        args = [_evaluate(a, env) for a in node.args]
        if name in FUNCTIONS:
            return FUNCTIONS[name](args[0])
        return functools.reduce(REDUCTIONS[name], args)
    raise ExpressionError(f"unexpected expression node {type(node).__name__}")  # pragma: no cover
