"""The core's threads (cpp/threads.hpp): one parallel_for on a pool whose caller never waits
for a helper that has not started; an explicit, bounded count; safe use from many threads."""
import multiprocessing as mp
import threading

import numpy as np
import pytest

import thinburn
from thinburn import _core
from thinburn.scenes import rect_sheet


def test_thread_count_round_trips():
    old = thinburn.get_threads()
    try:
        assert thinburn.set_threads(1) == 1
        assert thinburn.get_threads() == 1
        assert thinburn.set_threads(2) == 2
        assert thinburn.get_threads() == 2
        assert thinburn.set_threads(np.int64(3)) == 3  # numpy integers are integers
        assert thinburn.set_threads(None) == thinburn.hardware_threads()
    finally:
        thinburn.set_threads(old)


def test_the_ceiling_is_four_per_core_and_at_least_eight():
    assert thinburn.max_threads() == max(8, 4 * thinburn.hardware_threads())
    assert thinburn.set_threads(thinburn.max_threads()) == thinburn.max_threads()
    thinburn.set_threads(1)


# From ../shared/repro/r2_threads_huge_kills_process.py: 10**9 threads was accepted and the
# first step killed the interpreter; 2**31 gave a pybind signature dump.
@pytest.mark.parametrize("bad, exc", [(0, ValueError), (-3, ValueError), (2.5, TypeError), (True, TypeError),
                                      ("2", TypeError), (10**9, ValueError), (2**31, ValueError),
                                      (2**70, ValueError)])
def test_bad_thread_count_names_the_argument(bad, exc):
    with pytest.raises(exc, match="threads"):
        thinburn.set_threads(bad)


@pytest.mark.parametrize("bad", [10**9, 2**31, 0])
def test_a_simulation_refuses_a_bad_thread_count(bad):
    v, f = rect_sheet(0.1, 0.1, nx=5, ny=5)
    with pytest.raises(ValueError, match="threads"):
        thinburn.Simulation(v, f, cells=8, threads=bad)
    sim = thinburn.Simulation(v, f, cells=8, threads=1)
    with pytest.raises(ValueError, match="threads"):
        sim.threads = bad
    assert sim.threads == 1


@pytest.mark.parametrize("n", [0, 1, 2, 7, 1000, 40_000, 123_457])
@pytest.mark.parametrize("threads", [1, 2, 3, 8])
@pytest.mark.parametrize("cost", [1, 64])
def test_parallel_for_runs_every_item_once(n, threads, cost):
    out = np.asarray(_core.parallel_sum_check(n, cost, threads))
    np.testing.assert_array_equal(out, np.arange(1, n + 1))


def test_an_exception_in_a_chunk_reaches_the_caller_and_the_pool_survives():
    with pytest.raises(RuntimeError, match="item 77777 failed"):
        _core.parallel_sum_check(100_000, 1, 2, 77_777)
    np.testing.assert_array_equal(_core.parallel_sum_check(100_000, 1, 2), np.arange(1, 100_001))


def test_loops_from_several_threads_at_once_are_all_correct():
    # One loop holds the pool; the others run on their own caller: all must finish, right.
    results, errors = {}, []

    def go(k):
        try:
            for _ in range(20):
                results[k] = np.asarray(_core.parallel_sum_check(50_000 + k, 1, 2))
        except Exception as exc:  # reported below
            errors.append(exc)
    ts = [threading.Thread(target=go, args=(k,)) for k in range(4)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert not errors
    for k, out in results.items():
        np.testing.assert_array_equal(out, np.arange(1, 50_001 + k))


def _child_loop(queue):
    queue.put(int(np.sum(_core.parallel_sum_check(60_000, 1, 2))))


# Python 3.12+ warns that fork() in a threaded process may deadlock: that hazard is what this
# test checks the pool against.
@pytest.mark.filterwarnings("ignore:This process .* is multi-threaded:DeprecationWarning")
def test_a_forked_child_runs_parallel_loops():
    # After fork() only the forking thread exists: the child's pool starts anew.
    _core.parallel_sum_check(60_000, 1, 2)  # the parent's helpers exist
    ctx = mp.get_context("fork")
    q = ctx.Queue()
    p = ctx.Process(target=_child_loop, args=(q,))
    p.start()
    total = q.get(timeout=60)
    p.join(timeout=60)
    assert p.exitcode == 0 and total == 60_000 * 60_001 // 2


def _burning_sheet(threads=1):
    v, f = rect_sheet(0.21, 0.297, nx=15, ny=21)
    sim = thinburn.Simulation(v, f, cells=32, floor=0.0, threads=threads, seed=3)
    sim.ignite((0.0, 0.0, 0.0), time=0.0, radius=0.05)
    return sim


def _state(sim):
    return [sim.time, sim.cell_states(), sim.ignition_times(), sim.vertex_positions(),
            sim.lattice_positions(), sim.heat(), *sim.particles()]


def assert_same_state(a, b):
    for x, y in zip(_state(a), _state(b)):
        assert np.asarray(x).tobytes() == np.asarray(y).tobytes()


# From ../shared/repro/r1_same_sim_two_threads_segfault.py: two threads stepping one
# Simulation crashed (SIGSEGV) or gave non-finite positions.
def test_one_simulation_stepped_from_two_threads_is_serialised():
    shared, alone = _burning_sheet(), _burning_sheet()
    errors = []

    def go():
        try:
            for _ in range(30):
                shared.step(1 / 24)
                shared.vertex_positions()  # reads interleave with the other thread's steps
        except Exception as exc:  # reported below
            errors.append(exc)
    ts = [threading.Thread(target=go) for _ in range(2)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert not errors
    for _ in range(60):
        alone.step(1 / 24)
    # Every step has the same dt, so 2 x 30 serialised steps are the 60 steps of one thread.
    assert_same_state(shared, alone)


def test_simulations_on_several_threads_keep_their_own_counts_and_results():
    sims = [_burning_sheet(threads=t) for t in (1, 2, 2)]
    ref = _burning_sheet(threads=1)
    old = thinburn.get_threads()

    def go(sim):
        for _ in range(24):
            sim.step(1 / 24)
    ts = [threading.Thread(target=go, args=(s,)) for s in sims]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    go(ref)
    assert thinburn.get_threads() == old  # a Simulation's count never leaks into the default
    for sim in sims:
        assert_same_state(sim, ref)
