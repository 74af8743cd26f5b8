"""Stopping criteria."""

from __future__ import annotations

import math

import pytest

from subtask_opt.base.errors import ParameterError
from subtask_opt.base.stop import (
    MaxGenerations,
    MaxRuntime,
    NoImprovement,
    Progress,
    TargetCost,
    as_criteria,
    target_threshold,
)
from subtask_opt.ga.loop import run_in_chunks


def _p(gen=0, best=10.0, stall=0, t=0.0):
    return Progress(generation=gen, best_cost=best, generations_without_improvement=stall,
                    runtime_s=t)


def test_each_criterion_fires_at_its_threshold():
    assert not MaxGenerations(5)(_p(gen=4)) and MaxGenerations(5)(_p(gen=5))
    assert not MaxRuntime(1.0)(_p(t=0.5)) and MaxRuntime(1.0)(_p(t=1.0))
    assert not NoImprovement(3)(_p(stall=2)) and NoImprovement(3)(_p(stall=3))
    assert not TargetCost(5.0)(_p(best=5.1)) and TargetCost(5.0)(_p(best=5.0))


def test_generations_left_bounds_the_next_chunk():
    assert MaxGenerations(10).generations_left(_p(gen=4)) == 6
    assert NoImprovement(10).generations_left(_p(stall=3)) == 7
    assert MaxRuntime(1.0).generations_left(_p()) is None
    assert TargetCost(1.0).generations_left(_p()) is None


def test_as_criteria_normalises_and_validates():
    default = [MaxGenerations(3)]
    assert as_criteria(None, default) == default
    assert as_criteria(MaxRuntime(2.0), default) == [MaxRuntime(2.0)]
    with pytest.raises(ParameterError, match="at least one"):
        as_criteria([], default)
    with pytest.raises(ParameterError, match="not a stopping criterion"):
        as_criteria([42], default)
    with pytest.raises(ParameterError, match="TargetCost alone"):
        as_criteria([TargetCost(1.0)], default)
    assert target_threshold([MaxGenerations(1)]) == -math.inf
    assert target_threshold([TargetCost(2.0, tolerance=0.5)]) == pytest.approx(3.0)


@pytest.mark.parametrize("make", [
    lambda: MaxGenerations(0), lambda: MaxGenerations(2.5), lambda: MaxRuntime(0.0),
    lambda: MaxRuntime(float("inf")), lambda: NoImprovement(-1), lambda: TargetCost(float("nan")),
    lambda: TargetCost(1.0, tolerance=-1.0),
])
def test_bad_criteria_raise(make):
    with pytest.raises(ParameterError):
        make()


def _fake_kernel(stall_at: int | None = None):
    """A kernel that counts iterations and may stop itself early, like the GA's."""
    state = {"gen": 0, "chunks": []}

    def run_chunk(n: int) -> int:
        ran = n if stall_at is None else max(0, min(n, stall_at - state["gen"]))
        state["gen"] += ran
        state["chunks"].append(n)
        return ran

    def progress() -> Progress:
        return _p(gen=state["gen"])

    return state, run_chunk, progress


def test_run_in_chunks_stops_exactly_at_max_generations():
    state, run_chunk, progress = _fake_kernel()
    seen = []
    run_in_chunks(run_chunk, progress, [MaxGenerations(300)], on_chunk=seen.append)
    assert state["gen"] == 300
    # chunks start at one generation and grow 64-fold at most (the fake kernel is far under
    # the 0.05 s a chunk may take), never past the limit: 1, 64, then the last 235
    assert state["chunks"] == [1, 64, 235]
    assert [p.generation for p in seen] == [1, 65, 300]


def test_run_in_chunks_grows_towards_a_chunk_of_chunk_s_at_the_measured_rate(monkeypatch):
    from subtask_opt.ga import loop

    clock = [0.0]
    monkeypatch.setattr(loop.time, "perf_counter", lambda: clock[0])
    state, fake, progress = _fake_kernel()

    def run_chunk(n: int) -> int:  # a generation takes 1/64 s (exact in binary)
        clock[0] += n / 64
        return fake(n)

    run_in_chunks(run_chunk, progress, [MaxGenerations(40)])
    # 1 generation in 0.016 s: 3x (towards 0.05 s); 3 in 0.047 s: at least 2x; 6 in 0.094 s
    # are over it: no more growth
    assert state["chunks"] == [1, 3, 6, 6, 6, 6, 6, 6]


def test_run_in_chunks_ends_when_the_kernel_stops_itself():
    state, run_chunk, progress = _fake_kernel(stall_at=70)
    run_in_chunks(run_chunk, progress, [MaxRuntime(60.0)])
    assert state["gen"] == 70


def test_time_limit_raises_once_it_has_run_out_and_names_the_step():
    import time

    from subtask_opt.base.errors import TimeLimitReached
    from subtask_opt.base.stop import check_time_limit, time_limit

    check_time_limit("outside any limit")  # no limit: nothing happens
    with time_limit(None):
        check_time_limit("without a limit")
    with time_limit(60.0):
        check_time_limit("well within it")
        with time_limit(1e-6):  # the inner limit holds inside, then the outer one again
            time.sleep(0.01)
            with pytest.raises(TimeLimitReached, match=r"1e-06 s ran out in step 3"):
                check_time_limit("in step 3")
        check_time_limit("back within the outer limit")
    started = time.monotonic() - 10.0  # counted from an earlier start
    with time_limit(5.0, started=started), pytest.raises(TimeLimitReached):
        check_time_limit("late")


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf"), "5"])
def test_time_limit_refuses_a_bad_number_of_seconds(bad):
    from subtask_opt.base.stop import time_limit

    with pytest.raises(ParameterError, match="seconds"), time_limit(bad):
        pass
