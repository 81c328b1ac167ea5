"""Cycle jumps against the whole history (docs/method.md, section 6d).

The fretting example (the rounded punch of ``fretting.toml``, v* = (cos 2 pi t, 0), 16
steps per cycle) over 100 cycles: the whole history computed on one time grid of 1600
steps is the reference; cycle jumps compute one cycle in every J and extrapolate the
wear in between, with the jump-size control off (``max_increment = 1``) or on.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from vemwear.config import load_config
from vemwear.examples import config_path
from vemwear.simulate import TimeGrid, simulate
from vemwear.simulate.cycles import CycleJump, simulate_cycles

CYCLES = 100


@pytest.fixture(scope="module")
def fretting() -> tuple[Any, Any, np.ndarray]:
    """The one-cycle problem, its solver and the wear after 100 cycles of the whole
    history."""
    cfg = load_config(config_path("fretting"))
    one = cfg.problem
    steps = len(one.time.t) - 1
    whole = dataclasses.replace(one, time=TimeGrid.uniform(float(CYCLES), CYCLES * steps))
    ref = simulate(whole, cfg.solver, store="final").wear[-1]
    assert ref.max() > 0
    return one, cfg.solver, ref


def relative(w: np.ndarray, ref: np.ndarray) -> float:
    return float(np.abs(w - ref).max() / ref.max())


def test_jump_1_is_the_whole_history(fretting: tuple[Any, Any, np.ndarray]) -> None:
    one, solver, ref = fretting
    r = simulate_cycles(one, CycleJump(CYCLES, 1), solver)
    assert len(r.computed) == CYCLES and r.cycle[-1] == CYCLES
    assert relative(r.wear[-1], ref) < 1e-14


def test_jumps_of_10_without_control_within_one_percent(
    fretting: tuple[Any, Any, np.ndarray],
) -> None:
    one, solver, ref = fretting
    r = simulate_cycles(one, CycleJump(CYCLES, 10, max_increment=1.0), solver)
    assert r.jumps == [10] * 10 and len(r.computed) == 10
    assert relative(r.wear[-1], ref) < 1e-2


def test_default_control_within_one_percent(fretting: tuple[Any, Any, np.ndarray]) -> None:
    one, solver, ref = fretting
    cj = CycleJump(CYCLES, 10)
    assert cj.max_increment == 0.05  # the shipped default
    r = simulate_cycles(one, cj, solver)
    assert sum(r.jumps) == CYCLES and max(r.jumps) <= 10
    assert relative(r.wear[-1], ref) < 1e-2


def test_small_max_increment_shortens_the_jumps(fretting: tuple[Any, Any, np.ndarray]) -> None:
    """The extrapolated wear of a jump stays below max_increment * g: a small bound
    shortens the jumps, so more cycles are computed."""
    one, solver, ref = fretting
    free = simulate_cycles(one, CycleJump(CYCLES, 10, max_increment=1.0), solver)
    tight = simulate_cycles(one, CycleJump(CYCLES, 10, max_increment=0.01), solver)
    assert sum(tight.jumps) == CYCLES and max(tight.jumps) < 10
    assert len(tight.computed) > len(free.computed)
    assert relative(tight.wear[-1], ref) < 1e-2
