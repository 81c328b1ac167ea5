"""Streamed levels (result.h5) and the loop state: a run stopped and started again from
its state gives the arrays of an uninterrupted run, bitwise, for every solver and
every choice of kept levels."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from vemwear.paper import ex52
from vemwear.post.results import result_arrays
from vemwear.post.stream import H5Sink, read_stream, result_from_stream
from vemwear.simulate import SolverOptions, simulate
from vemwear.simulate.levels import run_levels
from vemwear.simulate.stream import StoragePlan, state_arrays, state_from_arrays


class Stop(Exception):
    pass


@pytest.fixture(scope="module")
def problem():
    return ex52.problem(0.2, 2.0, divisions=(8, 4), steps=40)


def test_storage_plan_keeps_final_and_displacement_levels() -> None:
    plan = StoragePlan.make(41, [5, 7], every=10)
    assert plan.levels.tolist() == [0, 5, 7, 10, 20, 30, 40]
    row, slot = plan.slots()
    assert row[7] == 2 and row[8] == -1 and slot[7] == 1 and slot[40] == -1
    with pytest.raises(ValueError, match="every"):
        StoragePlan.make(41, [], every=0)


@pytest.mark.parametrize("method", ["newton", "uzawa", "newton-full"])
@pytest.mark.parametrize(
    ("every", "u_levels"), [(1, [10, 20, 40]), (3, list(range(0, 41, 2))), (1, list(range(41)))]
)
def test_stop_and_resume_from_state_is_bitwise(problem, tmp_path: Path, method, every, u_levels):
    opts = SolverOptions(method)
    L = len(problem.time.t)
    plan = StoragePlan.make(L, u_levels, every)
    ref = simulate(problem, opts, store=problem.time.t[plan.u_levels], every=every, recover_block=4)
    saved: dict = {}

    def stop(n, _sol):
        if n == 17:
            raise Stop

    path = tmp_path / "result.h5"
    sink = H5Sink(path, problem, plan, on_checkpoint=lambda st: saved.update(state_arrays(st)))
    with pytest.raises(Stop) as info:
        run_levels(problem, opts, sink, plan, recover_block=4, callback=stop)
    sink.checkpoint(info.value.loop_state)
    sink.close()
    state = state_from_arrays(saved)
    assert state.completed == 17
    sink = H5Sink(path, problem, plan, resume=True)
    run_levels(problem, opts, sink, plan, start=state, recover_block=4)
    sink.close(completed=L)
    got, want = result_arrays(result_from_stream(problem, path)), result_arrays(ref)
    assert got.keys() == want.keys()
    for k in want:
        assert np.array_equal(got[k], want[k]), k


def test_stream_is_preallocated_and_reads_back(problem, tmp_path: Path) -> None:
    """Every dataset has its final size from the start (nothing grows while the run
    goes on); the names are those of result.npz."""
    L = len(problem.time.t)
    plan = StoragePlan.make(L, [L - 1], every=5)
    path = tmp_path / "result.h5"
    sink = H5Sink(path, problem, plan)
    with h5py.File(path, "r") as f:  # another handle, before any level
        assert f["wear"].shape == (len(plan.levels), len(problem.contact.nodes))
        assert f["u"].shape == (1, problem.mesh.n_points, 2)
        assert f["wear"].id.get_storage_size() == f["wear"].size * 8  # allocated
    run_levels(problem, SolverOptions(), sink, plan)
    sink.close(completed=L)
    data = read_stream(path)
    assert str(data["residual_names"][0]) == "equilibrium"
    assert data["t"].tolist() == problem.time.t[plan.levels].tolist()
    assert int(data["completed"]) == L
    ref = simulate(problem, store="final", every=5)
    assert np.array_equal(data["wear"], ref.wear) and np.array_equal(data["u"], ref.u)
    assert np.array_equal(data["penetration"], ref.u_nu - ref.wear)
