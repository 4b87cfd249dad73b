"""The atlas of normalised four-bar curves (synthesis/descriptors.py, synthesis/atlas.py).

Descriptors are checked against their invariances and against an independent numerical
integral; the atlas only in its tiny test size (the root conftest points the cache at a
temporary directory; the fixture below sets ``LINKAGEKIT_ATLAS_SIZE``).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

import linkagekit as lk
from linkagekit.cli import main
from linkagekit.synthesis import atlas as at
from linkagekit.synthesis import descriptors as de
from linkagekit.synthesis.run import make_problem, synthesize
from linkagekit.synthesis.space import builtin_space


@pytest.fixture(autouse=True)
def _tiny_atlas(monkeypatch):
    """A 2048-entry atlas (one chunk) in the session's temporary cache (the root conftest turns it off elsewhere)."""
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "2048")


def _curve(n: int = 40, seed: int = 1) -> np.ndarray:
    """A closed polygon with uneven vertices, no symmetry."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    return np.exp(1j * t) * (1 + 0.3 * np.cos(3 * t)) + 0.4 * np.exp(-1j * t) + 0.2 * np.exp(2j * t)


def _dense_coefficients(z: np.ndarray, closed: bool, H: int, m: int = 1 << 16) -> np.ndarray:
    """The Fourier coefficients of a polygon by resampling it at ``m`` equal arc-length steps and an FFT."""
    if not closed:
        z = np.concatenate([z, z[-2:0:-1]])
    zz = np.append(z, z[0])
    s = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(zz)))])
    u = np.arange(m) * s[-1] / m
    w = np.interp(u, s, zz.real) + 1j * np.interp(u, s, zz.imag)
    F = np.fft.fft(w) / m
    return np.concatenate([F[1 : H + 1], F[-1 : -H - 1 : -1]])


@pytest.mark.parametrize("closed", [True, False])
def test_coefficients_are_the_polygons_fourier_series(closed):
    z = _curve()
    _, Z = de.coefficients(z, closed, 6)
    # sampled trapezoidally on 2^16 points: the error of that sum is O(h^2) at the corners
    assert np.max(np.abs(Z - _dense_coefficients(z, closed, 6))) < 1e-6


def test_descriptor_ignores_position_rotation_scale_start_and_direction():
    z = _curve()
    d = de.describe(z)
    s, b = 0.3 - 1.2j, 5 + 2j
    split = np.insert(z, 5, 0.3 * z[5] + 0.7 * z[4])  # started within a segment, another vertex on it
    for other in (b + s * np.roll(z, 11), b + s * z[::-1], np.roll(split, 3), 7 * np.conj(np.conj(z))):
        assert np.max(np.abs(de.describe(other).vector - d.vector)) < 1e-10
    mirrored = de.describe(np.conj(z)).vector  # a mirror image is another shape (the atlas holds mirrored designs)
    assert np.max(np.abs(mirrored - d.vector)) > 1e-2
    e = de.describe(b + s * np.roll(z, 11))  # the removed similarity puts one curve onto the other
    assert np.max(np.abs(e.center + e.scale * (z - d.center) / d.scale - (b + s * z))) < 1e-12
    assert np.max(np.abs(e.place(((z - d.center) / d.scale)[None])[0] - (b + s * z))) < 1e-12


def test_open_curves_and_the_other_descriptor():
    z = _curve()[:25]
    d = de.describe(z, closed=False)
    e = de.describe(2 - 1j + (0.4 + 0.9j) * z[::-1], closed=False)  # the same arc from its other end
    assert np.max(np.abs(d.vector - e.vector)) < 1e-10
    # the flipped descriptor is that of (psi, phi) + (pi, pi): Z_k times (-1)^(k+1), i.e. the curve
    # restarted half a period later and turned by pi
    W, _ = de.normalise(*de.coefficients(_curve(), True, 6))
    k = np.concatenate([np.arange(1, 7), -np.arange(1, 7)])
    other = de.vector(W * np.exp(1j * np.pi * (1 + k)))
    assert np.max(np.abs(de.flipped(de.vector(W)) - other)) < 1e-12
    assert de.size() == len(d.vector) == 22


def test_a_design_of_the_atlas_is_its_own_nearest_neighbour():
    atlas = at.load()
    assert len(atlas) == 2048 and atlas.closed == 1024 and atlas.file.parent == at.directory()
    row = atlas.entries(np.array([100]))[0]
    J = row[at.JOINTS : at.SWEEP].reshape(5, 2) @ np.array([1, 1j])
    s, b = 0.7 + 2j, 3 - 1j
    Jq = b + s * J
    X = np.stack([Jq.real, Jq.imag], -1).reshape(1, 10)
    P, mu = at.curves(X, np.array([2 * np.pi]), True)
    assert abs(mu[0] - row[at.MU]) < 1e-4  # the stored transmission angle, recomputed
    m = at.nearest(atlas, np.roll(P[0], 17), True, 3)
    assert m.rows[0] == 100 and m.distance[0] < 1e-3 < m.distance[1]
    # float32 storage: the placed joints agree to its rounding, relative to the design's size
    assert np.max(np.abs(m.joints[0] - Jq)) < 1e-5 * abs(s) * np.max(np.abs(J))
    # an open entry's arc, from either end
    lo, _ = atlas.block(False)
    row = atlas.entries(np.array([lo + 7]))[0]
    Jo = row[at.JOINTS : at.SWEEP].reshape(5, 2) @ np.array([1, 1j])
    P, _ = at.curves(np.stack([Jo.real, Jo.imag], -1).reshape(1, 10), np.array([row[at.SWEEP]]), False)
    assert at.nearest(atlas, P[0][::-1], False, 1).rows[0] == lo + 7


@pytest.mark.long
def test_the_atlas_answer_seeds_path_synthesis(monkeypatch):
    atlas = at.load()
    rng = np.random.default_rng(3)
    s, b = 1.5 * np.exp(0.4j), 2 + 1j
    for r in rng.permutation(atlas.closed):  # the first entry that fits the bounds of its own targets
        row = atlas.entries(np.array([r]))[0]
        J = b + s * (row[at.JOINTS : at.SWEEP].reshape(5, 2) @ np.array([1, 1j]))
        P, _ = at.curves(np.stack([J.real, J.imag], -1).reshape(1, 10), np.array([2 * np.pi]), True, 12)
        problem = make_problem(P[0], "fourbar", reach=2.0)
        if at._fits(problem, J[None])[0] and row[at.MU] > 25:
            break
    again = [at.first_answer(problem, atlas).designs for _ in range(2)]
    assert np.array_equal(*again)  # no clock in it: a resumed run gets the seeds the first one had
    lines = []
    out = synthesize(P[0], "fourbar", reach=2.0, goal=1e-5, seconds=5, progress=lines.append)
    assert lines[0].source == "atlas" and lines[0].best_error == out.max_error / out.diagonal  # said first
    assert out.outcome.stopped_by == "goal" and out.outcome.generations == 0 and out.max_error < 1e-5 * out.diagonal
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "0")  # the atlas off
    plain = synthesize(P[0], "fourbar", reach=2.0, restarts=1, generations=3, popsize=5, goal=1.0)
    assert plain.outcome.restarts == 1  # without the atlas: a search


MAKE_CHUNK = at.make_chunk


def _spy(monkeypatch, stop_after: int | None = None) -> list[int]:
    """Record the chunks made; with ``stop_after``, interrupt the build after that many."""
    made: list[int] = []
    real = MAKE_CHUNK

    def make(index: int, entries: int) -> np.ndarray:
        if stop_after is not None and len(made) == stop_after:
            raise KeyboardInterrupt
        made.append(index)
        return real(index, entries)

    monkeypatch.setattr(at, "make_chunk", make)
    return made


def test_an_interrupted_build_resumes_and_ends_as_an_uninterrupted_one(monkeypatch, tmp_path):
    monkeypatch.setattr(at, "CHUNK", 256)
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "1024")
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path / "a"))
    _spy(monkeypatch, stop_after=2)
    with pytest.raises(KeyboardInterrupt):
        at.build(workers=1)
    assert not at.path().exists() and len(list(tmp_path.glob("a/*.parts/chunk-*.npy"))) == 2
    assert at.info().chunks == 2 and not at.info().built
    made = _spy(monkeypatch)
    first = np.load(at.build(workers=1), allow_pickle=False)
    assert sorted(made) == [2, 3] and not list(tmp_path.glob("a/*.parts"))
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path / "b"))
    again = np.load(at.build(workers=1), allow_pickle=False)
    assert np.array_equal(first, again) and first.shape == (at.COLUMNS, 1025)


def test_a_build_on_two_workers_interrupted_stops_at_once(monkeypatch, tmp_path):
    """A Ctrl-C during ``atlas build --workers 2`` (here: raised by the progress report once a chunk is done) left
    the plain pool to be shut down by ``with``, which built every chunk still queued first (12 s after the Ctrl-C
    at the size of 262144 entries, found by a review). The engine's pool is killed at once: at most the chunks in
    flight are written, no worker process is left."""
    import multiprocessing

    monkeypatch.setattr(at, "CHUNK", 256)
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", str(256 * 40))
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path))

    def tick(done: int, total: int) -> None:
        if done >= 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        at.build(workers=2, tick=tick)
    written = len(list(tmp_path.glob("*.parts/chunk-*.npy")))
    # the one reported, and those the two workers finished before the parent killed them (all 40 before); the
    # bound leaves the parent, on a busy machine, many chunks' time to get there
    assert 1 <= written <= 20, written
    assert not multiprocessing.active_children()
    assert not at.info().built


def test_two_builds_at_once_share_the_work_and_the_file(monkeypatch, tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    monkeypatch.setattr(at, "CHUNK", 256)
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "1024")
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path))
    with ThreadPoolExecutor(2) as pool:
        files = list(pool.map(lambda _: at.build(workers=1), range(2)))
    assert files[0] == files[1] == at.path() and at.info().built
    assert sorted(p.name for p in tmp_path.iterdir()) == [at.path().name]  # no temporary file, no chunks left
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path / "alone"))
    assert np.array_equal(np.load(at.build(workers=1)), np.load(files[0]))


def test_a_corrupt_stale_or_foreign_file_is_rebuilt_never_trusted(monkeypatch, tmp_path):
    monkeypatch.setattr(at, "CHUNK", 256)
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "256")
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path))
    file = at.path()
    good = np.load(at.build(workers=1), allow_pickle=False)
    bad = [
        lambda: file.write_bytes(file.read_bytes()[:-1000]),  # cut short
        lambda: file.write_bytes(b"not an atlas"),
        lambda: np.save(file, np.array([{"a": 1}], dtype=object), allow_pickle=True),  # a pickle: never loaded
        lambda: np.save(file, np.where(good == at.MARKER, 0, good)),  # right shape, no marker
        lambda: np.save(file, good.astype(np.float64)),
    ]
    for spoil in bad:
        spoil()
        made = _spy(monkeypatch)
        atlas = at.load()
        assert made == [0] and np.array_equal(np.asarray(atlas.data), good)
    monkeypatch.setattr(at, "VERSION", 2)  # a new release: a new file, built anew
    made = _spy(monkeypatch)
    assert at.load().file.name == "fourbar-atlas-v2-256.npy" and made == [0] and file.exists()


def test_the_atlas_command(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "256")
    assert main(["atlas", "info"]) == 0
    assert "not built yet" in capsys.readouterr().out
    assert main(["atlas", "build", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert f"fourbar-atlas-v{at.VERSION}-256.npy (built, 0.0 MB)" in out and "128 closed curves" in out
    assert main(["atlas", "info", "--workers", "3"]) == 2  # info never builds: no workers to give it
    assert capsys.readouterr().err.count("\n") == 1
    at.path().write_bytes(b"not an atlas")
    assert main(["atlas", "info"]) == 0
    assert "(damaged: a 0.0 MB file that is not a whole atlas; the next use rebuilds it)" in capsys.readouterr().out
    for bad in ("many", "-5", "0"):  # 0 turns the atlas off: there is none to build
        monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", bad)
        assert main(["atlas", "info"]) == 2
        assert "LINKAGEKIT_ATLAS_SIZE" in capsys.readouterr().err
    assert not at.applies(make_problem([[0, 0], [1, 0], [0, 1]], "fourbar"))


def test_no_entry_fits_the_bounds_no_answer_and_the_search_as_without():
    atlas = at.load()
    T = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    problem = make_problem(T, "fourbar", pivots=((100.0, 100.5), (100.0, 100.5)))  # pivots far off every curve
    ans = at.first_answer(problem, atlas)
    assert ans.designs.shape == (0, 10) and ans.error == np.inf


@pytest.mark.parametrize("first", [1.0, 0.0])
def test_the_command_says_the_atlas_answer_first(tmp_path, capsys, monkeypatch, first):
    """The atlas's answer meets the goal: one line, the atlas's. With ``first`` 0 a plain progress line is due at
    once, as when a busy machine makes the atlas take more than a second: it printed "search 1, generation 0" after
    the atlas's line (CI stop 40's machine, the suite beside it). The atlas's line is a progress line: the next one
    comes ``every`` seconds after it."""
    from linkagekit import cli

    monkeypatch.setattr(cli._Search, "first", first)
    at.load()  # built here when this test runs alone (its progress lines are not the command's)
    capsys.readouterr()
    T = np.array([[0.0, 0.0], [1.0, 0.2], [1.6, 0.9], [1.2, 1.8], [0.3, 1.5], [-0.2, 0.7]])
    np.savetxt(tmp_path / "t.csv", T, delimiter=",", header="x,y", comments="")
    assert main(["synthesize", str(tmp_path / "t.csv"), "--goal", "0.5", "-o", str(tmp_path / "a.yaml")]) == 0
    out, err = capsys.readouterr()
    assert err.startswith("linkagekit: synthesize: the atlas's nearest four-bar, placed and polished: max error ")
    assert err.count("\n") == 1 and "stopped by reaching the goal" in out and (tmp_path / "a.yaml").exists()


def test_only_the_free_four_bar_with_its_sweep_free_starts_from_the_atlas():
    T = np.array([[0.0, 0.0], [1.0, 0.2], [1.6, 0.9], [1.2, 1.8], [0.3, 1.5]])
    assert at.applies(make_problem(T, "fourbar"))
    assert at.applies(make_problem(T, "fourbar", partial=True))  # from the open entries (review of issue 30)
    assert not at.applies(make_problem(T, "fourbar", inputs=[0, 20, 40, 60, 80], partial=True))  # timed: no sweep
    assert at.applies(make_problem(T, "fourbar", shape_only=True))  # its ground pivots fixed: put on them
    assert not at.applies(make_problem(T, "watt2"))


def test_a_shape_only_answer_is_an_entry_on_the_fixed_pivots():
    atlas = at.load()
    row = atlas.entries(np.array([300]))[0]
    J = row[at.JOINTS : at.SWEEP].reshape(5, 2) @ np.array([1, 1j])
    P, _ = at.curves(np.stack([J.real, J.imag], -1).reshape(1, 10), np.array([2 * np.pi]), True, 12)
    T = 4 - 1j + 2.5 * np.exp(0.7j) * P[0]  # the curve moved, turned and scaled
    problem = make_problem(np.stack([T.real, T.imag], 1), "fourbar", shape_only=True, min_transmission=10.0)
    X = at.on_pivots(problem, J[None])
    pose = problem.space.poses(X)[0] @ np.array([1, 1j])  # A, B where the space fixes them, C D P the entry's shape
    ratio = (pose[1:] - pose[0]) / (J[1:] - J[0])  # one similarity maps the entry onto the pose, B included
    assert np.allclose(ratio, ratio[0], rtol=0, atol=1e-12)
    ans = at.first_answer(problem, atlas)
    assert ans.error < 1e-6 and ans.designs.shape[1] == 6


def _arc(x: np.ndarray, n: int = 4001) -> np.ndarray:
    """The tracer's curve of a partial design ``x`` (joints at the pose, then ``f`` and the span) over its sweep.

    Two arcs from the pose (``at.curves`` turns the crank from a pose): back by ``f`` of the span, on by the rest.
    """
    X, f, w = x[None, :10], x[10], x[11]
    back, _ = at.curves(X, np.array([-f * w]), False, n)
    on, _ = at.curves(X, np.array([(1 - f) * w]), False, n)
    return np.concatenate([back[0][::-1], on[0]])


@pytest.mark.parametrize("shape_only", [False, True])
def test_a_partial_problem_on_an_open_entry_is_answered_by_it(shape_only):
    """Targets exactly on an open entry's arc (moved, turned, scaled): the first answer is exact.

    Checked apart from the objective: the answer's arc over its sweep (solved from its design's
    ``f`` and span as Problem.sweep defines them) passes within 1e-6 of the diagonal of every target.
    """
    atlas = at.load()
    lo, hi = atlas.block(False)
    s, b = 1.5 * np.exp(0.4j), 2 + 1j
    for r in range(lo, hi):  # the first open entry that fits the bounds of its own targets
        row = atlas.entries(np.array([r]))[0]
        J = b + s * (row[at.JOINTS : at.SWEEP].reshape(5, 2) @ np.array([1, 1j]))
        P, _ = at.curves(np.stack([J.real, J.imag], -1).reshape(1, 10), row[None, at.SWEEP], False, 14)
        T = np.stack([P[0].real, P[0].imag], 1)
        problem = make_problem(T, "fourbar", reach=2.0, partial=True, shape_only=shape_only, min_transmission=10.0)
        if (shape_only or at._fits(problem, J[None])[0]) and row[at.MU] > 25:
            break
    ans = at.first_answer(problem, atlas)
    assert ans.error < 1e-6 and ans.designs.shape[1] == problem.dim == (8 if shape_only else 12)
    x = ans.designs[0]
    assert np.pi / 2 <= x[-1] <= 2 * np.pi and 0 <= x[-2] <= 1
    if not shape_only:  # placed by the design itself (shape-only: by the objective's fitted similarity)
        diag = np.hypot(*np.ptp(T, axis=0))
        arc = _arc(x)  # each target's distance to the polyline of its dense samples
        a, d, p = arc[:-1][None, :], np.diff(arc)[None, :], P[0][:, None]
        t = np.clip(((p - a) * np.conj(d)).real / np.maximum(np.abs(d) ** 2, 1e-300), 0.0, 1.0)
        assert np.max(np.min(np.abs(a + t * d - p), axis=1)) / diag < 1e-6


def test_turns_fully_agrees_with_the_check_of_the_mechanism():
    """``atlas.turns_fully`` (the Grashof inequalities of the dyad) against ``lk.check``'s assembly range."""
    rng = np.random.default_rng(5)
    sp = builtin_space("fourbar", (0.0, 0.0), 1.0)
    X = rng.uniform(-1, 1, (40, 10))
    J = X.reshape(40, 5, 2) @ np.array([1, 1j])
    got = at.turns_fully(J)
    for x, g in zip(X, got, strict=True):
        assert g == _full_turn(sp.mechanism(x)), x
    assert 5 < got.sum() < 35  # both kinds among them


