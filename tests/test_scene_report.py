"""The scene (what both drawings read) and the report page's file, without a browser.

The scene must hold exactly what the solver returned (positions to the bit, gaps where it
does not assemble), guides must carry their joints at every sample, and the page must be
self-contained, small, and hold the Result's own columns.  The page in a real browser is
tested in tests/test_report_browser.py.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import yaml

import linkagekit as lk
from linkagekit.cli import main
from linkagekit.viz.scene import broken_at_wraps, build_scene

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "examples"


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


@pytest.mark.parametrize(
    "name", ["seed000_fourbar", "jansen_leg", "slider_crank", "seed003_ex21", "seed001_stephenson"]
)
def test_scene_holds_the_results_positions_exactly(name):
    res = lk.analyze(lk.load(EX / f"{name}.yaml"))
    sc = build_scene(res)
    for k, j in enumerate(sc.joints):
        np.testing.assert_array_equal(sc.xy[:, k], res.xy(j))
    np.testing.assert_array_equal(sc.assembled, res.assembled)
    # gaps are exactly the runs of not-assembled samples
    bad = np.zeros(sc.n, bool)
    for a, b in sc.gaps:
        assert a <= b and not bad[a : b + 1].any()
        bad[a : b + 1] = True
    np.testing.assert_array_equal(bad, ~res.assembled)
    doc = json.loads(json.dumps(sc.to_dict(), allow_nan=False))
    for col, values in res.columns().items():
        got = np.array([np.nan if v is None else v for v in doc["columns"][col]], dtype=float)
        np.testing.assert_array_equal(got, np.asarray(values, float))


def test_gaps_of_seed003_match_its_assembly_range():
    res = lk.analyze(lk.load(EX / "seed003_ex21.yaml"))
    sc = build_scene(res)
    x = sc.inputs["crank"]
    # hand value (docs/seed-errata.md): assembles for crank in [86.782730, 273.217270] deg
    assert sc.gaps == ((0, int(np.flatnonzero(x > 86.78273)[0]) - 1), (int(np.flatnonzero(x < 273.21727)[-1]) + 1, 360))


def test_shading_is_the_exact_range_not_the_samples():
    """The grey bands were drawn from the assembled sample before a gap to the one after (over [60, 300] on a range
    ending at 61.59 and 298.41) and not at all for a gap no sample landed in (review 17b); they are now the
    complement of the exact assembly range over the sweep. Hand value for seed003 (docs/seed-errata.md): assembles
    for crank in [86.782730, 273.217270] deg; the gap four-bar does not assemble in (177.1351, 182.8649) deg."""
    sc = build_scene(lk.analyze(lk.load(EX / "seed003_ex21.yaml"), {"crank": np.arange(0.0, 361.0, 10.0)}))
    assert sc.exact_shading is not None and len(sc.shaded) == 2
    np.testing.assert_allclose(sc.shaded, [[0.0, 86.78273], [273.21727, 360.0]], rtol=0, atol=1e-5)
    gap = yaml.safe_load((EX / "seed000_fourbar.yaml").read_text())
    gap["joints"] = {
        "O1": [0, 0],
        "O2": [4.0, 0],
        "A": [0.0, 1.0],
        "B": [2.3433708590359985, 1.8709839361439946],
        "P": [1.1273076558555206, 2.2724690365779163],
    }
    gap["links"] = {"ground": ["O1", "O2"], "crank": ["O1", "A"], "coupler": ["A", "B", "P"], "rocker": ["O2", "B"]}
    gap["drivers"] = [{"link": "crank", "pivot": "O1", "toward": "A"}]
    for k in ("loads", "gravity"):
        gap.pop(k, None)
    res = lk.analyze(lk.Mechanism.from_dict(gap), {"crank": np.arange(5.0, 366.0, 10.0)})
    sc = build_scene(res)
    assert res.assembled.all() and sc.gaps == () and sc.breaks == (17,)
    np.testing.assert_allclose(sc.shaded, [[177.1351, 182.8649]], rtol=0, atol=1e-4)
    doc = json.loads(json.dumps(sc.to_dict(), allow_nan=False))
    assert doc["shaded_exact"] is True and np.allclose(doc["shaded"], sc.shaded)
    timed = build_scene(lk.simulate(lk.load(EX / "slider_crank.yaml"), np.linspace(0.0, 0.1, 5)))
    assert timed.exact_shading is None and timed.shaded == ()


def test_coupler_curves_are_the_joints_off_the_ground():
    kinds = {
        "seed000_fourbar": ("P",),
        "jansen_leg": ("W", "F"),
        "slider_crank": (),
        "seed003_ex21": ("P",),
    }
    for name, want in kinds.items():
        sc = build_scene(lk.analyze(lk.load(EX / f"{name}.yaml")))
        assert sc.coupler_curves == want, name
        assert not set(sc.coupler_curves) & set(sc.other_paths)
        assert set(sc.coupler_curves) | set(sc.other_paths) | set(sc.ground_joints) == set(sc.joints)


def test_link_kinds_and_plate_outlines():
    sc = build_scene(lk.analyze(lk.load(EX / "jansen_leg.yaml")))
    kinds = {ln.name: ln.kind for ln in sc.links}
    assert kinds == {
        "ground": "ground",
        "crank": "bar",
        "link_j": "bar",
        "link_k": "bar",
        "upper": "plate",
        "link_c": "bar",
        "link_f": "bar",
        "foot": "plate",
    }
    mech = lk.load(EX / "jansen_leg.yaml")
    for ln in sc.links:
        assert sorted(ln.outline) == sorted(mech.link(ln.name).joints)


def test_a_plate_outline_is_a_simple_polygon():
    # four joints given in a crossing order: the outline must go round them
    d = {
        "joints": {"O": [0, 0], "A": [1, 0], "B": [3, 0], "C": [2, 1], "D": [2, 2], "E": [3, 2]},
        "links": {"ground": ["O", "B"], "crank": ["O", "A"], "plate": ["A", "E", "C", "D"], "rocker": ["B", "E"]},
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
    }
    sc = build_scene(lk.analyze(lk.Mechanism.from_dict(d), [0.0]))
    outline = next(ln.outline for ln in sc.links if ln.name == "plate")
    pts = np.array([d["joints"][j] for j in outline], float)
    c = pts.mean(axis=0)
    ang = np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0])
    assert np.all(np.diff(ang) > 0)  # counter-clockwise about the centroid: no self-crossing


def test_a_fixed_guide_carries_its_joint():
    res = lk.analyze(lk.load(EX / "slider_crank.yaml"))
    sc = build_scene(res)
    (sl,) = sc.sliders
    assert sl.on == "ground" and sl.through == "B"
    b = res.xy("B")
    # the file: B slides along the x axis through (0.115, 0)
    np.testing.assert_allclose(sl.direction, np.tile([1.0, 0.0], (sc.n, 1)), atol=1e-15)
    np.testing.assert_allclose(_cross(sl.direction, b - sl.origin), 0, atol=1e-12)
    t = np.einsum("ij,ij->i", b - sl.origin, sl.direction)
    assert sl.span[0] < t.min() and t.max() < sl.span[1]


def test_a_guide_on_a_rocker_turns_with_it():
    # inverted slider-crank: the block at A slides on the rocker Q-R along the line Q-A
    d = {
        "joints": {"O": [0, 0], "A": [0, 1], "Q": [3, 0], "R": [3, 2]},
        "links": {"ground": ["O", "Q"], "crank": ["O", "A"], "block": ["A"], "rocker": ["Q", "R"]},
        "sliders": [{"link": "block", "on": "rocker", "through": "A", "direction": [-3, 1]}],
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
    }
    res = lk.analyze(lk.Mechanism.from_dict(d), np.linspace(0, 360, 73))
    assert res.assembled.all()
    (sl,) = build_scene(res).sliders
    q, a, r = res.xy("Q"), res.xy("A"), res.xy("R")
    # the guide passes through the rocker's pivot Q and the block's joint A at every sample,
    np.testing.assert_allclose(_cross(sl.direction, q - sl.origin), 0, atol=1e-12)
    np.testing.assert_allclose(_cross(sl.direction, a - sl.origin), 0, atol=1e-12)
    # and keeps its angle to the rocker Q->R (atan2(1,-3) - 90 deg in the pose)
    rel = np.arctan2(sl.direction[:, 1], sl.direction[:, 0]) - np.arctan2(r[:, 1] - q[:, 1], r[:, 0] - q[:, 0])
    want = math.atan2(1, -3) - math.pi / 2
    np.testing.assert_allclose(np.angle(np.exp(1j * (rel - want))), 0, atol=1e-12)


def test_plots_follow_what_the_result_has():
    kin = build_scene(lk.analyze(lk.load(EX / "seed000_fourbar.yaml")))
    assert [p.title for p in kin.plots] == [
        "Link angles",
        "Angular velocities",
        "Angular accelerations",
        "Joint speeds",
    ]
    dyn = build_scene(lk.analyze(lk.load(EX / "slider_crank.yaml")))
    titles = {p.title: p for p in dyn.plots}
    assert titles["Driver torques"].series == ("T[crank]",)
    assert len(titles["Bearing loads"].series) == 4
    res = lk.analyze(lk.load(EX / "slider_crank.yaml"))
    np.testing.assert_allclose(dyn.columns["|v|[A]"], np.hypot(*res.vxy("A").T), rtol=1e-15)
    for p in dyn.plots:
        assert all(s in dyn.columns and dyn.units[s] for s in p.series)


def test_an_angle_is_broken_where_it_wraps_not_joined():
    x = np.arange(6.0)
    y = np.array([170.0, 178.0, -176.0, -170.0, np.nan, -160.0])
    xb, yb = broken_at_wraps(x, y, 360.0)
    assert np.isnan(yb[2]) and np.isnan(xb[2]) and len(yb) == 7
    np.testing.assert_array_equal(yb[[0, 1, 3, 4, 6]], [170.0, 178.0, -176.0, -170.0, -160.0])
    np.testing.assert_array_equal(broken_at_wraps(x, y, None)[1], y)  # not an angle: unchanged


def test_a_batch_is_refused_with_a_clear_error():
    mech = lk.load(EX / "seed000_fourbar.yaml")
    res = lk.analyze(mech, [0.0, 10.0], poses=np.stack([mech.pose_array()] * 2))
    with pytest.raises(lk.InputError, match="design"):
        build_scene(res)
    build_scene(res.design(1))  # one design of it is fine


# ---------------------------------------------------------------------- the page file
def _scene_of(page: str) -> dict:
    m = re.search(r'<script type="application/json" id="lk-scene">(.*?)</script>', page, re.S)
    assert m
    return json.loads(m.group(1))


def test_report_is_self_contained_small_and_holds_the_results_columns(tmp_path):
    out = tmp_path / "r.html"
    assert main(["report", str(EX / "seed000_fourbar.yaml"), "-o", str(out)]) == 0
    page = out.read_text(encoding="utf-8")
    assert out.stat().st_size < 1_000_000  # the issue: under 1 MB for a 361-sample four-bar
    # nothing to fetch: no src/href attribute, no url(), no @import, no http(s) address but
    # the SVG namespace (an identifier, never fetched)
    assert not re.search(r"\b(src|href)\s*=", page.replace("a.href = URL.createObjectURL", ""))
    assert "url(" not in page and "@import" not in page
    assert set(re.findall(r"https?://[^\s\"'<>)]+", page)) <= {"http://www.w3.org/2000/svg"}
    doc = _scene_of(page)
    res = lk.analyze(lk.load(EX / "seed000_fourbar.yaml"))
    assert doc["n"] == res.n == 361
    for col, values in res.columns().items():
        got = np.array([np.nan if v is None else v for v in doc["columns"][col]], dtype=float)
        np.testing.assert_array_equal(got, np.asarray(values, float))
    # the page shows the file itself and the checks with the solve plan
    assert "Romero-Nunez" in page and "Solve plan" in page
    assert page.count('data-role="input"') == 1


def test_report_of_two_drivers_has_a_range_each(tmp_path):
    out = tmp_path / "r.html"
    assert main(["report", str(EX / "fivebar_two_drivers.yaml"), "-o", str(out)]) == 0
    page = out.read_text(encoding="utf-8")
    assert re.findall(r'data-role="input" data-driver="(\w+)"', page) == ["crank1", "crank2"]


def test_report_escapes_what_the_file_says(tmp_path):
    src = (EX / "seed000_fourbar.yaml").read_text()
    evil = "</script><script>alert(1)</script><b>x</b> & co"
    bad = tmp_path / "evil.yaml"
    bad.write_text(re.sub(r"^name: .*$", "name: " + json.dumps(evil), src, count=1, flags=re.M))
    out = tmp_path / "r.html"
    assert main(["report", str(bad), "-o", str(out)]) == 0
    page = out.read_text()
    assert "<script>alert(1)" not in page and "<b>x</b>" not in page
    assert _scene_of(page)["name"] == evil  # the JSON still reads back exactly
    assert page.count("<script") == 2


@pytest.mark.parametrize(
    "argv, words",
    [
        (["report", "examples/seed000_fourbar.yaml", "-o", "out.txt"], ".html"),
        (["report", "examples/seed000_fourbar.yaml"], "-o"),
        (["report", "nope.yaml", "-o", "out.html"], "nope.yaml"),
        (["report", "examples/seed000_fourbar.yaml", "-o", "out.html", "--angles", "0:10:0"], "STEP"),
        (["report", "examples/seed000_fourbar.yaml", "-o", "/nonexistent-dir/out.html"], "cannot write"),
    ],
)
def test_report_bad_arguments_exit_2_with_one_line(argv, words, capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "Traceback" not in err
    assert not (ROOT / "out.html").exists() and not (ROOT / "out.txt").exists()


def test_the_picture_commands_follow_the_branch_through_change_points_when_asked(tmp_path, capsys):
    """``analyze --branch continuous`` kept a parallelogram one, but ``report``, ``plot`` and ``animate`` had no
    ``--branch``: their pictures folded it into a crossed four-bar past 180 deg. The report's columns are now those of
    ``lk.analyze(..., branch="continuous")`` (the coupler keeps its direction: its angle stays the pose's to 1e-9
    deg); without the option, those of the pose's signs (it folds); with ``--time`` the option is refused."""
    path = EX / "seed003_ex22.yaml"
    mech = lk.load(path)
    for branch in ("continuous", "pose"):
        out = tmp_path / f"{branch}.html"
        assert main(["report", str(path), "-o", str(out), "--branch", branch]) == 0
        doc = _scene_of(out.read_text(encoding="utf-8"))
        res = lk.analyze(mech, branch=branch)
        for col, values in res.columns().items():
            got = np.array([np.nan if v is None else v for v in doc["columns"][col]], dtype=float)
            np.testing.assert_array_equal(got, np.asarray(values, float))
        angle = np.array(doc["columns"]["coupler.angle"], dtype=float)
        turned = np.nanmax(np.abs(angle - angle[0]))
        assert (turned < 1e-9) if branch == "continuous" else (turned > 1.0), (branch, turned)
    assert main(["plot", str(path), "-o", str(tmp_path / "p.png"), "--branch", "continuous", "--time", "0:1:0.5"]) == 2
    assert "--branch goes with a sweep" in capsys.readouterr().err


