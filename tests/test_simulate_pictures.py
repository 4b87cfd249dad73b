"""Pictures of a simulated motion, tested like numbers: `plot -q`, `animate` and `report` with `--time`.

The motion is the one `lk.simulate` computes (called here independently of the command line):
the slider-crank of the examples started from rest by the motor T = 3 (1 - w/60), 41 output
times 0, 0.005, ..., 0.2 s (the crank turns about one and a half times, its speed rises
and falls: the time axis and the input axis are far from proportional).

* `plot --time ... -q crank.omega`: the PNG carries the map from (time, value) to pixels
  (``linkagekit:transform``, as the mechanism drawings do); every computed (t, omega) point
  has a line pixel within 2 px and every line pixel is within 3 px of the computed polyline.
  NEGATIVE controls: the same check fails on a blank image, on the transform shifted by 8 px,
  and on the values drawn one output time late;
* `animate --time ...`: one frame per output time; the pixel transform of the frames is fitted
  to the pins found in frames 0 and 20 (`test_animate.fit_transform`, from the picture alone),
  and frames 7 and 33 show their pins where the simulation puts the joints at their times
  (1.5 px). NEGATIVE: the joints of three samples later, or shifted by 6 px, are not there;
* `report --time ...` in Debian's headless chromium: the slider steps through the output
  times (``data-role="time-value"`` = ``repr`` of the time, joints ``repr``-exact), every
  plot's line and cursor are affine in time to 0.01 px (the drawn path) and 0.5 px (the
  cursor) and NOT affine in the input (NEGATIVE control on the same points), Play paces the
  samples by their times, and the page requests nothing and logs no error;
* a motion that meets a toggle: the picture of the motion up to it is written, then one
  line on stderr (the simulation's message), exit status 1; the page says where it stopped.
"""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
import yaml
from PIL import Image
from scipy.spatial import cKDTree

import linkagekit as lk
from linkagekit.cli import main
from linkagekit.viz import draw
from linkagekit.viz.scene import build_scene
from linkagekit.web.report import report_html
from test_animate import fit_transform, gif_frames, pins_missing, to_px

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SLIDER = EXAMPLES / "slider_crank.yaml"
TIME = ["--time", "0:0.2:0.005", "--motor", "3,60"]
TIMES = np.arange(41) * 0.005
LINE_RGB = np.array([0x1F, 0x77, 0xB4], float)  # matplotlib's first colour: a plot of one quantity


@pytest.fixture(scope="module")
def motion():
    """The simulated motion every picture here must show (computed once, independently of the CLI)."""
    res = lk.simulate(lk.load(SLIDER), TIMES, motor=(3.0, 60.0))
    assert res.stopped is None and res.n == 41 and np.all(res.assembled)
    np.testing.assert_allclose(res.time, TIMES, rtol=0, atol=1e-15)
    return res


def _toggle_file(tmp_path: Path) -> Path:
    """Seed 003's four-bar with masses: its crank cannot turn fully, so a torque drives it into a toggle."""
    doc = yaml.safe_load((EXAMPLES / "seed003_ex21.yaml").read_text())
    for name, link in list(doc["links"].items()):
        if name != "ground":
            joints = link if isinstance(link, list) else link["joints"]
            cg = np.mean([doc["joints"][j] for j in joints], axis=0).tolist()
            doc["links"][name] = {"joints": joints, "mass": 1.0, "cg": cg, "inertia": 0.01}
    path = tmp_path / "toggle.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


# --------------------------------------------------------------------------- plot -q over time
def _polyline_px(t: list[float], x: np.ndarray, y: np.ndarray, step: float = 0.5) -> np.ndarray:
    """The pixels (column, row) of the straight segments through the data points, every `step` px."""
    p = np.stack([t[0] * x + t[1], t[2] * y + t[3]], axis=-1)
    out = [p[:1]]
    for a, b in zip(p[:-1], p[1:], strict=True):
        k = max(int(np.ceil(np.linalg.norm(b - a) / step)), 1)
        out.append(a + (b - a) * (np.arange(1, k + 1) / k)[:, None])
    return np.concatenate(out)