def test_a_full_turn_problem_on_an_arc_is_answered_from_the_open_entries():
    """Twelve targets on an arc of a crank-rocker's curve (an open entry whose crank turns fully), no --partial:
    the closed entries' shapes miss a part of a curve, the open ones match it; the answer is a full turn."""
    atlas = at.load()
    lo, hi = atlas.block(False)
    rows = atlas.entries(np.arange(lo, hi))
    J = rows[:, at.JOINTS : at.SWEEP].reshape(-1, 5, 2) @ np.array([1, 1j])
    good = np.flatnonzero(at.turns_fully(J) & (rows[:, at.MU] > 25))
    for r in good:  # the first such entry that fits the bounds of its own targets
        Jr = 3 - 2j + 2.0 * np.exp(1.1j) * J[r]
        P, _ = at.curves(np.stack([Jr.real, Jr.imag], -1).reshape(1, 10), rows[None, r, at.SWEEP], False, 12)
        T = np.stack([P[0].real, P[0].imag], 1)
        problem = make_problem(T, "fourbar", reach=3.0, min_transmission=10.0)
        if at._fits(problem, Jr[None])[0]:
            break
    X = at._arcs_of_turns(problem, atlas)  # the open entries' candidates, before any polish
    err, _ = problem.measure(X)
    best = int(np.argmin(err))
    assert err[best] < 5e-3 and _full_turn(problem.space.mechanism(X[best]))  # a whole turn, as the problem asks
    assert at.first_answer(problem, atlas).error <= err[best]