def test_plot_draws_its_at_poses_on_the_sweeps_branch(tmp_path, monkeypatch):
    """``plot --branch continuous --at`` drew the sweep as a parallelogram but its ``--at`` poses on the pose's signs
    (folded past the flat position): the poses are now ``lk.analyze(..., branch=...)``'s, for either branch."""
    from linkagekit.viz import draw

    path = EX / "seed003_ex22.yaml"
    mech = lk.load(path)
    drawn = {}

    def capture(res, poses=None, **kw):
        drawn["poses"] = poses
        raise SystemExit(0)  # the figure itself is not needed

    monkeypatch.setattr(draw, "mechanism_figure", capture)
    name = mech.drivers[0].name
    sweeps = {branch: lk.analyze(mech, branch=branch) for branch in ("continuous", "pose")}
    apart = [np.linalg.norm(sweeps["continuous"].xy(j) - sweeps["pose"].xy(j), axis=-1) for j in mech.joint_names]
    i = int(np.nanargmax(np.nanmax(apart, axis=0)))  # past the flat position, where the branches differ most
    assert np.nanmax(apart, axis=0)[i] > 1.0
    for branch, res in sweeps.items():
        value = float(res.inputs[name][i])
        with pytest.raises(SystemExit):
            main(["plot", str(path), "-o", str(tmp_path / "p.png"), "--branch", branch, "--at", f"{name}={value!r}"])
        want = lk.analyze(mech, {name: [value]}, branch=branch)
        for j in mech.joint_names:
            np.testing.assert_allclose(drawn["poses"].xy(j), want.xy(j), rtol=0, atol=1e-9)
            np.testing.assert_allclose(want.xy(j)[0], res.xy(j)[i], rtol=0, atol=1e-9)  # the sweep's own pose there


