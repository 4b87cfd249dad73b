"""``--topology auto``: the enumeration of dyad topologies, the tracer fit, and the command."""

from __future__ import annotations

import os

import numpy as np
import pytest

import linkagekit as lk
from helpers import interruptible
from linkagekit.cli import main
from linkagekit.errors import InputError
from linkagekit.params import compile as compile_params
from linkagekit.positions import solve
from linkagekit.synthesis.space import builtin_space
from linkagekit.synthesis.topologies import enumerate_topologies
from linkagekit.synthesis.tracer import fit, fit_shifts


def test_counts_by_hand_for_five_and_six_joints() -> None:
    """5 joints: the four-bar only. 6 joints: one more joint is one more dyad on two joints already there.

    Of the pairs of {A, B, C, D} not on one body only (A, D) and (B, C) remain; with (B, C) the
    new joint's links are B-E (a ground pivot: no tracer) and C-E, whose motion does not
    depend on D (a four-bar C-E-B in disguise): so one six-bar, E on A and D, P on D-E.
    """
    assert [t.name for t in enumerate_topologies(5)] == ["fourbar"]
    six = enumerate_topologies(6)
    assert [t.name for t in six] == ["fourbar", "sixbar-1"]
    links = {frozenset(j) for _, j in six[1].links}
    assert {frozenset("AB"), frozenset("AC"), frozenset("CD"), frozenset("BD"), frozenset("AE")} <= links
    assert frozenset("DEP") in links


def test_named_six_bars_are_found_again_and_counts_grow() -> None:
    eight = enumerate_topologies(8)
    names = [t.name for t in eight]
    assert {"watt2", "stephenson3"} <= set(names)
    assert len(names) == len(set(names))
    assert [len(enumerate_topologies(n)) for n in (5, 6, 7, 8)] == [1, 2, 16, 84]


def test_every_template_assembles_at_its_pose_with_one_driver() -> None:
    """All of up to 7 joints, and every 10th of 8 joints (each takes a plan and a compile)."""
    seven = enumerate_topologies(7)
    for t in seven + enumerate_topologies(8)[len(seven) :: 10]:
        sp = builtin_space(t.name, (0.0, 0.0), 1.0)  # from_dict: refused unless the drivers match the dof
        assert [d.name for d in sp.template.drivers] == ["crank"]
        assert len(sp.template.joint_names) == t.n_joints <= 8
        pose = sp.template.pose_array()
        params = compile_params(sp.template, pose[None], sp.plan)
        z = solve(params, params.pose_inputs[0][None, :, None]).z[:, 0, 0]
        np.testing.assert_allclose(z, pose[:, 0] + 1j * pose[:, 1], atol=1e-9, err_msg=t.name)


@pytest.mark.parametrize("n", [3, 4, 11])
def test_max_joints_out_of_range(n: int) -> None:
    with pytest.raises(InputError, match="--max-joints"):
        enumerate_topologies(n)


def _brute(Xi: np.ndarray, Xj: np.ndarray, T: np.ndarray, width: int) -> tuple[float, complex]:
    """Every shift and direction by numpy's least squares: (least SSE, its c)."""
    n, m = len(Xi), len(T)
    p = (np.arange(m) * width) // m
    best = (np.inf, 0j)
    for Td in (T, T[::-1]):
        for s in range(n):
            k = (p + s) % n
            A = np.stack([np.ones(m), Xi[k], Xj[k] - Xi[k]], 1)
            if not np.all(np.isfinite(A)):
                continue
            u = np.linalg.lstsq(A, Td, rcond=None)[0]
            sse = float(np.sum(np.abs(A @ u - Td) ** 2))
            best = min(best, (sse, u[2] / u[1]), key=lambda b: b[0])
    return best


@pytest.mark.parametrize("width", [24, 13])
def test_tracer_fit_over_shifts_matches_brute_force(width: int) -> None:
    rng = np.random.default_rng(3)
    Xi = rng.normal(size=(3, 24)) + 1j * rng.normal(size=(3, 24))
    Xj = rng.normal(size=(3, 24)) + 1j * rng.normal(size=(3, 24))
    Xi[1, 4] = np.nan  # a sample where design 1 does not assemble
    T = rng.normal(size=9) + 1j * rng.normal(size=9)
    f = fit_shifts(Xi, Xj, T, width)
    for d in range(3):
        sse, c = _brute(Xi[d], Xj[d], T, width)
        assert f.sse[d] == pytest.approx(sse, rel=1e-8)
        assert abs(f.c[d] - c) < 1e-8 * (1 + abs(c))


def test_spectra_taken_once_serve_every_width_of_a_partial_fit() -> None:
    """A partial fit tries several widths on the same samples: their spectra taken once give each width's fit of
    fresh spectra, bit for bit, and each matches the brute force over the shifts."""
    from linkagekit.synthesis.tracer import spectra

    rng = np.random.default_rng(5)
    Xi = rng.normal(size=(2, 32)) + 1j * rng.normal(size=(2, 32))
    Xj = rng.normal(size=(2, 32)) + 1j * rng.normal(size=(2, 32))
    Xi[0, 7] = np.nan
    T = rng.normal(size=11) + 1j * rng.normal(size=11)
    spec = spectra(Xi, Xj)
    for width in (9, 12, 16, 24):
        once, fresh = fit_shifts(Xi, Xj, T, width, spec=spec), fit_shifts(Xi, Xj, T, width)
        for field in ("c", "a", "b", "sse", "shift", "direction"):
            assert np.array_equal(getattr(once, field), getattr(fresh, field)), (width, field)
        for d in range(2):
            assert once.sse[d] == pytest.approx(_brute(Xi[d], Xj[d], T, width)[0], rel=1e-8)