def _full_turn(mech) -> bool:
    """``lk.check`` finds the crank assembling over one whole turn."""
    r = lk.check(mech).input_range
    return len(r) == 1 and r[0][1] - r[0][0] >= 360.0 - 1e-9


def _chunk_killed(parts: Path, index: int, entries: int) -> int:
    """A chunk whose worker process is killed (chunk 0) or that ends at once."""
    import signal

    if index == 0:
        os.kill(os.getpid(), signal.SIGKILL)
    return index


def test_a_worker_killed_during_a_build_is_one_line_not_an_internal_error(monkeypatch, tmp_path):
    """A build worker killed (the system out of memory, say) was the pool's BrokenProcessPool, which the command
    printed as 'internal error' (the line of a bug): now WorkersLost (one line, exit status 1), nothing left running."""
    import multiprocessing

    from linkagekit.synthesis.distribute import WorkersLost

    monkeypatch.setattr(at, "CHUNK", 256)
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "1024")
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(at, "_build_chunk", _chunk_killed)
    with pytest.raises(WorkersLost, match="worker process"):
        at.build(workers=2)
    assert not multiprocessing.active_children() and not at.info().built


def _build_in(cache: str) -> str:
    """A build on two workers in a daemonic process (a multiprocessing.Pool's worker)."""
    os.environ["LINKAGEKIT_CACHE_DIR"] = cache
    try:
        return str(at.build(workers=2))
    except BaseException as e:  # noqa: BLE001 - the test shows what was raised there
        return f"{type(e).__name__}: {e}"


