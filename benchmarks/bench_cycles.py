"""Cycle jumps: accuracy and speed-up against the whole history computed at once.

The fretting example (the rounded punch of ``fretting.toml``: v* = (cos 2 pi t, 0),
16 steps per cycle) over ``--cycles`` cycles: the whole history on one time grid of
``cycles * 16`` steps (the floor of accuracy), and cycle jumps with J = 1 (every cycle
computed), and the ``--jumps``, each twice: rows ``jump J`` with the jump-size control
off (``max_increment = 1``: every jump is J cycles, the last one cut to end at the
requested number), rows ``jump J, control`` with the shipped default control
(``max_increment`` = 0.05 of g, the default of ``[time] cycle_jump``: a jump is
shortened while its extrapolated wear exceeds that at some node). Reported: the largest
wear after the last cycle, its relative difference to the whole history (max over the
nodes, relative to the largest wear), the computed cycles and the wall time (min /
median / max of ``--repeat`` interleaved repeats; the problem's factorization is
shared, as in a run), and the speed-up against the whole history and against jump 1.
The column ``linear`` extrapolates the increment of the computed cycle without the
slope term (s = 0), to show what the second-order rule buys.

Usage::

    python benchmarks/bench_cycles.py --cycles 100 --jumps 5 10 20 --repeat 3
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

from vemwear.config import load_config
from vemwear.examples import config_path
from vemwear.simulate import TimeGrid, simulate
from vemwear.simulate.cycles import CycleJump, simulate_cycles


def linear_jumps(problem, solver, cycles: int, jump: int) -> np.ndarray:
    """Cycle jumps with the plain linear extrapolation ``w_{c+J} = w_c + J f_c``."""
    w = np.zeros(len(problem.contact.nodes))
    done = 0
    while done < cycles:
        r = simulate(problem, solver, store="final", initial_wear=w)
        f = r.wear[-1] - w
        J = min(jump, cycles - done)
        w = w + J * f
        done += J
    return w


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--cycles", type=int, default=100)
    ap.add_argument("--jumps", type=int, nargs="+", default=[5, 10, 20])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores; python {sys.version.split()[0]}")
    cfg = load_config(config_path("fretting"))
    one = cfg.problem
    steps = len(one.time.t) - 1
    whole = dataclass_replace_time(one, TimeGrid.uniform(float(args.cycles), args.cycles * steps))
    ref = simulate(whole, cfg.solver, store="final").wear[-1]
    simulate(one, cfg.solver, store="final")  # the factorization, shared by the runs below
    scale = float(ref.max())
    default = CycleJump(args.cycles).max_increment  # the shipped control
    # (J, max_increment): control off for jump 1 and the jumps, then the default control
    cases = [(1, 1.0), *((J, 1.0) for J in args.jumps), *((J, default) for J in args.jumps)]
    times: dict[object, list[float]] = {c: [] for c in [*cases, "whole"]}
    err: dict[tuple[int, float], float] = {}
    comp: dict[tuple[int, float], int] = {}
    lin: dict[int, float] = {}
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        simulate(whole, cfg.solver, store="final")
        times["whole"].append(time.perf_counter() - t0)
        for J, mi in cases:
            t0 = time.perf_counter()
            r = simulate_cycles(one, CycleJump(args.cycles, J, max_increment=mi), cfg.solver)
            times[J, mi].append(time.perf_counter() - t0)
            err[J, mi] = float(np.abs(r.wear[-1] - ref).max() / scale)
            comp[J, mi] = len(r.computed)
    for J in args.jumps:
        lin[J] = float(np.abs(linear_jumps(one, cfg.solver, args.cycles, J) - ref).max() / scale)

    def st(v: list[float]) -> str:
        return f"{min(v):7.3f} {statistics.median(v):7.3f} {max(v):7.3f}"

    print(
        f"fretting punch, {args.cycles} cycles of {steps} steps; max wear {scale:.6g}; "
        f"'control': max_increment = {default:g} g (the default), else off"
    )
    print(
        f"{'run':>17} | {'computed':>8} | {'rel. diff':>9} | {'linear':>9} | "
        f"{'wall s (min med max)':>23} | {'speed-up':>8} | {'vs jump 1':>9}"
    )
    base = statistics.median(times["whole"])
    one_cycle = statistics.median(times[1, 1.0])
    print(
        f"{'whole history':>17} | {args.cycles:8d} | {0.0:9.2e} | {'':>9} | "
        f"{st(times['whole']):>23} | {1.0:8.1f} | {one_cycle / base:9.1f}"
    )
    for J, mi in cases:
        label = f"jump {J}" + (", control" if mi != 1.0 else "")
        li = f"{lin[J]:9.2e}" if J in lin and mi == 1.0 else f"{'':>9}"
        med = statistics.median(times[J, mi])
        print(
            f"{label:>17} | {comp[J, mi]:8d} | {err[J, mi]:9.2e} | {li} | "
            f"{st(times[J, mi]):>23} | {base / med:8.1f} | {one_cycle / med:9.1f}"
        )


def dataclass_replace_time(problem, grid):
    import dataclasses

    return dataclasses.replace(problem, time=grid)


if __name__ == "__main__":
    main()