def test_a_cylinders_barrel_is_rigid_in_every_picture():
    """The barrel was drawn as 0.55 of the cylinder's current length: 0.99 m retracted, 1.595 m extended (the
    boom's stroke is 1.8..2.9 m, so the drawn barrel was shorter than the stroke). It is now 0.85 of the retracted
    length at every sample (Matplotlib's drawing here; the page reads the same scene value), cut at the rod's end."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from linkagekit.viz.draw import Drawing

    mech = lk.load(ROOT / "examples" / "excavator_boom.yaml")
    boom = next(d for d in mech.drivers if d.name == "boom_cylinder")
    lo, hi = boom.type.stroke
    res = lk.analyze(mech, {"boom_cylinder": np.linspace(lo, hi, 5), "stick_cylinder": 2.9}, rates=False)
    sc = build_scene(res)
    assert next(ln for ln in sc.links if ln.name == "boom_cylinder").barrel == pytest.approx(0.85 * lo, rel=1e-15)
    fig, ax = plt.subplots()
    try:
        drawing = Drawing(ax, sc)
        barrels = [art for ln, art, _ in drawing.links if ln.name == "boom_cylinder" and art.get_linewidth() > 5]
        drawn = []
        for i in range(5):
            drawing.update(i)
            x, y = barrels[0].get_data()
            drawn.append(math.hypot(x[1] - x[0], y[1] - y[0]))
        np.testing.assert_allclose(drawn, 0.85 * lo, rtol=1e-12)  # the same at 1.8 m and at 2.9 m
    finally:
        plt.close(fig)
    page_links = {ln["name"]: ln for ln in json.loads(json.dumps(sc.to_dict()))["links"]}  # what the page draws by
    assert page_links["boom_cylinder"]["barrel"] == pytest.approx(0.85 * lo)


def test_a_link_of_joints_in_line_is_a_bar_and_the_pictures_name_the_ground_pivots():
    """seed004's input link A-C-D (lengths 2 + 3 = 5: in line) was a plate of no area, drawn as a pale ghost (a
    plate's 0.35 alpha on an outline of no area); ``plot``'s PNG left the ground pivots unnamed, where the page
    names them."""
    import matplotlib

    matplotlib.use("Agg")
    from linkagekit.viz.draw import mechanism_figure

    mech = lk.load(ROOT / "examples" / "seed004_stephenson1.yaml")
    res = lk.analyze(mech, {"input": np.linspace(0, 360, 37)}, rates=False)
    links = {ln.name: ln for ln in build_scene(res).links}
    assert links["input"].kind == "bar" and links["input"].outline == ("A", "D", "C")  # its ends first
    assert links["coupler"].kind == "plate" and links["ternary"].kind == "plate"
    # decided by the link's rigid shape (the file's exact lengths), not the pose's digits (a review's two cases)
    from linkagekit.viz.scene import scene_links

    triangle, in_line = mech.to_dict(), mech.to_dict()
    triangle["links"]["input"]["lengths"]["A-D"] = 4.9  # the pose in line, the lengths a triangle
    in_line["joints"]["D"] = [2.6, 4.2]  # the pose off the line, the lengths 2 + 3 = 5 in line
    for doc, kind in ((triangle, "plate"), (in_line, "bar")):
        drawn = {ln.name: ln.kind for ln in scene_links(lk.Mechanism.from_dict(doc))}
        assert drawn["input"] == kind
    # Whitworth's lever, 0.15 + 0.32 = 0.47: its shape off the line by the square root of rounding (6e-9 of its
    # extent) was still a pale plate in the pictures and the animation (review of the docs' pictures)
    whitworth = {ln.name: ln for ln in scene_links(lk.load(ROOT / "examples" / "whitworth_quick_return.yaml"))}
    assert whitworth["lever"].kind == "bar" and set(whitworth["lever"].outline[:2]) == {"B", "L"}
    fig = mechanism_figure(res)
    ax = fig.axes[0]
    assert {"A", "B"} <= {t.get_text() for t in ax.texts if t.get_visible()}
    drawn = [p for p in ax.patches if p.get_visible() and np.ptp(p.get_xy(), axis=0).max() > 0]
    assert len([p for p in drawn if 0.3 < p.get_facecolor()[3] < 0.4]) == 2  # the coupler and the ternary


@pytest.mark.parametrize("bad", ["x", 3, [1], [[0, 1, 2]], [[0, float("nan")]], [[5, 1]]])
def test_build_scene_refuses_a_malformed_input_range_with_a_linkage_error(bad) -> None:  # type: ignore[no-untyped-def]
    """Review 18b: a malformed ``input_range`` raised ValueError or TypeError from inside the scene; it is an
    InputError naming the argument. An empty one (a mechanism that assembles nowhere) is taken."""
    import linkagekit as lk

    res = lk.analyze(lk.load(EX / "seed000_fourbar.yaml"), {"crank": np.arange(0, 360, 10.0)})
    with pytest.raises(lk.InputError, match=r"^input_range: expected a list of \[start, stop\] pairs"):
        lk.build_scene(res, input_range=bad)
    assert lk.build_scene(res, input_range=[]).name == res.mechanism.name


def test_report_refuses_a_sweep_longer_than_a_page_naming_the_option_before_any_work(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    """Review 18b: ``report --angles 0:360:0.01`` said '36001 samples, more than a report page holds (10000)',
    naming neither ``--angles`` nor the file, after the whole analysis. It names the option, before it."""
    from unittest import mock

    from linkagekit.cli import main

    out = tmp_path / "r.html"
    with mock.patch("linkagekit.analyze", side_effect=AssertionError("analysed")):
        code = main(["report", str(EX / "seed000_fourbar.yaml"), "--angles", "0:360:0.01", "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("linkagekit: error: --angles: 36001 samples, more than a report page holds")
    assert not out.exists()


@pytest.mark.parametrize(
    "name, sweep", [("seed003_ex21.yaml", None), ("nongrashof_rocker.yaml", np.arange(-90.0, 90.5, 1.0))]
)
def test_paths_run_on_to_the_dead_points(name, sweep):
    """Paths stopped at the last sample inside the range, not at the dead point `check` gives: next to a toggle
    the joints move fastest, and seed 003's P was 11 px short at either end, the non-Grashof rocker's D 48 px
    (review 19f). Each path now ends at the joints' positions at the range's ends, solved on their own (to the
    square root of the hair the end is taken inside the range: positions go as the root of the distance to a
    fold), and no segment crosses the range's gap."""
    from linkagekit.viz.scene import build_scene

    mech = lk.load(EX / name)
    res = lk.analyze(mech, None if sweep is None else {"crank": sweep})
    sc = build_scene(res)
    lo, hi = lk.check(mech).input_range[0]
    ends = lk.analyze(mech, {"crank": [lo + 1e-9, hi - 1e-9]}, rates=False)
    size = np.ptp(sc.xy[..., 0][np.isfinite(sc.xy[..., 0])])
    for j in (*sc.coupler_curves, *sc.other_paths):
        p = sc.path_xy[:, sc.index(j)]
        drawn = p[np.all(np.isfinite(p), axis=1)]
        got = {tuple(np.round(drawn[k], 12)) for k in (0, -1)}
        want = ends.xy(j)
        for w in want:  # each end of the range is an end of the drawn path
            assert min(np.hypot(*(np.array(g) - w)) for g in got) < 1e-4 * size, (j, got, want)
        samples = sc.xy[:, sc.index(j)]
        inside = samples[np.all(np.isfinite(samples), axis=1)]
        assert len(drawn) == len(inside) + 2  # the samples inside the range, and its two ends
    assert sc.to_dict()["paths"] is not None and len(sc.to_dict()["path_breaks"]) == len(sc.path_breaks)


