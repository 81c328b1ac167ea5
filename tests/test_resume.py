"""Interrupted runs keep their finished levels and resume to the same result, bitwise."""

from __future__ import annotations

import numpy as np
import pytest

from vemwear.paper import ex52
from vemwear.simulate import SolverOptions, simulate

FIELDS = ("wear", "u_nu", "p_rigid", "p_soft", "u", "u_levels", "iterations", "residuals")


class Stop(Exception):
    pass


def stop_at(level):
    def cb(n, _sol):
        if n == level:
            raise Stop

    return cb


@pytest.mark.parametrize("method", ["newton", "uzawa"])
@pytest.mark.parametrize("store", ["all", [0.5, 1.0]])
@pytest.mark.parametrize("level", [1, 9, 15])
def test_resume_equals_uninterrupted_run(method, store, level):
    pr = ex52.problem(0.2, 2.0, divisions=(8, 4), steps=16)
    opts = SolverOptions(method)
    with pytest.raises(Stop) as info:
        simulate(pr, opts, store=store, recover_block=4, callback=stop_at(level))
    part = info.value.partial_result
    assert part.is_partial and 0 <= part.completed <= level
    assert np.all(part.u_levels < part.completed)
    for k in ("wear", "u_nu", "p_rigid", "p_soft", "iterations", "residuals"):
        assert not np.any(getattr(part, k)[part.completed :]), k  # unfinished levels are zero
    resumed = simulate(pr, opts, store=store, recover_block=4, resume=part)
    ref = simulate(pr, opts, store=store, recover_block=4)
    assert not resumed.is_partial
    for k in FIELDS:
        assert np.array_equal(getattr(resumed, k), getattr(ref, k)), k


def test_same_input_twice_gives_identical_arrays():
    pr = ex52.problem(0.6, 10.0, divisions=(16, 8), steps=16)
    a, b = simulate(pr), simulate(pr)
    for k in FIELDS:
        assert np.array_equal(getattr(a, k), getattr(b, k)), k


def test_resume_rejects_another_problem():
    pr = ex52.problem(0.2, 2.0, divisions=(8, 4), steps=16)
    with pytest.raises(Stop) as info:
        simulate(pr, callback=stop_at(5))
    other = ex52.problem(0.2, 2.0, divisions=(8, 4), steps=8)
    with pytest.raises(ValueError, match="time grid"):
        simulate(other, resume=info.value.partial_result)