def _line_fit(rgb: np.ndarray, t: list[float], x: np.ndarray, y: np.ndarray) -> tuple[float, int]:
    """(share of the polyline's points with a line pixel within 2 px, line pixels farther than 3 px from it)."""
    mask = np.linalg.norm(rgb - LINE_RGB, axis=-1) < 60
    rows, cols = np.nonzero(mask)
    if rows.size == 0:
        return 0.0, 0
    pixels = np.stack([cols + 0.5, rows + 0.5], axis=-1)
    poly = _polyline_px(t, x, y)
    near, _ = cKDTree(pixels).query(poly, distance_upper_bound=2.0)
    stray, _ = cKDTree(poly).query(pixels, distance_upper_bound=3.0)
    return float(np.isfinite(near).mean()), int(np.isinf(stray).sum())


@pytest.fixture(scope="module")
def omega_png(motion, tmp_path_factory):
    out = tmp_path_factory.mktemp("plot") / "omega.png"
    assert main(["plot", str(SLIDER), *TIME, "-q", "crank.omega", "--dpi", "100", "-o", str(out)]) == 0
    im = Image.open(out)
    im.load()
    return np.asarray(im.convert("RGB"), float), json.loads(im.text[draw.TRANSFORM_KEY])


def test_plot_q_draws_the_simulated_column_against_time(motion, omega_png):
    rgb, t = omega_png
    x, y = motion.time, np.asarray(motion.columns()["crank.omega"], float)
    assert np.ptp(y) > 50  # the crank speeds up and slows down: a curve with something to miss
    share, strays = _line_fit(rgb, t, x, y)
    assert share >= 0.98 and strays == 0, (share, strays)
    # NEGATIVE controls: blank, shifted, one output time late
    assert _line_fit(np.full_like(rgb, 255.0), t, x, y)[0] == 0.0
    share, strays = _line_fit(rgb, [t[0], t[1] + 8.0, t[2], t[3]], x, y)
    assert share < 0.7 and strays > 50, (share, strays)
    share, strays = _line_fit(rgb, t, x[1:], y[:-1])
    assert share < 0.8 and strays > 50, (share, strays)


def test_plot_quantity_runs_along_time(motion):
    """The drawn line is (time, column) exactly; the x label says time in seconds."""
    from matplotlib.figure import Figure

    ax = Figure().add_subplot()
    draw.plot_quantity(ax, motion, "input:crank")
    (line,) = ax.get_lines()
    np.testing.assert_array_equal(line.get_xdata(), motion.time)
    np.testing.assert_array_equal(line.get_ydata(), motion.inputs["crank"])
    assert ax.get_xlabel() == "time [s]"
    sc = build_scene(motion)
    assert sc.timed and sc.x_axis == "time" and sc.breaks == ()
    assert sc.sample_text(7) == f"t = {TIMES[7]:.6g} s, crank = {motion.inputs['crank'][7]:.6g} deg"
    assert not build_scene(lk.analyze(lk.load(SLIDER), {"crank": [0.0, 10.0]})).timed


# --------------------------------------------------------------------------- animate
@pytest.fixture(scope="module")
def gif(tmp_path_factory) -> list[np.ndarray]:
    out = tmp_path_factory.mktemp("anim") / "motion.gif"
    assert main(["animate", str(SLIDER), *TIME, "-o", str(out)]) == 0
    return gif_frames(out)


@pytest.mark.parametrize("k", [7, 33])
def test_animation_frames_follow_the_time_axis(motion, gif, k):
    assert len(gif) == motion.n == 41
    mech = motion.mechanism
    q = motion.inputs["crank"]
    fitted = fit_transform(mech, [(gif[0], q[0]), (gif[20], q[20])])

    def at(i: int, shift: float = 0.0) -> dict[str, np.ndarray]:
        return {j: to_px(fitted, complex(*motion.xy(j)[i])) + [shift, 0.0] for j in ("A", "B")}

    assert pins_missing(gif[k], at(k)) == []
    assert len(pins_missing(gif[k], at(k + 3))) >= 1  # NEGATIVE: another time's pose
    assert pins_missing(gif[k], at(k, 6.0)) == ["A", "B"]  # NEGATIVE: shifted