SMALL_GAP = {  # crank 2, coupler 2.99, rocker 3, ground 4: it does not assemble for crank in (172.98, 187.02) deg
    "format": "linkagekit/1",
    "name": "small gap",
    "units": {"length": "m", "angle": "deg"},
    "joints": {"A": [0, 0], "B": [4, 0], "C": [1.0, 1.7320508075688772], "D": [3.714189139887952, 2.9863543246309563]},
    "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D"], "rocker": ["B", "D"]},
    "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
}


@pytest.mark.parametrize("branch", ["pose", "continuous"])
def test_paths_to_the_ends_follow_the_sweeps_way_and_branch(branch):
    """Review 19g: with the branch followed continuously every picture failed ('signs: D needs a number'), the
    signs per sample not passed as such; a sweep going down put the two ends of a gap between two samples in the
    ascending order, so each was drawn as a lone point. The crank's end C at the gap's ends, by hand: C = 2 e^(i t)
    (t = 187.02 deg, then 172.98)."""
    mech = lk.Mechanism.from_dict(SMALL_GAP)
    lo, hi = lk.check(mech).input_range[0]  # [-172.98, 172.98]: through 0
    res = lk.analyze(mech, {"crank": np.arange(210.0, 149.0, -20.0)}, branch=branch)
    sc = build_scene(res)
    C = sc.path_xy[:, sc.index("C")]
    angles = np.degrees(np.arctan2(C[:, 1], C[:, 0])) % 360
    assert angles == pytest.approx([210.0, 190.0, lo + 360, hi, 170.0, 150.0], abs=1e-6)
    assert sc.path_breaks == (2,)  # only the segment across the gap
    assert np.hypot(*C[2]) == pytest.approx(2.0, abs=1e-12) and np.hypot(*C[3]) == pytest.approx(2.0, abs=1e-12)