def test_the_normal_matrices_inverted_by_their_adjugate_agree_with_lapack() -> None:
    """``_Inverse3`` (the adjugate, shared by both directions) against NumPy's solve on the same ridged matrices:
    Gram matrices of random bases, well and badly conditioned (columns nearly dependent)."""
    from linkagekit.synthesis.tracer import RIDGE, _Inverse3

    rng = np.random.default_rng(2)
    B = rng.normal(size=(200, 3, 20)) + 1j * rng.normal(size=(200, 3, 20))
    B[100:, 2] = B[100:, 1] * (1 + 1e-5j) + 1e-6 * B[100:, 2]  # cond ~1e10
    G = np.einsum("npk,nqk->npq", np.conj(B), B)
    r = rng.normal(size=(200, 3)) + 1j * rng.normal(size=(200, 3))
    u, _ = _Inverse3(G).solve(r, 0.0)
    scale = np.einsum("nii->n", G).real[:, None, None]
    want = np.linalg.solve(G + RIDGE * scale * np.eye(3), r[..., None])[..., 0]
    err = np.abs(u - want).max(axis=1) / np.abs(want).max(axis=1)
    assert err[:100].max() < 1e-12 and err[100:].max() < 1e-4  # rounding times the condition number, both ways


def test_tracer_fit_recovers_a_placed_coupler_point() -> None:
    """A four-bar's coupler point, moved, turned and scaled, sampled from another shift: found exactly."""
    mech = lk.load("examples/seed000_fourbar.yaml")
    res = lk.analyze(mech, {"crank": np.arange(0.0, 360.0, 10.0)})
    C, D, P = (res.point(j) for j in "CDP")
    c_true = (P[0] - C[0]) / (D[0] - C[0])
    T = np.roll(0.3 - 2j + (0.5 + 0.8j) * P, -7)  # target k is sample k + 7
    f = fit_shifts(C[None], D[None], T)
    assert f.sse[0] < 1e-10 * np.sum(np.abs(T) ** 2) and f.shift[0] == 7 and f.direction[0] == 1
    assert abs(f.c[0] - c_true) < 1e-8 and abs(f.b[0] - (0.5 + 0.8j)) < 1e-8  # the ridge: ~1e-10
    g = fit(C[None], D[None], P, placement=False)  # where it is: c alone
    assert abs(g.c[0] - c_true) < 1e-10


