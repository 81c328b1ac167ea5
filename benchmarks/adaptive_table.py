"""The measurement shared by the adaptive benchmarks (``adaptive_ex52.py``,
``adaptive_punch.py``): the wear at T along Gamma_C against a reference, cases run
interleaved, and the table of dofs, wall times and errors against one uniform case."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from vemwear.simulate import Result

#: A case: runs once, returns the dofs at T and the result.
Case = Callable[[], tuple[int, Result]]


def wear_at_T(r: Result) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The wear at the last level along Gamma_C, by increasing x."""
    x = r.contact_points[:, 0]
    order = x.argsort()
    return x[order], np.asarray(r.wear[-1])[order]


def wear_error(reference: Result) -> Callable[[Result], float]:
    """The relative L2 error along Gamma_C of a run's wear at T, interpolated onto the
    contact nodes of ``reference``."""
    xr, wr = wear_at_T(reference)

    def error(r: Result) -> float:
        x, w = wear_at_T(r)
        d = np.interp(xr, x, w) - wr
        return float(np.sqrt(np.trapezoid(d**2, xr) / np.trapezoid(wr**2, xr)))

    return error


def measure(
    cases: dict[str, Case], repeat: int, error: Callable[[Result], float]
) -> tuple[dict[str, list[float]], dict[str, tuple[int, float]]]:
    """Every case ``repeat`` times, interleaved: the wall times, and the dofs and error."""
    times: dict[str, list[float]] = {k: [] for k in cases}
    found: dict[str, tuple[int, float]] = {}
    for _ in range(repeat):
        for name, run in cases.items():
            t0 = time.perf_counter()
            dofs, r = run()
            times[name].append(time.perf_counter() - t0)
            found[name] = (dofs, error(r))
    return times, found


def table(
    times: dict[str, list[float]],
    found: dict[str, tuple[int, float]],
    base: str,
    ratio: Callable[[float], str] = lambda q: f"{q:.2f}",
) -> str:
    """Markdown: dofs, min / median / max wall time and error per case, and the dofs and
    median time over those of ``base`` (written by ``ratio``)."""
    dofs0, med0 = found[base][0], statistics.median(times[base])
    lines = [
        "| mesh | dofs at T | wall time [s] min / median / max | wear error | "
        f"dofs / {base} | time / {base} |",
        "|---|---|---|---|---|---|",
    ]
    for name, ts in times.items():
        dofs, err = found[name]
        med = statistics.median(ts)
        lines.append(
            f"| {name} | {dofs} | {min(ts):.2f} / {med:.2f} / {max(ts):.2f} | {err:.2e} | "
            f"{ratio(dofs / dofs0)} | {ratio(med / med0)} |"
        )
    return "\n".join(lines)