# --------------------------------------------------------------------------- a toggle
def test_a_stopped_motion_is_drawn_up_to_the_toggle_then_exit_1(tmp_path, capsys):
    path = _toggle_file(tmp_path)
    res = lk.simulate(lk.load(path), np.arange(61) * 0.05, torque=2.0)
    assert res.stopped and 2 < res.n < 61
    png, page = tmp_path / "q.png", tmp_path / "r.html"
    for argv, out in ((["plot", "-q", "crank.omega"], png), (["report"], page)):
        assert main([argv[0], str(path), "--time", "0:3:0.05", "--torque", "2", *argv[1:], "-o", str(out)]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert err == [f"linkagekit: {res.stopped}"]
        assert out.stat().st_size > 1000
    text = page.read_text()
    assert f'data-role="stopped">{html.escape(res.stopped)}</p>' in text
    assert f't = 0 to {res.time[-1]:.6g} s, <span data-role="sample-count">{res.n}</span> samples' in text
    assert 'data-role="stopped"' not in report_html(lk.analyze(lk.load(path), {"crank": [120.0]}))


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["plot", "-q", "crank.omega", "--motor", "3,60"], "--motor drives a simulated motion: give --time"),
        (["report", "--speed", "2"], "--speed drives a simulated motion"),
        (["animate", "--time", "0:1:0.1", "--angles", "0:90:10"], "--time draws a simulated motion, --angles"),
        (["plot", "--time", "0:1:0.1", "--at", "30"], "--time draws a simulated motion, not --at"),
        (["plot", "--time", "0:1:0.1", "--modes"], "--time draws a simulated motion, not --modes"),
        (["animate", "--time", "1:0:0.1"], "--time: STEP must be non-zero"),
        (["animate", "--time", "0:10:0.001"], "more frames than an animation takes"),
    ],
)
def test_bad_motion_options_are_one_line_exit_2(tmp_path, capsys, argv, needle):
    out = tmp_path / ("x.gif" if argv[0] == "animate" else "x.html" if argv[0] == "report" else "x.png")
    assert main([argv[0], str(SLIDER), *argv[1:], "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0], err
    assert not out.exists()


# --------------------------------------------------------------------------- the page, in chromium
PAGE_STATE = """
() => {
  const t = document.querySelector('[data-role="time-value"]');
  const joints = {};
  for (const e of document.querySelectorAll('[data-joint]')) joints[e.getAttribute('data-joint')] =
    [e.getAttribute('data-x'), e.getAttribute('data-y')];
  const plots = [...document.querySelectorAll('svg[data-role="plot"]')].map(p => {
    const c = p.querySelector('[data-role="cursor"]');
    const labels = [...p.querySelectorAll('text')].map(e => e.textContent);
    const series = {};
    for (const e of p.querySelectorAll('path[data-series]'))
      series[e.getAttribute('data-series')] = e.getAttribute('d');
    return {title: p.getAttribute('data-title'), cursor: +c.getAttribute('x1'), index: c.getAttribute('data-index'),
            labels, series};
  });
  return {time: t && t.getAttribute('data-value'), text: t && t.textContent,
          slider: document.querySelector('input[data-role="input"]').value, joints, plots};
}
"""


def _path_points(d: str) -> np.ndarray:
    """(X, Y) of every M/L command of an SVG path."""
    return np.array([[float(a), float(b)] for a, b in re.findall(r"[ML](-?[\d.]+) (-?[\d.]+)", d)])


def _affine_residual(u: np.ndarray, v: np.ndarray) -> float:
    a, b = np.polyfit(u, v, 1)
    return float(np.max(np.abs(a * u + b - v)))


def test_report_steps_through_the_times_and_plots_along_time(motion, browser, tmp_path):
    out = tmp_path / "motion.html"
    assert main(["report", str(SLIDER), "--time", "0:0.2:0.005", "--motor", "3,60", "-o", str(out)]) == 0
    ctx = browser.new_context(viewport={"width": 1280, "height": 900})
    requests, errors = [], []
    ctx.on("request", lambda r: requests.append(r.url))
    page = ctx.new_page()
    page.on("console", lambda m: m.type == "error" and errors.append(m.text))
    page.on("pageerror", lambda e: errors.append(str(e)))
    try:
        page.goto(out.as_uri(), wait_until="load")
        slider = page.locator('input[data-role="input"][data-driver="crank"]')
        slider.focus()
        slider.press("Home")
        cursors: list[tuple[int, float]] = []
        for key, times in (("ArrowRight", 0), ("ArrowRight", 9), ("ArrowRight", 14), ("End", 1)):
            for _ in range(times):
                slider.press(key)
            st = page.evaluate(PAGE_STATE)
            i = int(st["slider"])
            assert st["time"] == repr(float(motion.time[i])) and st["text"] == f"t = {motion.time[i]:g} s"
            for j in motion.mechanism.joint_names:
                assert st["joints"][j] == [repr(float(v)) for v in motion.xy(j)[i]], (j, i)
            assert {p["index"] for p in st["plots"]} == {str(i)}
            cursors += [(i, p["cursor"]) for p in st["plots"][:1]]
        assert [i for i, _ in cursors] == [0, 9, 23, 40]
        idx, cx = np.array([i for i, _ in cursors]), np.array([c for _, c in cursors])
        scene = build_scene(motion)  # the plotted columns (joint speeds too)
        assert _affine_residual(motion.time[idx], cx) < 0.5 and np.ptp(cx) > 100
        for p in st["plots"]:
            assert "time [s]" in p["labels"], p["title"]
            for name, d in p["series"].items():
                xy = _path_points(d)
                v = np.asarray(scene.columns[name], float)
                ok = np.isfinite(v)
                assert len(xy) == ok.sum(), (name, len(xy), ok.sum())
                assert _affine_residual(motion.time[ok], xy[:, 0]) < 0.01, name
                if np.ptp(v[ok]) > 1e-9:
                    assert _affine_residual(v[ok], xy[:, 1]) < 0.01, name
        # NEGATIVE control on the same drawn points: they are not affine in the crank's input
        first = _path_points(st["plots"][0]["series"]["crank.angle"])
        assert _affine_residual(motion.inputs["crank"], first[:, 0]) > 5.0
        # Play paces the samples by their times: 5 ms apart, so the fastest pace the page allows
        assert page.evaluate("() => window.linkagekit.playStep()") == 16
        page.locator('[data-action="play"]').click()
        page.wait_for_timeout(200)
        page.locator('[data-action="play"]').click()
    finally:
        ctx.close()
    own = out.as_uri()
    assert not [u for u in requests if u != own and not u.startswith(("data:", "blob:"))]
    assert not errors, errors


def test_a_motion_that_stopped_says_so_in_its_picture():
    """A simulated motion that stopped at a toggle looked complete in its picture and its animation's last frame:
    only stderr said it (review 19f). The figure's note says where it stopped, and so does the last frame."""
    mech = lk.load(Path(__file__).resolve().parents[1] / "examples" / "nongrashof_rocker.yaml")
    res = lk.simulate(mech, np.arange(0.0, 2.0, 0.01), torque=50.0)
    assert res.stopped and res.n < 200
    said = re.search(r"stopped at t = [\d.]+ s, crank = [\d.]+ deg", res.stopped).group(0)
    fig = draw.mechanism_figure(res)
    assert f"the motion {said}" in [t.get_text() for t in fig.axes[0].texts]
    drawing = draw.Drawing(fig.axes[0], build_scene(res))  # as animate draws each frame
    drawing.update(res.n - 1)
    assert drawing.note.get_text() == f"the motion {said}"
    drawing.update(0)
    assert drawing.note.get_text() == ""
