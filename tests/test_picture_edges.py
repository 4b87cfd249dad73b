"""Edge cases of the pictures and the page, found by an independent review (each failed before its fix).

* a plot whose values are constant up to round-off hung the page's tick loop;
* long sweeps overflowed ``Math.min.apply`` in the page;
* names with ``$`` were read as mathematics by matplotlib (a crash, or a different name);
* the GIF palette came from the first frame only (links drawn grey, a flickering background);
* plots ran along the first driver even when it was held still;
* two samples on either side of a gap no sample landed in were joined by a line;
* wrong argument types escaped as AttributeError/TypeError; long sweeps ran out of memory.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import linkagekit as lk
from linkagekit.cli import main
from linkagekit.viz import draw
from linkagekit.viz.scene import build_scene

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "examples"

CRANK_ONLY = {
    "name": "a crank alone",
    "joints": {"A": [0, 0], "C": [0.3, 0.4]},
    "links": {"ground": ["A"], "crank": ["A", "C"]},
    "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
}
SLIDER_DRIVEN = {
    "name": "slider driven",
    "joints": {"O": [0, 0], "A": [0.03, 0.04], "B": [0.115, 0.0]},
    "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B"], "block": ["B"]},
    "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0]}],
    "drivers": [{"slider": 0, "displacements": {"start": -0.05, "stop": 0.05, "step": 0.001}}],
}


# ---------------------------------------------------------------------- gaps between samples
def test_a_gap_between_two_samples_breaks_the_curves():
    mech = lk.Mechanism.from_dict(SLIDER_DRIVEN)
    # the block cannot reach x in (O-rod..) : check says where it does not assemble
    ranges = lk.check(mech).input_range
    assert len(ranges) == 2, ranges
    gap = (ranges[0][1], ranges[1][0])
    # a sweep whose samples straddle the gap without landing in it
    lo, hi = gap[0] - 0.3 * (gap[1] - gap[0]), gap[1] + 0.3 * (gap[1] - gap[0])
    res = lk.analyze(mech, {"block": np.array([lo - 0.01, lo, hi, hi + 0.01])})
    assert res.assembled.all()
    sc = build_scene(res)
    assert sc.breaks == (1,)
    # the matplotlib line has a hole there; the fine sweep has none (its gap has samples)
    fig = draw.quantities_figure(sc, [["rod.angle"]])
    (line,) = fig.axes[0].lines
    assert np.isnan(np.asarray(line.get_ydata(), float)).sum() == 1
    assert build_scene(lk.analyze(mech)).breaks == ()


def test_no_breaks_on_a_full_turn_and_on_a_sweep_inside_the_range():
    assert build_scene(lk.analyze(lk.load(EX / "jansen_leg.yaml"), {"crank": [0, 90, 180, 270, 360]})).breaks == ()
    s3 = lk.load(EX / "seed003_ex21.yaml")  # assembles for crank in [86.78, 273.22]
    assert build_scene(lk.analyze(s3, {"crank": [90.0, 180.0, 270.0]})).breaks == ()
    # 270 -> 450 (= 90 next turn) crosses the gap [273.2, 446.8]
    assert build_scene(lk.analyze(s3, {"crank": [180.0, 270.0, 450.0]})).breaks == (1,)
    # and 450 -> 500 lies in the next turn's range
    assert build_scene(lk.analyze(s3, {"crank": [450.0, 500.0]})).breaks == ()


# ---------------------------------------------------------------------- the driver the plots use
def test_plots_run_along_the_driver_that_moves():
    mech = lk.load(EX / "fivebar_two_drivers.yaml")
    inputs = {"crank1": np.full(37, 30.0), "crank2": np.linspace(0, 360, 37)}
    res = lk.analyze(mech, inputs)
    sc = build_scene(res)
    assert sc.x_driver == "crank2"
    fig = draw.quantities_figure(sc, [["link1.angle"]])
    (line,) = fig.axes[0].lines
    x = np.asarray(line.get_xdata(), float)
    x = x[np.isfinite(x)]  # wraps of the angle insert NaN points
    np.testing.assert_array_equal(x, inputs["crank2"])
    assert fig.axes[0].get_xlabel().startswith("crank2")


# ---------------------------------------------------------------------- names as text
@pytest.mark.parametrize("name", [r"pay $\bad{$ now", "$x_1$ and $", "点四连杆机构"])
def test_names_are_drawn_as_written(tmp_path, name, capsys):
    d = dict(lk.load(EX / "seed000_fourbar.yaml").to_dict(), name=name)
    path = tmp_path / "m.yaml"
    lk.save(lk.Mechanism.from_dict(d), path)
    for argv in (
        ["plot", str(path), "-o", str(tmp_path / "a.png")],
        ["plot", str(path), "--modes", "--at", "30", "-o", str(tmp_path / "b.png")],
        ["plot", str(path), "-q", "angles", "-o", str(tmp_path / "c.png")],
        ["animate", str(path), "--frames", "36", "-o", str(tmp_path / "d.gif")],
    ):
        assert main(argv) == 0, argv
        assert capsys.readouterr().err == ""  # no glyph warnings on stderr either
    fig = draw.mechanism_figure(lk.analyze(lk.Mechanism.from_dict(d)))
    fig.canvas.draw()  # renders
    shown = fig._suptitle.get_text().replace(r"\$", "$")
    assert shown.startswith(name)


# ---------------------------------------------------------------------- GIF colours
def test_gif_keeps_every_colour_and_a_white_background(tmp_path):
    from PIL import Image

    out = tmp_path / "s3.gif"
    # the first frame does not assemble (no link drawn in it)
    assert main(["animate", str(EX / "seed003_ex21.yaml"), "--frames", "36", "-o", str(out)]) == 0
    im = Image.open(out)
    crank_blue = np.array([int(draw.PALETTE[0][k : k + 2], 16) for k in (1, 3, 5)])
    seen_blue = 0
    for k in range(im.n_frames):
        im.seek(k)
        rgb = np.asarray(im.convert("RGB"), int)
        assert (rgb[5, 5] == 255).all(), (k, rgb[5, 5])  # the corner is white in every frame
        seen_blue += int((np.abs(rgb - crank_blue).sum(axis=-1) < 30).sum() > 50)
    # the crank (first link colour) is drawn in its colour in the frames where it assembles
    res = lk.analyze(lk.load(EX / "seed003_ex21.yaml"), {"crank": np.linspace(0, 360, 36)})
    assert seen_blue == int(res.assembled.sum()) > 10


def test_gif_fps_above_50_is_refused_mp4_not(tmp_path, capsys):
    argv = ["animate", str(EX / "seed000_fourbar.yaml"), "--frames", "36", "--fps", "60"]
    assert main([*argv, "-o", str(tmp_path / "a.gif")]) == 2
    assert "50" in capsys.readouterr().err
    assert main([*argv, "-o", str(tmp_path / "a.mp4")]) == 0


def test_too_many_frames_is_refused_before_drawing(tmp_path, capsys):
    argv = ["animate", str(EX / "seed000_fourbar.yaml"), "--angles", "0:360:0.1", "-o", str(tmp_path / "a.gif")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--frames" in err
    assert not (tmp_path / "a.gif").exists()


def test_an_ffmpeg_that_cannot_run_is_named(tmp_path, monkeypatch, capsys):
    fake = tmp_path / "ffmpeg"
    fake.write_text("not a program")
    fake.chmod(0o755)
    monkeypatch.setattr("linkagekit.viz.animate.find_ffmpeg", lambda: str(fake))
    assert main(["animate", str(EX / "seed000_fourbar.yaml"), "--frames", "36", "-o", str(tmp_path / "a.mp4")]) == 1
    err = capsys.readouterr().err
    assert "cannot run ffmpeg" in err and err.count("\n") == 1
    assert not (tmp_path / "a.mp4").exists()


# ---------------------------------------------------------------------- limits and arguments
def test_modes_figure_has_a_panel_limit(tmp_path, capsys):
    joints = {"G0": [0.0, 0.0], "J0": [0.3, 1.0]}
    links = {"crank": ["G0", "J0"]}
    ground = ["G0"]
    for k in range(1, 8):  # seven loops of distinct sizes: 2^7 = 128 distinct modes
        joints[f"G{k}"] = [1.0 * k, 0.0]
        joints[f"J{k}"] = [1.0 * k + 0.3 + 0.05 * k, 1.0 + 0.1 * k]
        links[f"c{k}"] = [f"J{k - 1}", f"J{k}"]
        links[f"r{k}"] = [f"G{k}", f"J{k}"]
        ground.append(f"G{k}")
    links["ground"] = ground
    mech = lk.Mechanism.from_dict(
        {"joints": joints, "links": links, "drivers": [{"link": "crank", "pivot": "G0", "toward": "J0"}]}
    )
    at = float(np.degrees(math.atan2(1.0, 0.3)))
    n = lk.modes(mech, at=at).distinct
    assert n > draw.MAX_MODE_PANELS
    with pytest.raises(lk.InputError, match="more than a figure shows"):
        draw.modes_figure(mech, at)


def test_report_sample_limit(tmp_path, capsys):
    argv = ["report", str(EX / "seed000_fourbar.yaml"), "--angles", "0:360:0.01", "-o", str(tmp_path / "r.html")]
    assert main(argv) == 2
    assert "more than a report page holds" in capsys.readouterr().err


@pytest.mark.parametrize(
    "call",
    [
        lambda res: lk.draw_mechanism(None, res),
        lambda res: lk.draw_mechanism(_ax(), res, at="abc"),
        lambda res: lk.draw_mechanism(_ax(), res, at=[1, 2]),
        lambda res: lk.draw_mechanism(_ax(), res, at=float("nan")),
        lambda res: lk.draw_mechanism(_ax(), res, at=1e9),
        lambda res: lk.plot_quantity(_ax(), res, ["x"]),
        lambda res: lk.plot_quantity(_ax(), res, "coupler.omega", period="x"),
        lambda res: lk.plot_quantity(None, res, "coupler.omega"),
        lambda res: lk.animate(res, None),
        lambda res: lk.animate(res, "a.gif", progress=5),
        lambda res: lk.write_report(res, None),
        lambda res: lk.write_report(res, "a.html", source=5),
        lambda res: lk.write_report(res, "a.html", title=5),
        lambda res: lk.build_scene({"not": "a result"}),
    ],
)
def test_wrong_arguments_raise_linkage_errors(call, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    res = lk.analyze(lk.load(EX / "seed000_fourbar.yaml"))
    with pytest.raises(lk.LinkageError) as info:
        call(res)
    assert str(info.value) and "\n" not in str(info.value)
    assert not list(tmp_path.iterdir())


def test_numpy_numbers_are_numbers(tmp_path):
    res = lk.analyze(lk.load(EX / "seed000_fourbar.yaml"), {"crank": [0.0, 90.0]})
    lk.animate(res, tmp_path / "a.gif", fps=np.float32(10), dpi=np.int64(40), size=np.float64(3))
    ax = _ax()
    assert lk.draw_mechanism(ax, res, at=np.float64(90.0)) is ax


def test_drawing_between_samples_says_which_sample_it_shows():
    """``draw_mechanism(at=178)`` on a 10-degree sweep drew the sample at 175 deg with no word, where the mechanism
    of review 17b does not assemble at 178; the note now says which input is drawn."""
    res = lk.analyze(lk.load(EX / "seed000_fourbar.yaml"), {"crank": [0.0, 90.0, 180.0]})
    for at, note in ((90.0, ""), (100.0, "the nearest sample, crank = 90 deg (asked 100 deg)")):
        ax = lk.draw_mechanism(_ax(), res, at=at)
        texts = [t.get_text() for t in ax.texts if "sample" in t.get_text() or "assemble" in t.get_text()]
        assert texts == ([note] if note else []), texts


def _ax():
    from matplotlib.figure import Figure

    return Figure().add_subplot()


def test_a_mechanism_that_never_assembles_draws_its_ground(tmp_path):
    from PIL import Image

    out = tmp_path / "never.png"
    assert main(["plot", str(EX / "seed003_ex21.yaml"), "--angles", "0:80:5", "-o", str(out)]) == 0
    img = Image.open(out)
    sx, tx, sy, ty = __import__("json").loads(img.text[draw.TRANSFORM_KEY])
    rgb = np.asarray(img.convert("RGB"), int)
    mech = lk.load(EX / "seed003_ex21.yaml")
    for j in mech.link("ground").joints:
        z = mech.joints[j]
        c, r = round(sx * z.real + tx), round(sy * z.imag + ty)
        patch = rgb[r - 6 : r + 7, c - 6 : c + 7]
        assert (patch.sum(axis=-1) < 200).sum() > 10, j  # a black pin ring


def test_crank_alone_report_scene_has_a_constant_speed_plot():
    res = lk.analyze(lk.Mechanism.from_dict(CRANK_ONLY))
    sc = build_scene(res)
    v = sc.columns["|v|[C]"]
    assert np.ptp(v) < 1e-12 and np.ptp(v) > 0  # constant up to round-off: the case that hung the page


def test_a_long_name_is_a_title_of_several_lines_within_the_picture():
    """At 800 px a long name was one title line cut off on both sides. It is broken into lines that fit: every line
    of the drawn title lies inside the figure."""
    import yaml as _yaml
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from linkagekit.viz import draw

    doc = _yaml.safe_load((Path(__file__).resolve().parents[1] / "examples" / "seed000_fourbar.yaml").read_text())
    doc["name"] = "A rather long mechanism name that a user might write to describe the four-bar of a packaging machine"
    fig = draw.mechanism_figure(lk.analyze(lk.Mechanism.from_dict(doc)), pixels=(800, None))
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    title = fig._suptitle
    box = title.get_window_extent(canvas.get_renderer())
    assert title.get_text().count("\n") >= 1
    assert box.x0 >= 0 and box.x1 <= fig.bbox.width and box.y1 <= fig.bbox.height