def test_a_build_in_a_daemonic_process_builds_its_chunks_itself(monkeypatch, tmp_path):
    """A ``multiprocessing.Pool``'s worker may not start processes: ``synthesize(..., workers=1)`` there, first using
    the atlas, failed with 'AssertionError: daemonic processes are not allowed to have children' (the build's
    workers default to every core). It builds the chunks itself, the same file."""
    import multiprocessing

    monkeypatch.setattr(at, "CHUNK", 256)
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "512")
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path / "here"))
    here = np.load(at.build(workers=1), allow_pickle=False)
    with multiprocessing.get_context("fork").Pool(1) as pool:
        got = pool.apply(_build_in, (str(tmp_path / "pool"),))
    assert got == str(tmp_path / "pool" / at.path().name), got
    assert np.array_equal(np.load(got, allow_pickle=False), here)


@pytest.mark.parametrize("workers", [1, 2])
def test_a_search_builds_a_missing_atlas_on_its_own_workers(monkeypatch, tmp_path, workers):
    """``synthesize(..., workers=1)`` built a missing atlas on every core: a user who gave the search one core (on a
    shared machine) got all of them taken for the build. The build now runs on the search's workers."""
    monkeypatch.setattr(at, "CHUNK", 256)
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "512")
    monkeypatch.setenv("LINKAGEKIT_CACHE_DIR", str(tmp_path))
    asked: list[int | None] = []
    real = at._run_chunks

    def spy(parts, todo, per, total, tick, workers):  # noqa: ANN001, ANN202 - the build's own arguments
        asked.append(workers)
        return real(parts, todo, per, total, tick, workers)

    monkeypatch.setattr(at, "_run_chunks", spy)
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    targets = np.stack([np.cos(t), 0.6 * np.sin(t)], 1)
    synthesize(targets, seconds=0.5, restarts=1, generations=2, popsize=5, workers=workers, seed=1)
    assert asked == [workers] and at.path().exists()


