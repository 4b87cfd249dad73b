"""One BLAS thread while linkagekit computes (src/linkagekit/threads.py): inside its calls every loaded BLAS library
runs one thread, and after them each has the threads it had before (the caller's own NumPy work keeps its own)."""

from __future__ import annotations

import numpy as np
from threadpoolctl import threadpool_info, threadpool_limits

import linkagekit as lk
from linkagekit import api, threads


def blas_threads() -> dict[str, int]:
    return {lib["filepath"]: lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}


def test_analyze_runs_on_one_blas_thread_and_gives_the_threads_back(monkeypatch):
    seen = []
    solve = api.solve_request

    def spy(req):
        seen.append(blas_threads())
        return solve(req)

    monkeypatch.setattr(api, "solve_request", spy)
    mech = lk.load("examples/seed000_fourbar.yaml")
    with threadpool_limits(2, user_api="blas"):  # what a caller has (on a one-core machine OpenBLAS starts with one)
        before = blas_threads()
        assert before and set(before.values()) == {2}
        res = lk.analyze(mech, {"crank": [10.0, 20.0]})
        assert blas_threads() == before
    assert res.assembled.all()
    assert len(seen) == 1 and set(seen[0]) == set(before) and set(seen[0].values()) == {1}


def test_scipy_s_own_blas_is_limited_too():
    import scipy.linalg  # noqa: F401 -- its OpenBLAS loaded before the limit looks

    with threadpool_limits(2, user_api="blas"):
        before = blas_threads()
        assert len(before) >= 2  # NumPy's and SciPy's own (wheels bring one each)
        with threads.blas_limited(with_scipy=True):
            inside = blas_threads()
        assert set(inside) == set(before) and set(inside.values()) == {1}
        assert blas_threads() == before


def test_the_limit_does_not_change_an_answer():
    mech = lk.load("examples/seed003_ex21.yaml")
    q = {mech.drivers[0].name: np.linspace(0.0, 360.0, 73)}
    a = lk.analyze(mech, q, method="numerical")
    b = api.analyze.__wrapped__(mech, q, method="numerical")  # the same call without the limit
    assert np.array_equal(a.assembled, b.assembled)
    for j in mech.joint_names:
        np.testing.assert_allclose(a.point(j), b.point(j), rtol=0, atol=1e-12 * 10)


def test_overlapping_calls_in_two_threads_keep_the_limit_until_the_last_ends_then_give_the_threads_back():
    """Review 10c: each call saved and restored the counts on its own, but they belong to the process. A enters,
    B enters, A leaves: B ran on OpenBLAS's own threads again, and once both had left the process stayed on one
    thread. Now the first to enter limits and the last to leave restores."""
    import threading

    seen: dict[str, dict[str, int]] = {}
    a_in, b_in, a_out = threading.Event(), threading.Event(), threading.Event()

    def a() -> None:
        with threads.blas_limited():
            a_in.set()
            b_in.wait(10)
        a_out.set()

    def b() -> None:
        a_in.wait(10)
        with threads.blas_limited():
            b_in.set()
            a_out.wait(10)
            seen["b after a left"] = blas_threads()

    # OpenBLAS's own count (one per core: 2 on the suite's machine); not threadpool_limits(2) set here first: after
    # that OpenBLAS (0.3.31) reports the main thread's count to a limit set in another thread
    before = blas_threads()
    ta, tb = threading.Thread(target=a), threading.Thread(target=b)
    ta.start(), tb.start()
    ta.join(20), tb.join(20)
    assert a_out.is_set() and set(seen["b after a left"].values()) == {1}
    assert blas_threads() == before