def test_auto_writes_a_valid_mechanism_and_names_its_topology(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    csv = tmp_path / "ellipse.csv"
    np.savetxt(csv, np.stack([np.cos(t), 0.6 * np.sin(t)], 1), delimiter=",", header="x,y", comments="")
    out = tmp_path / "out.yaml"
    code = main(["synthesize", str(csv), "--topology", "auto", "--max-joints", "5", "--seconds", "1.5", "-o", str(out)])
    text, err = capsys.readouterr()
    assert code == 0
    assert "topology fourbar (5 joints)" in text
    lines = err.splitlines()  # off a terminal, plain progress lines (there were none: issue 30's "a plain line")
    assert lines[0].startswith("linkagekit: synthesize: the four-bar from its atlas, then a screen of ")
    assert any(line.startswith("linkagekit: synthesize: searching fourbar") for line in lines)
    assert all(line.startswith("linkagekit: synthesize: ") and line.endswith(" of 1.5 s") for line in lines), lines
    mech = lk.load(out)
    a = mech.to_dict()["drivers"][0]["angles"]
    res = lk.analyze(mech, {"crank": np.linspace(a["start"], a["stop"], 1441)})
    assert np.all(res.assembled)
    P = res.xy("P")
    d = np.min(np.hypot(P[:, 0][None] - np.cos(t)[:, None], P[:, 1][None] - 0.6 * np.sin(t)[:, None]), axis=1)
    assert np.max(d) < 0.05 * np.hypot(2, 1.2)  # near every target
    # the file's name gives the printed max error, as a single topology's does, and its description's first line is
    # a line (it ended in a literal backslash-n, review 18a)
    printed = next(line for line in text.splitlines() if line.startswith("max error "))
    assert mech.name.startswith("synthesised fourbar: max error ")
    assert mech.name.endswith(" % of the targets' diagonal)")
    named, shown = (float(x.split("max error ")[1].split(" ")[0]) for x in (mech.name, printed))
    assert named == pytest.approx(shown, rel=1e-3) and mech.name.split("max error ")[1].split(" ")[1] == "m"
    assert mech.description.splitlines()[0] == "topology fourbar (5 joints), crank 360 deg"
    assert "\\n" not in mech.description


@pytest.mark.parametrize("workers", [1, 2])
def test_auto_reports_its_stages_and_a_line_every_tick_never_better_than_what_it_writes(monkeypatch, workers) -> None:  # type: ignore[no-untyped-def]
    """``--topology auto`` printed no progress at all off a terminal (its local searches took no callback). It now
    reports each stage at once (the first before the four-bar search starts) and, while its searches run, a line
    every :data:`TICK` seconds (at the latest after each local search, or, with workers, each wait for them); the
    best it reports is the four-bar candidate's two-sided distance, which the written design never exceeds (it is
    chosen by it). No bound on the time between lines: on a busy machine a local search takes longer."""
    import time

    from linkagekit.synthesis import auto

    monkeypatch.setattr(auto, "TICK", 0.05)
    got: list = []
    real = auto.four_bar_engine
    monkeypatch.setattr(auto, "four_bar_engine", lambda *a, **k: got.append((None, len(got))) or real(*a, **k))
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    T = np.stack([np.cos(t), 0.6 * np.sin(t)], 1)
    t0 = time.monotonic()
    out = auto.synthesize_auto(
        T, max_joints=6, seconds=2.0, seed=3, workers=workers, progress=lambda s: got.append((time.monotonic() - t0, s))
    )
    assert got[0][1].what.startswith("the four-bar from its atlas") and got[1] == (None, 1)  # then the search
    got = [g for g in got if g[0] is not None]
    searching = [s for _, s in got if s.what.startswith("searching ")]
    assert len(searching) >= 2  # the stage, then at least one tick (after the first local search, or a wait)
    for w, s in got:
        assert abs(s.elapsed - (got[0][1].elapsed + w - got[0][0])) < 0.5  # the run's own clock
    four = next(r for r in out.tried if r.name == auto.FOUR_BAR_ENGINE)
    reported = {s.best for _, s in got if s.best == s.best}
    assert reported == {four.two_sided}  # its two-sided distance, as the choice measures it
    assert auto.two_sided(out, T) / out.diagonal <= four.two_sided + 1e-15


def test_auto_reports_how_the_whole_run_went() -> None:
    """The outcome of ``synthesize_auto`` counts every topology's searches and the time from the start (it was the
    chosen topology's own search: "in 0.3 s" for a run of 1 s)."""
    from linkagekit.synthesis.auto import synthesize_auto

    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    out = synthesize_auto(np.stack([np.cos(t), 0.6 * np.sin(t)], 1), max_joints=6, seconds=1.0, seed=3)
    assert len(out.tried) >= 2
    assert out.outcome.seconds >= 0.9  # the run is stopped by its clock: at least its budget less the reserve
    assert out.outcome.restarts >= len(out.tried)


@pytest.mark.parametrize(
    "extra", [["--max-joints", "3"], ["--max-joints", "x"], ["--topology", "fourbar", "--max-joints", "6"]]
)
def test_bad_max_joints_is_one_line_exit_2(extra: list[str], tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    csv = tmp_path / "t.csv"
    csv.write_text("x,y\n0,0\n1,0\n0,1\n")
    args = ["synthesize", str(csv), "--topology", "auto", *extra, "-o", str(tmp_path / "o.yaml")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--max-joints" in err


def test_the_screen_on_two_workers_screens_each_topology_as_one_worker_does() -> None:
    """Each topology's random designs come from its own seed: dealt out to two processes, the topologies screened
    (here the three always screened: the deadline has passed) get the same designs and fits as on one."""
    import time

    from linkagekit.synthesis.auto import Maker, screen

    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    make = Maker(np.stack([np.cos(t), 0.6 * np.sin(t)], 1), "m", False, (("min_transmission", 20.0),))
    tops = enumerate_topologies(8)  # the first to name Watt II and Stephenson III
    one = screen(tops, make, np.random.default_rng(5), time.monotonic() - 1.0, workers=1)
    two = screen(tops, make, np.random.default_rng(5), time.monotonic() - 1.0, workers=2)
    assert set(one) == set(two) == {"fourbar", "watt2", "stephenson3"}
    for name in one:
        assert one[name][0] == two[name][0] and np.array_equal(one[name][1], two[name][1]), name
        assert np.isfinite(one[name][0])  # a fit was found: the comparison is not of two failures


@pytest.mark.parametrize("workers, want", [(1, 3), (2, 4), (3, 3), (4, 4), (5, 5)])
def test_the_topologies_searched_fill_whole_rounds_of_the_workers(workers: int, want: int) -> None:
    from linkagekit.synthesis.auto import searched

    assert searched(workers) == want


def test_a_dense_drawing_is_fitted_along_its_strokes_not_by_its_points() -> None:
    """A drawing of 150 closely spaced points and one long straight stroke between two of them (as between the
    strokes of the letter E): the search's 100 targets are spread evenly along the whole line, the stroke included
    (thinning by index put none on it)."""
    from linkagekit.synthesis.auto import Projected
    from linkagekit.synthesis.run import make_problem

    first = np.linspace(0, 1, 75) + 0j
    second = 1 + 3j + np.linspace(0, 1, 75)  # the stroke from 1 to 1 + 3i is 3 long, the rest 2 in all
    pts = np.concatenate([first, second])
    proj = Projected(make_problem(np.stack([pts.real, pts.imag], 1), "fourbar", None, "m"), partial=True)
    T = proj.targets
    assert len(T) == 100
    # each target's place along the line: on the first part, on the stroke, on the second part
    s = np.where(np.abs(T.imag) < 1e-12, T.real, np.where(np.abs(T.real - 1) < 1e-12, 1 + T.imag, 3 + T.real))
    assert np.allclose(np.diff(s), 5.0 / 99, rtol=1e-9)  # on the line, evenly along its 5 units
    assert np.sum(np.abs(T.real - 1) < 1e-12) >= 59  # 3/5 of them on the stroke


def test_the_chamfer_parts_are_never_negative_where_samples_lie_on_targets() -> None:
    """The squared distances come from the expanded square ``|p|^2 - 2 p.t + |t|^2``, a little below 0 by rounding
    where a sample lies on a target: their square roots (the search's residuals) were NaN with a RuntimeWarning (seen
    on letter I of the LINK-ABC benchmark). On curves through their targets, far from the origin, none is below 0."""
    from types import SimpleNamespace

    from linkagekit.synthesis.auto import _chamfer

    rng = np.random.default_rng(0)
    one = SimpleNamespace(a=np.zeros(1, complex), b=np.ones(1, complex), c=np.zeros(1, complex), sse=np.zeros(1))
    worst = 0.0
    for _ in range(50):
        T = (rng.normal(size=40) + 1j * rng.normal(size=40)) * rng.uniform(0.1, 100) + complex(
            *rng.uniform(-1e3, 1e3, 2)
        )
        P = np.concatenate([T, T[:10] + 1e-3])[None]
        d, _, parts = _chamfer(one, P, P, T, np.ones(P.shape, bool))
        worst = min(worst, float(parts.min()))
        assert d[0] == pytest.approx(10 * 1e-6 / 50, rel=1e-4)  # ten of the 50 samples 1e-3 off a target
    assert worst == 0.0


def test_the_chamfer_pairs_are_the_nearest_ones_of_a_brute_force_in_double() -> None:
    """The nearest pairs come from the expanded square and are measured again directly: the distances equal those of
    a brute force to rounding (1e-12 of the squared size), on curves far from the origin, with samples off the
    window never paired."""
    from types import SimpleNamespace

    from linkagekit.synthesis.auto import _chamfer

    rng = np.random.default_rng(4)
    N, n, m = 6, 50, 30
    T = 500.0 + 3j + rng.normal(size=m) + 1j * rng.normal(size=m)
    P = 500.0 + 3j + 1.3 * (rng.normal(size=(N, n)) + 1j * rng.normal(size=(N, n)))
    window = rng.random((N, n)) < 0.7
    one = SimpleNamespace(a=np.zeros(N, complex), b=np.ones(N, complex), c=np.zeros(N, complex), sse=np.zeros(N))
    d, k, parts = _chamfer(one, P, P, T, window)
    D2 = np.abs(P[:, :, None] - T[None, None, :]) ** 2
    to_targets = np.where(window, D2.min(axis=2), 0.0) / window.sum(axis=1)[:, None]
    nearest = np.where(window[:, :, None], D2, np.inf).min(axis=1)  # (N, m): to the window's samples
    assert np.all(window[np.arange(N)[:, None], k])
    size2 = np.abs(T - T.mean()).max() ** 2
    assert np.abs(parts[:, m:] - to_targets).max() < 1e-12 * size2 / n
    assert np.all(parts[:, :m] <= nearest / m + 1e-12 * size2 / m)  # the chords only come nearer than the samples


@pytest.mark.parametrize("m", [3, 6, 10, 40])
def test_a_partial_fit_of_few_targets_still_turns_the_crank_a_quarter_turn(m: int) -> None:
    """The window of a partial fit runs from its first target to its last, ``(m - 1) / m`` of the width: the
    narrowest width (96 deg) left 87.2 deg with 10 targets and 81.6 with 6, under the 90 deg a written sweep must
    turn (review 18a). Every design's span, and the sweep written for the best, is at least 90 deg."""
    from linkagekit.synthesis.auto import Projected, written
    from linkagekit.synthesis.optimize import Outcome
    from linkagekit.synthesis.run import make_problem

    s = np.linspace(0, 1, m)
    pts = 2 * s + 0.4j * np.sin(3 * s)
    proj = Projected(make_problem(np.stack([pts.real, pts.imag], 1), "fourbar", None, "m"), partial=True)
    lo, hi = proj.bounds
    X = lo + np.random.default_rng(5).random((64, len(lo))) * (hi - lo)
    p = proj.placed(X)
    assert np.all(p.span * 360.0 / proj.samples >= 90.0 - 1e-9)
    best = X[int(np.argmin(proj.cost(X)))]
    syn = written(proj, best, Outcome(best, 0.0, 1, 0, 1, 0.0, "time"))
    assert syn.sweep is not None and syn.sweep[1] - syn.sweep[0] >= 90.0 - 1e-9


def test_a_partial_fits_distance_is_the_brute_force_chamfer_of_its_window_on_the_turn() -> None:
    """The nearest points of a partial fit are searched among its window's samples only; the distance it reports
    equals the two-sided chamfer computed here over the whole turn's samples with the window as a mask (each target
    to its nearest window sample or either chord from it to a neighbour on the turn in the window; each window
    sample to its nearest target), to rounding, for designs whose windows wrap round the turn's first sample."""
    from linkagekit.synthesis.auto import Projected, _tracer_base
    from linkagekit.synthesis.run import make_problem

    s = np.linspace(0, 1, 60)
    pts = 2 * s + 0.4j * np.sin(3 * s)
    proj = Projected(make_problem(np.stack([pts.real, pts.imag], 1), "watt2", None, "m"), partial=True)
    lo, hi = proj.bounds
    X = lo + np.random.default_rng(3).random((48, len(lo))) * (hi - lo)
    p = proj.placed(X)
    i, j = _tracer_base(proj.problem)
    T = proj.targets
    n, checked, wrapped = proj.samples, 0, 0
    for d in np.flatnonzero(np.isfinite(p.distance)):
        w = p.window[d]
        P = p.fit.a[d] + p.fit.b[d] * (p.solution.z[i][d] + p.fit.c[d] * (p.solution.z[j][d] - p.solution.z[i][d]))
        on = np.flatnonzero(w)
        to_samples = np.abs(P[on][None, :] - T[:, None]) ** 2  # (m, window)
        to_curve = to_samples.min(axis=1)
        for t_, k in enumerate(on[np.argmin(to_samples, axis=1)]):  # the chords at each target's nearest sample
            for k2 in ((k - 1) % n, (k + 1) % n):
                if w[k2]:
                    a, ab = P[k], P[k2] - P[k]
                    u = np.clip((np.conj(ab) * (T[t_] - a)).real / abs(ab) ** 2, 0, 1)
                    to_curve[t_] = min(to_curve[t_], abs(a + u * ab - T[t_]) ** 2)
        brute = to_curve.mean() + to_samples.min(axis=0).mean()
        assert p.distance[d] == pytest.approx(brute, rel=1e-12, abs=1e-15)
        checked += 1
        wrapped += bool(w[0] and w[-1])
    assert checked >= 10 and wrapped >= 1, (checked, wrapped)


#: a script whose argv[1] searches on two worker processes take ten minutes each unless stopped: those of the
#: seeds in argv[2] return at once, the others sleep their share
_SLOW_SEARCHES = """
import sys, time
import linkagekit.synthesis.auto as auto
quick = {int(s) for s in sys.argv[2].split(",") if s}

def slow(proj, seed, seconds, x0):
    if seed not in quick:
        sys.stdout.write("started\\n")  # one write: two workers may start at once
        sys.stdout.flush()
        time.sleep(seconds)
    return seed

auto._multistart = slow
try:
    auto.local_searches([None] * int(sys.argv[1]), list(range(int(sys.argv[1]))), [None] * int(sys.argv[1]), 1200, 2)
except KeyboardInterrupt:
    sys.exit("interrupted")
"""


@pytest.mark.parametrize(
    "k, quick",
    [(4, ""), (2, "0")],
    ids=["the second round is not started", "an idle worker prints no traceback"],
)
def test_ctrl_c_during_the_searches_on_two_workers_ends_them_at_once_in_one_line(k: int, quick: str) -> None:
    """Ctrl-C (SIGINT to the process group, as a terminal sends it) while auto's own worker processes search: the
    run ends at once (not after the searches queued behind the interrupted ones, each a whole share of the time),
    and the parent's line is all that is printed (a worker waiting for a task printed its KeyboardInterrupt)."""
    import os
    import signal
    import subprocess
    import sys
    import time

    cmd = [sys.executable, "-c", _SLOW_SEARCHES, str(k), quick]
    proc = subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=interruptible,
    )
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "started\n"
        time.sleep(0.3)  # the other worker at its task, or waiting for one
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)  # a hang guard: the searches queued would take ten minutes
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert (proc.returncode, err) == (1, "interrupted\n")


def test_a_dense_closed_drawing_is_fitted_round_its_whole_loop() -> None:
    """A closed drawing (the search goes round a whole turn) of 150 points on a half circle, its straight side the
    stroke from its last point back to its first (a D): the targets are spread evenly round the whole loop, the
    straight side included (none were put there), the first not repeated at the end; and a list that repeats its
    first point at the end gives no two targets at one place (one place twice in the turn)."""
    from linkagekit.synthesis.auto import Projected
    from linkagekit.synthesis.run import make_problem

    arc = 1j * np.exp(-1j * np.linspace(0, np.pi, 150))  # from i round to -i: the side from -i to i is 2 long
    for pts in (arc, np.append(arc, arc[0])):
        proj = Projected(make_problem(np.stack([pts.real, pts.imag], 1), "fourbar", None, "m"), partial=False)
        T = proj.targets
        assert len(T) == 100
        on_side = np.abs(T.real) < 1e-12
        assert np.all(on_side | (np.abs(np.abs(T) - 1) < 1e-3))  # on the line: the side or the arc
        gaps = np.abs(np.diff(np.append(T, T[0])))  # round the loop, the last target to the first included
        loop = 2.0 + 149 * np.abs(arc[1] - arc[0])  # the polygon's length
        assert np.allclose(gaps[on_side & np.roll(on_side, -1)], loop / 100, rtol=1e-9)
        assert np.min(gaps) > 0.9 * loop / 100  # chords of the arc a little shorter than its arcs; none 0
        assert np.sum(on_side) >= 100 * 2.0 / loop - 1


def _killed(proj: object, seed: int, seconds: float, x0: object) -> int:
    """A search whose process is killed (seed 0) or that ends at once."""
    import os
    import signal

    if seed == 0:
        os.kill(os.getpid(), signal.SIGKILL)
    return seed


def test_a_worker_killed_during_the_searches_is_one_line_not_an_internal_error(monkeypatch) -> None:
    """A worker process killed (the system out of memory, say): WorkersLost, whose line is an error of exit status 1
    (it was the pool's BrokenProcessPool, an 'internal error' as of a bug)."""
    import linkagekit.synthesis.auto as auto
    from linkagekit.synthesis.distribute import WorkersLost

    monkeypatch.setattr(auto, "_multistart", _killed)
    with pytest.raises(WorkersLost, match="worker process"):
        auto.local_searches([None] * 2, [0, 1], [None] * 2, 1.0, 2)  # type: ignore[list-item]


def test_scheduler_with_topology_auto_is_one_line_exit_2(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    """Its searches run on local processes: a Dask address was accepted and ignored (the run went on locally)."""
    csv = tmp_path / "t.csv"
    csv.write_text("x,y\n0,0\n1,0\n0,1\n")
    args = [
        "synthesize",
        str(csv),
        "--topology",
        "auto",
        "--scheduler",
        "tcp://127.0.0.1:1",
        "-o",
        str(tmp_path / "o.yaml"),
    ]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--scheduler" in err and not (tmp_path / "o.yaml").exists()


def test_spare_workers_search_the_topologies_again_each_from_a_seed_of_its_own() -> None:
    """``--max-joints 5`` has one topology: on two workers the second searched nothing. Fewer objectives than workers
    are searched again in turn, each replica from another seed and without the screen's start; one objective's
    outcome is its best search's, with every search counted."""
    from linkagekit.synthesis.auto import _merged, _replicas
    from linkagekit.synthesis.optimize import Outcome

    a, b = np.zeros(2), np.ones(2)
    owner, seeds, starts = _replicas([7, 9], [a, b], 5)
    assert owner == [0, 1, 0, 1, 0] and len(set(seeds)) == 5 and seeds[:2] == [7, 9]
    assert starts[0] is a and starts[1] is b and starts[2:] == [None, None, None]
    assert _replicas([7, 9, 11, 13], [a, b, a, b], 2) == ([0, 1, 2, 3], [7, 9, 11, 13], [a, b, a, b])  # as given
    owner, seeds, starts = _replicas([7, 9, 11], [a, b, a], 2)  # the second round's idle worker searches the first
    assert owner == [0, 1, 2, 0] and seeds[3] not in seeds[:3] and starts[3] is None
    outs = [Outcome(np.full(2, float(c)), c, 3, 0, 100, 1.0, "time") for c in (0.5, 0.2, 0.9)]
    m = _merged(outs)
    assert m.cost == 0.2 and np.array_equal(m.x, outs[1].x) and m.restarts == 9 and m.evaluations == 300


def test_a_topology_auto_names_is_a_topology_of_the_command_line_too(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    """The docs say every enumerated name ``--topology auto`` prints is a ``--topology`` of its own, and the Python
    API took them, but the command line refused them ("neither a topology nor a file")."""
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    csv = tmp_path / "ellipse.csv"
    np.savetxt(csv, np.stack([np.cos(t), 0.6 * np.sin(t)], 1), delimiter=",", header="x,y", comments="")
    out = tmp_path / "out.yaml"
    args = ["synthesize", str(csv), "--topology", "sixbar-1", "--seconds", "1", "--workers", "1", "-o", str(out)]
    args += ["--restarts", "1", "--generations", "5"]
    code = main(args)
    text = capsys.readouterr().out
    assert code == 0, text
    mech = lk.load(out)
    assert len(mech.joint_names) == 6 and "sixbar-1" in mech.name  # A, C, B, D, E and P
    assert main(["synthesize", str(csv), "--topology", "sixbar-99999", "-o", str(out)]) == 2
    assert "such as sixbar-1" in capsys.readouterr().err


def test_auto_refuses_reach_in_one_line_as_it_does_not_apply(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    """``--reach`` was dropped silently by ``--topology auto`` while the file's description recorded it (review 18a:
    ``--reach 0.5`` and a joint at 6.03 diagonals); it is refused, as ``--pivots`` and the others are."""
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    csv = tmp_path / "ellipse.csv"
    np.savetxt(csv, np.stack([np.cos(t), 0.6 * np.sin(t)], 1), delimiter=",", header="x,y", comments="")
    out = tmp_path / "out.yaml"
    assert main(["synthesize", str(csv), "--topology", "auto", "--reach", "0.5", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--reach" in err and "do not apply" in err and not out.exists()


def test_auto_takes_the_four_bar_search_of_a_single_topology_as_a_candidate_too(monkeypatch) -> None:
    """On seven points of an arc, ``--topology auto`` ended at 0.2-1.1 % of the diagonal in 15-20 s where
    ``--topology fourbar --shape-only`` reaches 0.003 % in 5 s (its atlas, then its engine): the projected search is
    built for shapes no four-bar draws. The four-bar search now runs for a share of the time as a candidate of its
    own (listed as "fourbar (atlas)"), and the candidate nearest the targets on both sides (:func:`two_sided`; the
    targets' own errors miss a curve that runs on past them), feasible first, is the answer."""
    from linkagekit.synthesis import auto

    seen: list = []
    for name in ("four_bar_engine", "written"):
        real = getattr(auto, name)
        monkeypatch.setattr(auto, name, lambda *a, _real=real, **k: seen.append(_real(*a, **k)) or seen[-1])
    arc = np.array([[0, 0], [1, 0.5], [2, 0.8], [3, 0.9], [4, 0.8], [5, 0.5], [6, 0]], float)
    out = auto.synthesize_auto(arc, max_joints=6, seconds=1.0, seed=1, workers=1)
    errors = {t.name: t.error for t in out.tried}
    engine = next(c for c in seen if c.topology == "fourbar" and auto.FOUR_BAR_ENGINE in errors)
    assert abs(errors[auto.FOUR_BAR_ENGINE] - engine.rms_error / engine.diagonal) < 1e-12 and len(seen) >= 2
    judged = sorted((not c.feasible, auto.two_sided(c, arc)) for c in seen)
    assert (not out.feasible, auto.two_sided(out, arc)) == judged[0]
    listed = {t.name: t.two_sided for t in out.tried}  # what the `searched:` line prints, over the diagonal
    assert abs(listed[auto.FOUR_BAR_ENGINE] - auto.two_sided(engine, arc) / engine.diagonal) < 1e-12
    assert abs(min(listed.values()) - judged[0][1] / out.diagonal) < 1e-12
    res = lk.analyze(out.mechanism, {"crank": np.linspace(0.0, 360.0, 3601)})
    assert np.all(res.assembled)


class _Killed(Exception):
    """The run stopped."""


def test_a_killed_auto_run_resumes_from_its_checkpoint_without_doing_again_what_it_did(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """``--topology auto --checkpoint FILE`` (it was refused: a long letter run killed lost everything). A run stopped
    after one round of its local searches resumes: the screen and the four-bar search are not run again, the
    searches start from their best designs so far with seeds moved on, and the clock goes on from the time used."""
    from linkagekit.synthesis import auto, autosave

    monkeypatch.setattr(autosave, "ROUND_SECONDS", 0.3)
    monkeypatch.setattr(auto, "ROUND_SECONDS", 0.3)
    calls: list = []
    real, kill = auto.local_searches, True

    def once(projs, seeds, starts, seconds, workers, tick=None):  # type: ignore[no-untyped-def]
        calls.append((list(seeds), [np.array(x) for x in starts], seconds))
        if len(calls) == 2 and kill:
            raise _Killed  # killed in the second round
        return real(projs, seeds, starts, seconds, workers, tick)

    monkeypatch.setattr(auto, "local_searches", once)
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    T, path = np.stack([np.cos(t), 0.6 * np.sin(t)], 1), str(tmp_path / "run.npz")
    with pytest.raises(_Killed):
        auto.synthesize_auto(T, max_joints=5, seconds=2.0, seed=4, workers=1, checkpoint=path)
    topologies = enumerate_topologies(5)
    make = auto.Maker(T, "m", False, (("min_transmission", 20.0),))
    ck = auto._checkpoint(path, make, topologies, (T, "m", False, {"min_transmission": 20.0}, 5, 4, "local"))
    saved = ck.load()
    assert saved.order == ["fourbar"] and saved.rounds == 1 and saved.fourbar is not None
    assert saved.elapsed > 0.7 * 2.0 * (auto.SCREEN + auto.FOUR_BAR_SHARE)  # the screen's and the four-bar's time
    first = saved.best[0]
    for name in ("screen", "four_bar_engine"):  # done: not again
        monkeypatch.setattr(auto, name, lambda *a, **k: pytest.fail("run again"))
    calls.clear()
    kill = False
    stages: list = []
    out = auto.synthesize_auto(T, max_joints=5, seconds=2.0, seed=4, workers=1, checkpoint=path, progress=stages.append)
    assert stages[0].what.startswith("resumed from its checkpoint after ")  # (it said it searched the four-bar)
    assert stages[1].what == "the four-bar found"  # and that it screened
    assert np.array_equal(calls[0][1][0], first.x)  # from the best so far
    assert calls[0][0] == [(saved.seeds[0] + 7919) % 2**32]  # the seeds moved on by the round done
    assert out.outcome.seconds >= 0.95 * 2.0 * (1 - auto.RESERVE)  # both runs' time: the budget, not twice it
    done = ck.load()
    assert done.rounds > saved.rounds and done.best[0].cost <= first.cost  # never worse than it was
    assert done.best[0].starts >= first.starts and done.best[0].designs > first.designs
    assert out.feasible and out.topology in ("fourbar",)


def test_an_auto_checkpoint_of_another_run_or_altered_is_refused_in_one_line(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Another run's checkpoint (other targets or options), an array of another shape, a name that is no topology of
    the run: each refused naming the file, before any array is read."""
    from linkagekit.synthesis.autosave import Best, Checkpoint, Saved

    path = str(tmp_path / "ck.npz")
    dims = {"fourbar": 6, "watt2": 10}.__getitem__
    saved = Saved(1.5, [3], ["watt2"], [(0.2, np.ones(10))], None, [Best(np.full(10, 2.0), 0.1, 4, 400, 1.0)], 1)
    Checkpoint(path, "abc", dims, 9).save(saved)
    back = Checkpoint(path, "abc", dims, 9).load()
    assert back is not None and back.elapsed == 1.5 and back.best[0].x.tolist() == [2.0] * 10
    with pytest.raises(InputError, match=r"ck\.npz: this checkpoint belongs to another run"):
        Checkpoint(path, "xyz", dims, 9).load()
    with pytest.raises(InputError, match=r"ck\.npz: not a usable .*_x_0 .*shape \(10,\), expected .*\(12,\)"):
        Checkpoint(path, "abc", {"fourbar": 6, "watt2": 12}.__getitem__, 9).load()
    with pytest.raises(InputError, match=r"ck\.npz: not a usable .*'watt2' is no topology of this run"):
        Checkpoint(path, "abc", {"fourbar": 6}.__getitem__, 9).load()
    assert Checkpoint(str(tmp_path / "none.npz"), "abc", dims, 9).load() is None


@pytest.mark.parametrize("bad", [np.nan, np.inf, 1e300])
def test_an_auto_checkpoint_holding_a_number_no_design_has_is_refused(tmp_path, bad) -> None:  # type: ignore[no-untyped-def]
    """A review: NaN in a saved design reached the targets' check ('poses: every coordinate must be a finite number',
    naming neither file), 1e300 the writer (exit 1). Refused at reading, naming the checkpoint."""
    from linkagekit.synthesis.autosave import Best, Checkpoint, Saved

    path = str(tmp_path / "ck.npz")
    dims = {"watt2": 3}.__getitem__
    Checkpoint(path, "k", dims, 2).save(
        Saved(1.0, [3], ["watt2"], [(0.2, np.ones(3))], None, [Best(np.array([0.0, bad, 1.0]), 0.1, 1, 9, 1.0)], 1)
    )
    with pytest.raises(InputError, match=r"ck\.npz: not a usable linkagekit checkpoint \(array best_x_0 holds"):
        Checkpoint(path, "k", dims, 2).load()


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="no /proc here")
@pytest.mark.parametrize("topology", ["auto", "fourbar"])
def test_a_checkpoint_that_cannot_be_written_is_refused_before_the_search(tmp_path, capsys, topology) -> None:  # type: ignore[no-untyped-def]
    """``--checkpoint /proc/ck.npz``: the first save failed after the screen (exit 1, 1.6 s in; a review)."""
    csv = tmp_path / "t.csv"
    csv.write_text("x,y\n0,0\n1,0\n1,1\n0,1\n")
    args = [
        "synthesize",
        str(csv),
        "--topology",
        topology,
        "--checkpoint",
        "/proc/ck.npz",
        "-o",
        str(tmp_path / "o.yaml"),
    ]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--checkpoint /proc/ck.npz: cannot be written" in err


def test_ctrl_c_saves_the_time_used_so_a_resumed_run_keeps_to_its_budget(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """A review: runs killed and resumed took 24-26 s of a 20 s budget: the time since the last checkpoint was not
    counted. On Ctrl-C the time used is saved (the work of the round under way is lost, not its time)."""
    import time as clock

    from linkagekit.synthesis import auto, autosave

    monkeypatch.setattr(autosave, "ROUND_SECONDS", 0.3)
    monkeypatch.setattr(auto, "ROUND_SECONDS", 0.3)
    real, calls = auto.local_searches, []

    def interrupted(projs, seeds, starts, seconds, workers, tick=None):  # type: ignore[no-untyped-def]
        calls.append(seconds)
        if len(calls) == 2:
            clock.sleep(0.5)  # half a second into the second round
            raise KeyboardInterrupt
        return real(projs, seeds, starts, seconds, workers, tick)

    monkeypatch.setattr(auto, "local_searches", interrupted)
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    T, path = np.stack([np.cos(t), 0.6 * np.sin(t)], 1), str(tmp_path / "run.npz")
    t0 = clock.monotonic()
    with pytest.raises(KeyboardInterrupt):
        auto.synthesize_auto(T, max_joints=5, seconds=2.0, seed=4, workers=1, checkpoint=path)
    took = clock.monotonic() - t0
    make = auto.Maker(T, "m", False, (("min_transmission", 20.0),))
    ck = auto._checkpoint(
        path, make, enumerate_topologies(5), (T, "m", False, {"min_transmission": 20.0}, 5, 4, "local")
    )
    saved = ck.load()
    # the interrupted round's time counted (the 0.5 s slept in it): less only by the setup before the run's clock
    # and the checkpoint's write after it, which on a busy machine took 0.056 s
    assert saved.rounds == 1 and took - 0.3 <= saved.elapsed <= took