def test_a_deadline_bounds_the_atlas_answer(monkeypatch):
    """200 shape-only targets of an open letter made the answer take 23 s of a 3 s budget (every evaluation places
    the curve by its nearest points). With a deadline already past, only the nearest chunk is scored and the polish
    but the first stops at its start: the designs are those of the first ``COST_CHUNK`` candidates."""
    atlas = at.load()
    problem = make_problem(_curve(12), "fourbar", reach=2.0)
    calls = []
    cost = type(problem).cost
    monkeypatch.setattr(type(problem), "cost", lambda self, X: calls.append(len(X)) or cost(self, X))
    free = at.first_answer(problem, atlas, polish=1)
    assert calls[0] == len(free.designs) - free.polished > at.COST_CHUNK  # every candidate scored at once
    calls.clear()
    late = at.first_answer(problem, atlas, polish=2, until=time.monotonic() - 1.0)
    assert calls[0] == at.COST_CHUNK and len(late.designs) == at.COST_CHUNK + 2
    assert late.polished == 2  # the first polish runs whole, the second returns its start (cut at once)
    assert len(np.unique(late.designs, axis=0)) == len(late.designs) - 1  # that start is among the candidates too
    past = time.monotonic() - 1.0  # the whole budget past too: the first polish returns its start as well
    spent = at.first_answer(problem, atlas, polish=2, until=past, first_until=past)
    assert len(np.unique(spent.designs, axis=0)) == len(spent.designs) - 2
