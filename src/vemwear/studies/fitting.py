"""``vemwear fit``: calibrate kappa (and mu, c, g) against measured wear profiles.

The measured data are a CSV file with a header naming the columns ``x`` (the
coordinate along the foundation: the contact nodes' x) or ``s`` (the arc length along
Gamma_C), ``w`` (the measured wear) and ``t`` (the time of the measurement; one or
several times). The model's wear is interpolated linearly in time between its levels
and along x or s between its contact nodes.

The parameters (``kappa`` = ``[contact] kappa``, ``mu``, ``c`` = the constant of a
linear compliance ``[contact] p.c``, ``g``; each a number in the configuration, the
start of the fit) are found by :func:`scipy.optimize.least_squares` (trust region
reflective, within bounds) on the residuals ``(w_model - w_measured) / sigma``: sigma
from a ``sigma`` column, else proportional to the measured wear (``errors =
"relative"``, the default: a relative measurement error, at least 1 % of the largest
wear) or 1 (``errors = "absolute"``). The Jacobian is
by forward differences (relative step 1e-5), its runs a Dask study: every trial point is
run together with its perturbed points in parallel, so the Jacobian of an accepted
point costs no extra wall time with ``p + 1`` workers. The covariance of the estimate
is ``s^2 (J^T J)^-1`` with ``s^2 = |r|^2 / (n - p)``, and the 95 % intervals are
``estimate +- t_{0.975, n-p} * sqrt(diag)``.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import shutil
import tempfile
import time
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..util.hashing import sha256_json
from .design import RunSpec, StudyError, params_text

__all__ = ["PARAMETERS", "FitResult", "Measured", "fit", "read_measured"]

#: The parameters a fit may calibrate: name -> (configuration key, default bounds).
PARAMETERS: dict[str, tuple[str, tuple[float, float]]] = {
    "kappa": ("contact.kappa", (0.0, math.inf)),
    "mu": ("contact.mu", (0.0, math.inf)),
    "c": ("contact.p.c", (0.0, math.inf)),
    "g": ("contact.g", (1e-12, math.inf)),
}
_RUN_OUTPUT = {"output.figures": False, "output.vtk": False, "output.store_u": "final"}
_STEP = 1e-5


@dataclass(frozen=True)
class Measured:
    """Measured wear: ``w`` at the points ``a`` (x or s, per ``abscissa``) at times ``t``."""

    abscissa: str
    a: NDArray[np.float64]
    t: NDArray[np.float64]
    w: NDArray[np.float64]
    source: str = ""
    sigma: NDArray[np.float64] | None = None

    def scale(self, errors: str) -> NDArray[np.float64]:
        """The standard error of each point up to a common factor: the ``sigma`` column
        if given; else 1 (``errors = "absolute"``) or ``|w|``, at least 1 % of the largest
        ``|w|`` (``errors = "relative"``)."""
        if self.sigma is not None:
            return self.sigma
        if errors == "absolute":
            return np.ones_like(self.w)
        big = float(np.max(np.abs(self.w), initial=0.0)) or 1.0
        return np.maximum(np.abs(self.w), 0.01 * big)


def read_measured(path: str | os.PathLike[str]) -> Measured:
    """Read a CSV of measured wear (columns ``x`` or ``s``, ``w``, ``t``; any order; an
    optional column ``sigma``, the standard error of each point, weighs the residuals).

    Raises
    ------
    StudyError
        Naming the file, the line and the problem.
    """
    from ..util.text import NotUtf8Error, read_utf8

    src = str(path)
    try:
        rows = list(csv.reader(io.StringIO(read_utf8(path), newline="")))
    except NotUtf8Error as exc:
        raise StudyError(f"{src}: {exc}") from None
    except OSError as exc:
        raise StudyError(f"{src}: cannot read the data: {exc.strerror or exc}") from None
    rows = [r for r in rows if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise StudyError(f"{src}: no data")
    head = [h.strip().lower() for h in rows[0]]
    ab = [c for c in ("x", "s") if c in head]
    if len(ab) != 1 or "w" not in head or "t" not in head:
        raise StudyError(
            f"{src}: the header must name the columns w, t and one of x or s, got {rows[0]}"
        )
    cols = {c: head.index(c) for c in (ab[0], "w", "t", "sigma") if c in head}
    vals: dict[str, list[float]] = {c: [] for c in cols}
    for n, r in enumerate(rows[1:], start=2):
        for c, i in cols.items():
            try:
                v = float(r[i])
            except (IndexError, ValueError):
                got = r[i] if i < len(r) else "nothing"
                raise StudyError(
                    f"{src}: line {n}: column {c} must be a number, got {got!r}"
                ) from None
            if not math.isfinite(v):
                raise StudyError(f"{src}: line {n}: column {c} must be finite, got {v}")
            vals[c].append(v)
    arr = {c: np.asarray(v, dtype=np.float64) for c, v in vals.items()}
    if arr["w"].size == 0:
        raise StudyError(f"{src}: no data rows")
    sig = arr.get("sigma")
    if sig is not None and np.any(sig <= 0):
        raise StudyError(f"{src}: column sigma must be > 0")
    return Measured(ab[0], arr[ab[0]], arr["t"], arr["w"], src, sig)


@dataclass
class FitResult:
    """The outcome of :func:`fit`.

    Attributes
    ----------
    params : tuple of str
        The calibrated parameters, e.g. ``("kappa",)``.
    estimate, initial, stderr : dict
        The estimates, the starting values (from the configuration), standard errors.
    interval : dict
        The 95 % confidence interval ``(low, high)`` of each parameter.
    residuals : ndarray
        ``w_model - w_measured`` at the estimate, in the order of the data.
    errors : str
        How the residuals were weighed: ``relative``, ``absolute`` or ``sigma``.
    fitted : ndarray
        ``w_model`` at the data points.
    s2 : float
        The variance of the weighted residuals, ``|r|^2 / (n - p)``.
    covariance, jacobian : ndarray
        ``s^2 (J^T J)^-1`` and J at the estimate.
    success : bool
    message : str
        Of :func:`scipy.optimize.least_squares`.
    nfev, runs : int
        Trial points evaluated, model runs made (with the Jacobian's).
    seconds : float
    data : Measured
    """

    params: tuple[str, ...]
    estimate: dict[str, float]
    initial: dict[str, float]
    stderr: dict[str, float]
    interval: dict[str, tuple[float, float]]
    residuals: NDArray[np.float64]
    fitted: NDArray[np.float64]
    s2: float
    covariance: NDArray[np.float64]
    jacobian: NDArray[np.float64]
    success: bool
    message: str
    nfev: int
    runs: int
    seconds: float
    data: Measured
    errors: str = "relative"
    profiles: dict[str, Any] = field(default_factory=dict, repr=False)

    def rows(self) -> list[tuple[str, str]]:
        """Two columns for printing: each parameter's estimate and interval, the fit."""
        out = [
            (
                p,
                f"{self.estimate[p]:.6g} (95 % interval {self.interval[p][0]:.6g} .. "
                f"{self.interval[p][1]:.6g}; std error {self.stderr[p]:.3g}; start "
                f"{self.initial[p]:.6g})",
            )
            for p in self.params
        ]
        rms = float(np.sqrt(np.mean(self.residuals**2)))
        out += [
            (
                "residuals",
                f"rms {rms:.3g}, max |r| {float(np.max(np.abs(self.residuals))):.3g} "
                f"({self.errors} errors, s = {math.sqrt(self.s2):.3g})",
            ),
            ("data", f"{self.residuals.size} points at t = {_times(self.data.t)}"),
            ("runs", f"{self.runs} ({self.nfev} trial points; {self.message})"),
        ]
        return out

    def to_json(self) -> dict[str, Any]:
        """A JSON-friendly summary."""
        return {
            "params": list(self.params),
            "estimate": self.estimate,
            "initial": self.initial,
            "stderr": self.stderr,
            "interval_95": {k: list(v) for k, v in self.interval.items()},
            "s2": self.s2,
            "errors": self.errors,
            "covariance": self.covariance.tolist(),
            "residuals": self.residuals.tolist(),
            "success": self.success,
            "message": self.message,
            "nfev": self.nfev,
            "runs": self.runs,
            "seconds": self.seconds,
            "data": self.data.source,
        }


def _times(t: NDArray[np.float64]) -> str:
    return ", ".join(f"{x:g}" for x in np.unique(t))


def _number_at(data: Mapping[str, Any], key: str, src: str) -> float:
    node: Any = data
    for k in key.split("."):
        node = node.get(k) if isinstance(node, Mapping) else None
    if isinstance(node, bool) or not isinstance(node, int | float):
        raise StudyError(
            f"{src}: [{key.rsplit('.', 1)[0]}] {key.rsplit('.', 1)[1]} must be a number to be "
            f"fitted (one contact part, a linear compliance for c), got {node!r}"
        )
    return float(node)


class _Model:
    """Runs of the configuration at parameter values, on Dask, and the predictions."""

    def __init__(
        self, data: dict[str, Any], src: str, keys: list[str], m: Measured, out: Path, client: Any
    ) -> None:
        self.data, self.src, self.keys, self.m, self.out, self.client = (
            data,
            src,
            keys,
            m,
            out,
            client,
        )
        self.runs = 0
        self.last: dict[str, NDArray[Any]] = {}

    def spec(self, theta: NDArray[np.float64]) -> RunSpec:
        from ..config import apply_overrides

        params = {k: float(v) for k, v in zip(self.keys, theta, strict=True)}
        d = apply_overrides(self.data, params)
        return RunSpec("r" + sha256_json({"config": d})[:12], 0, params, d)

    def evaluate(self, thetas: Sequence[NDArray[np.float64]]) -> list[NDArray[np.float64]]:
        from ..post.results import load_result
        from .dataset import run_arrays
        from .execute import run_all
        from .layout import RUNS_DIR

        specs = list({s.id: s for s in map(self.spec, thetas)}.values())
        ex = run_all(specs, self.out, self.client, progress=False, extract=run_arrays)
        self.runs += ex.computed
        preds = {}
        for s in specs:
            rec = ex.records[s.id]
            if rec["status"] != "done":
                raise StudyError(
                    f"{self.src}: the run at {params_text(s.params)} failed: {rec['error']}"
                )
            # handed back by the task; read from the run's files if it ran earlier
            res = ex.arrays.get(s.id) or load_result(self.out / RUNS_DIR / s.id)
            preds[s.id] = self.predict(res)
            self.last = res
        return [preds[self.spec(th).id] for th in thetas]

    def predict(self, res: Mapping[str, NDArray[Any]]) -> NDArray[np.float64]:
        m = self.m
        a = res["contact_points"][:, 0] if m.abscissa == "x" else res["contact_s"]
        order = np.argsort(a, kind="stable")
        a, wear, t = np.asarray(a)[order], np.asarray(res["wear"])[:, order], res["t"]
        out = np.empty_like(m.w)
        for tu in np.unique(m.t):
            sel = m.t == tu
            j = int(np.clip(np.searchsorted(t, tu), 1, t.size - 1))
            f = (tu - t[j - 1]) / (t[j] - t[j - 1])
            row = (1 - f) * wear[j - 1] + f * wear[j]
            out[sel] = np.interp(m.a[sel], a, row)
        return out


def _check_data(m: Measured, data: Mapping[str, Any], src: str) -> None:
    from ..config import parse_config

    cfg = parse_config(data, source=src)
    t = cfg.problem.time.t
    bad = (m.t < t[0] - 1e-12) | (m.t > t[-1] + 1e-12)
    if np.any(bad):
        raise StudyError(
            f"{m.source}: t = {m.t[bad][0]:g} is outside the configuration's time grid "
            f"[{t[0]:g}, {t[-1]:g}]"
        )
    if m.w.size <= 0:
        raise StudyError(f"{m.source}: no data")
    cb = cfg.problem.contact
    a = np.asarray(cb.points[:, 0] if m.abscissa == "x" else cb.s, dtype=np.float64)
    lo, hi = float(a.min()), float(a.max())
    tol = 1e-9 * max(hi - lo, 1.0)
    off = (m.a < lo - tol) | (m.a > hi + tol)
    if np.any(off):  # np.interp would clamp it to the end value
        i = int(np.flatnonzero(off)[0])
        raise StudyError(
            f"{m.source}: data point {i + 1} at {m.abscissa} = {m.a[i]:g} is off the contact "
            f"part: its contact nodes, where the model's wear is known, span {m.abscissa} = "
            f"{lo:g} .. {hi:g}"
        )


def interval95(
    value: float, stderr: float, q: float, low: float, high: float
) -> tuple[float, float]:
    """The 95 % interval of a positive parameter: by the delta method in its logarithm
    (``value * exp(+-q stderr / value)``, so never below 0: a linear interval of mu
    reached -0.68), clipped to the bounds ``[low, high]``."""
    if value > 0 and math.isfinite(stderr):
        f = math.exp(min(q * stderr / value, 700.0))
        a, b = value / f, value * f
    else:  # at the lower bound 0
        a, b = value - q * stderr, value + q * stderr
    return max(a, low), min(b, high)


def fit(
    config: str | os.PathLike[str],
    data: str | os.PathLike[str] | Measured,
    params: Sequence[str] = ("kappa",),
    client: Any = None,
    *,
    out: str | os.PathLike[str] | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    errors: str = "relative",
    scheduler: str | None = None,
    workers: int | None = None,
    figures: bool = True,
    say: Callable[[str], None] | None = None,
) -> FitResult:
    """Calibrate parameters of ``config`` against measured wear by least squares.

    Parameters
    ----------
    config : path
        The configuration file; its values of ``params`` are the starting point.
    data : path or Measured
        The measured wear (:func:`read_measured`).
    params : sequence of str
        Names from :data:`PARAMETERS`: ``kappa``, ``mu``, ``c``, ``g``.
    client : distributed.Client, optional
        A client of the user's own cluster (left open); else ``scheduler`` or an
        embedded ``LocalCluster`` of ``workers``.
    out : path, optional
        Output directory for the runs, ``fit.json``, ``fit.md`` and ``fit.png``;
        without it the runs go to a temporary directory, removed at the end.
    bounds : mapping, optional
        ``{name: (low, high)}``; defaults in :data:`PARAMETERS`.
    errors : {"relative", "absolute"}
        Without a ``sigma`` column: measurement errors proportional to the wear (the
        residuals divided by ``|w|``, at least 1 % of the largest) or all alike.
    figures : bool
        Write ``fit.png`` and ``fit.md`` (with ``out``).
    say : callable, optional
        Where the dashboard's address goes.

    Returns
    -------
    FitResult

    Raises
    ------
    StudyError
        Bad parameters, data, or a failed run.
    """
    from scipy import optimize, stats

    from .execute import study_client
    from .layout import open_study_dir

    t0 = time.perf_counter()
    src = str(config)
    names = tuple(dict.fromkeys(params))
    unknown = [p for p in names if p not in PARAMETERS]
    if unknown or not names:
        raise StudyError(f"--params {unknown or list(params)}: choose from {', '.join(PARAMETERS)}")
    from ..util.text import read_utf8

    try:
        base = tomllib.loads(read_utf8(config))
    except (OSError, ValueError) as exc:
        raise StudyError(f"{src}: cannot read the configuration: {exc}") from None
    from ..config import apply_overrides
    from .design import _absolute_mesh

    base = _absolute_mesh(apply_overrides(base, _RUN_OUTPUT), Path(config).resolve().parent)
    m = data if isinstance(data, Measured) else read_measured(data)
    _check_data(m, base, src)
    keys = [PARAMETERS[p][0] for p in names]
    x0 = np.asarray([_number_at(base, k, src) for k in keys])
    bl = dict(bounds or {})
    lo = np.asarray([bl.get(p, PARAMETERS[p][1])[0] for p in names], dtype=np.float64)
    hi = np.asarray([bl.get(p, PARAMETERS[p][1])[1] for p in names], dtype=np.float64)
    if np.any(x0 < lo) or np.any(x0 > hi):
        raise StudyError(
            f"{src}: the starting values {dict(zip(names, x0, strict=True))} are outside the bounds"
        )
    if errors not in ("relative", "absolute"):
        raise StudyError(f"errors must be 'relative' or 'absolute', got {errors!r}")
    weight = 1.0 / m.scale(errors)
    if m.w.size <= len(names):  # no residual variance: a zero-width interval
        raise StudyError(
            f"{m.source}: {m.w.size} data points for {len(names)} parameters; a fit needs more "
            "points than parameters (for the residual variance and the intervals)"
        )
    tmp = None if out is not None else Path(tempfile.mkdtemp(prefix="vemwear-fit-"))
    target = Path(out) if out is not None else Path(str(tmp)) / "fit"
    outdir = open_study_dir(target, "fit", [config])
    try:
        with study_client(client, scheduler=scheduler, workers=workers, say=say) as c:
            model = _Model(base, src, keys, m, outdir, c)
            cache: dict[bytes, tuple[NDArray[np.float64], NDArray[np.float64]]] = {}

            def steps(th: NDArray[np.float64]) -> NDArray[np.float64]:
                h = _STEP * np.maximum(np.abs(th), 1e-3)
                return np.where(th + h > hi, -h, h)

            def both(th: NDArray[np.float64]) -> tuple[NDArray[Any], NDArray[Any]]:
                k = th.tobytes()
                if k not in cache:
                    h = steps(th)
                    pts = [th] + [th + h[j] * np.eye(th.size)[j] for j in range(th.size)]
                    pred = model.evaluate(pts)
                    r0 = (pred[0] - m.w) * weight
                    J = np.column_stack(
                        [(pred[j + 1] - pred[0]) * weight / h[j] for j in range(th.size)]
                    )
                    cache[k] = (r0, J)
                return cache[k]

            sol = optimize.least_squares(
                lambda th: both(th)[0],
                x0,
                jac=lambda th: both(th)[1],
                bounds=(lo, hi),
                method="trf",
                x_scale="jac",
                xtol=1e-10,
                ftol=1e-10,
                gtol=1e-10,
                max_nfev=100,
            )
            r, J = both(sol.x)
            final = model.evaluate([sol.x])[0]
            last = model.last
        n, p = r.size, len(names)
        dof = max(n - p, 1)
        s2 = float(r @ r) / dof
        cov = s2 * np.linalg.pinv(J.T @ J)
        se = np.sqrt(np.maximum(np.diag(cov), 0.0))
        q = float(stats.t.ppf(0.975, dof))
        res = FitResult(
            params=names,
            estimate={k: float(v) for k, v in zip(names, sol.x, strict=True)},
            initial={k: float(v) for k, v in zip(names, x0, strict=True)},
            stderr={k: float(v) for k, v in zip(names, se, strict=True)},
            interval={
                k: interval95(float(v), float(e), q, float(a), float(b))
                for k, v, e, a, b in zip(names, sol.x, se, lo, hi, strict=True)
            },
            residuals=final - m.w,
            fitted=final,
            errors="sigma" if m.sigma is not None else errors,
            s2=s2,
            covariance=cov,
            jacobian=J,
            success=bool(sol.success),
            message=str(sol.message),
            nfev=int(sol.nfev),
            runs=model.runs,
            seconds=time.perf_counter() - t0,
            data=m,
            profiles={k: last[k] for k in ("t", "wear", "contact_s", "contact_points")},
        )
        if out is not None:
            _write(res, outdir, figures)
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
    return res


def _write(res: FitResult, outdir: Path, figures: bool) -> None:
    from ..runner.outdir import read_marker, write_marker
    from ..util.atomic import write_atomic

    names = ["fit.json"]
    write_atomic(outdir / "fit.json", json.dumps(res.to_json(), indent=2) + "\n")
    if figures:
        from .plots import plot_fit

        plot_fit(res, outdir / "fit.png")
        rows = "\n".join(f"| {a} | {b} |" for a, b in res.rows())
        text = f"# Fit of {', '.join(res.params)}\n\n| | |\n|---|---|\n{rows}\n\n![fit](fit.png)\n"
        write_atomic(outdir / "fit.md", text)
        names += ["fit.png", "fit.md"]
    old = read_marker(outdir) or {}
    write_marker(outdir, "complete", [*old.get("files", []), *names], command="fit")
