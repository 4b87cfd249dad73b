"""Browser tests of the ``linkagekit report FILE -o OUT.html`` page (mechanism-format.md section 5).

What is tested, independently of how the page is written, against the page's hook contract:

* the page is one self-contained file: while it is used (keys, mouse, play, CSV download)
  every request is the page's own file URL, a ``data:`` or a ``blob:`` URL, and there is no
  console error and no uncaught exception; the seed000 four-bar page is under 1 MB;
* every joint is one element of an inline SVG with ``data-joint``, ``data-x``, ``data-y``;
  ``data-x``/``data-y`` are exactly ``repr(float(v))`` of ``res.xy(joint)[index]`` of
  ``lk.analyze(lk.load(FILE))`` (empty where it does not assemble), and the drawn centres
  (``getBoundingClientRect``, relative to the drawing's ``<svg>``) of all joints at all visited
  inputs fit ONE transform ``u = s x + tx, v = -s y + ty`` (uniform scale, y up) within 0.5 px;
* each driver's ``<input type="range" data-role="input" data-driver=NAME>`` has min 0,
  max n-1, step 1, its value is the sample index, and it is moved with real input: focus and
  ArrowRight / ArrowLeft / Home / End, a mouse click on the track and a mouse drag; with
  several drivers all sliders show the same index;
* ``data-role="input-value"`` (one per driver, ``data-driver``) has ``data-value`` equal to
  ``repr`` of that driver's input at the current sample;
* every ``<svg data-role="plot">`` has a ``data-title`` and a ``data-role="cursor"`` with
  ``data-index`` = the current sample, whose centre x is affine in the input value (and moves);
  files with mass properties have a torque plot and a bearing-load plot;
* ``data-action="play"`` changes the slider within a second, and a second click stops it;
* ``data-action="csv"`` downloads a CSV whose header names columns of ``res.columns()``, one
  row per sample, values equal to 1e-12 relative, empty cells exactly where NaN;
* where the mechanism does not assemble (seed003 example 2.1 outside [86.78, 273.22] deg) the
  joints have empty ``data-x``/``data-y`` and a visible ``data-role="message"`` has text; moving
  back into the range shows the joints again.

How: each report is written once per module through ``linkagekit.cli.main(["report", FILE,
"-o", OUT])`` and opened from its ``file://`` URL in Debian's headless Chromium (``/usr/bin/chromium``)
driven by Playwright (module-scoped browser, one fresh context per test).  The page is read
back through its data attributes after each move (waiting up to a second for it to settle).

Without ``/usr/bin/chromium`` these tests FAIL (install Debian's ``chromium`` package); they
are skipped only when ``LINKAGEKIT_NO_BROWSER=1``.  With ``LINKAGEKIT_SCREENSHOTS=1`` one
screenshot of the seed000 page at its middle input is written to ``docs/images/report.png``.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
import time
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import linkagekit as lk

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
VIEWPORT = {"width": 1280, "height": 900}
SETTLE_S = 10.0  # how long a move may take to show on the page (polled; generous for a busy machine)
PX_TOL = 0.5  # drawn positions: residual of the fitted transform, in CSS px
MAX_PAGE_BYTES = 1_000_000

FILES = {
    "seed000": "seed000_fourbar.yaml",  # four-bar, 361 samples
    "jansen": "jansen_leg.yaml",  # 8 joints
    "slider_crank": "slider_crank.yaml",  # slider, mass properties -> torque plot
    "seed003": "seed003_ex21.yaml",  # does not assemble outside about [86.78, 273.22] deg
    "fivebar": "fivebar_two_drivers.yaml",  # two drivers
    "excavator": "excavator_boom.yaml",  # two cylinder drivers (drawn as barrel and rod), forces
}
ALL = list(FILES)


# ----------------------------------------------------------------------------- Python side
@cache
def analysis(name: str) -> Any:
    """The Python result the page must show: the file's own sweep, default inputs."""
    return lk.analyze(lk.load(EXAMPLES / FILES[name]))


def driver_names(res: Any) -> list[str]:
    return [d.name for d in res.mechanism.drivers]


def input_at(res: Any, driver: str, i: int) -> float:
    return float(np.broadcast_to(res.inputs[driver], res.shape)[i])


def rep(v: float) -> str:
    """What the page must show for a coordinate: ``repr(float)``, empty for NaN."""
    v = float(v)
    return "" if math.isnan(v) else repr(v)


# ----------------------------------------------------------------------------- browser side
@pytest.fixture(scope="module")
def report_file(tmp_path_factory):
    """``report_file(name)``: the HTML written by ``linkagekit report`` (once per module)."""
    out_dir = tmp_path_factory.mktemp("reports")
    made: dict[str, Path | str] = {}

    def make(name: str) -> Path:
        if name not in made:
            from linkagekit import cli

            out = out_dir / f"{name}.html"
            try:
                code = cli.main(["report", str(EXAMPLES / FILES[name]), "-o", str(out)])
            except SystemExit as exc:  # pragma: no cover - main returns its status
                code = exc.code
            if code != 0:
                made[name] = f"`linkagekit report {FILES[name]} -o OUT.html` exited with status {code}"
            elif not out.is_file():
                made[name] = f"`linkagekit report {FILES[name]}` exited 0 but wrote no {out.name}"
            else:
                made[name] = out
        got = made[name]
        if isinstance(got, str):
            pytest.fail(got, pytrace=False)
        return got

    return make


JS_STATE = """
() => {
  const outer = el => { let s = el.ownerSVGElement || (el.tagName.toLowerCase() === 'svg' ? el : null);
                        while (s && s.ownerSVGElement) s = s.ownerSVGElement; return s; };
  const centre = (el, frame) => {
    const r = el.getBoundingClientRect(), f = frame ? frame.getBoundingClientRect() : {left: 0, top: 0};
    return {cx: r.left + r.width / 2 - f.left, cy: r.top + r.height / 2 - f.top, w: r.width, h: r.height};
  };
  const attr = (el, a) => el.getAttribute(a);
  const joints = [];
  for (const e of document.querySelectorAll('[data-joint]')) {
    const svg = outer(e);
    joints.push(Object.assign({name: attr(e, 'data-joint'), x: attr(e, 'data-x'), y: attr(e, 'data-y'),
      tag: e.tagName, inSvg: !!svg, svgIsPlot: !!(svg && svg.closest('[data-role="plot"]'))}, centre(e, svg)));
  }
  const sliders = [];
  for (const e of document.querySelectorAll('[data-role="input"]')) {
    sliders.push({driver: attr(e, 'data-driver'), tag: e.tagName.toLowerCase(), type: attr(e, 'type'),
      value: e.value, min: attr(e, 'min'), max: attr(e, 'max'), step: attr(e, 'step')});
  }
  const values = [];
  for (const e of document.querySelectorAll('[data-role="input-value"]')) {
    values.push({driver: attr(e, 'data-driver'), value: attr(e, 'data-value'), text: e.textContent.trim()});
  }
  const plots = [];
  for (const p of document.querySelectorAll('[data-role="plot"]')) {
    const cursors = [...p.querySelectorAll('[data-role="cursor"]')];
    plots.push({title: attr(p, 'data-title'), tag: p.tagName.toLowerCase(), n_cursors: cursors.length,
      cursor: cursors.length ? Object.assign({index: attr(cursors[0], 'data-index')}, centre(cursors[0], p)) : null});
  }
  const messages = [];
  for (const e of document.querySelectorAll('[data-role="message"]')) {
    const r = e.getBoundingClientRect(), st = getComputedStyle(e);
    messages.push({text: e.textContent.trim(),
      visible: r.width > 0 && r.height > 0 && st.visibility !== 'hidden' && st.display !== 'none'
               && st.opacity !== '0'});
  }
  return {joints, sliders, values, plots, messages};
}
"""


@dataclass
class ReportPage:
    """One report page open in a fresh browser context, with what it requested and logged."""

    name: str
    page: Any
    url: str
    path: Path
    requests: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    points: list[tuple[float, float, float, float, str]] = field(default_factory=list)  # x, y, u, v, where

    @property
    def res(self) -> Any:
        return analysis(self.name)

    @property
    def n(self) -> int:
        return int(self.res.n_samples)

    @property
    def drivers(self) -> list[str]:
        return driver_names(self.res)

    # ------------------------------------------------------------------ reading
    def settle(self) -> None:
        self.page.evaluate("() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")

    def state(self) -> dict:
        return self.page.evaluate(JS_STATE)

    def slider(self, driver: str | None = None) -> Any:
        driver = driver or self.drivers[0]
        return self.page.locator(f'input[type="range"][data-role="input"][data-driver="{driver}"]')

    def index(self) -> int:
        return int(self.slider().input_value())

    # ------------------------------------------------------------------ moving (real input only)
    def press(self, key: str, times: int = 1, driver: str | None = None) -> None:
        s = self.slider(driver)
        s.focus()
        for _ in range(times):
            s.press(key)
        self.settle()

    def click_track(self, frac: float, driver: str | None = None) -> None:
        s = self.slider(driver)
        s.scroll_into_view_if_needed()
        box = s.bounding_box()
        assert box is not None and box["width"] > 20, f"{self.name}: slider {driver} has no usable size: {box}"
        self.page.mouse.click(box["x"] + frac * box["width"], box["y"] + box["height"] / 2)
        self.settle()

    def drag_track(self, f0: float, f1: float, driver: str | None = None) -> None:
        s = self.slider(driver)
        s.scroll_into_view_if_needed()
        box = s.bounding_box()
        assert box is not None and box["width"] > 20, f"{self.name}: slider {driver} has no usable size: {box}"
        y = box["y"] + box["height"] / 2
        self.page.mouse.move(box["x"] + f0 * box["width"], y)
        self.page.mouse.down()
        self.page.mouse.move(box["x"] + f1 * box["width"], y, steps=8)
        self.page.mouse.up()
        self.settle()

    # ------------------------------------------------------------------ checking one state
    def problems(self, st: dict, index: int | None) -> list[str]:
        """Everything the state violates at sample ``index`` (None: take the slider's)."""
        res, n, out = self.res, self.n, []
        sliders = {s["driver"]: s for s in st["sliders"]}
        for d in self.drivers:
            s = sliders.get(d)
            if s is None:
                out.append(f"no <input type=range data-role=input data-driver={d!r}> (found {list(sliders)})")
                continue
            if (s["tag"], s["type"]) != ("input", "range"):
                out.append(f"slider {d}: <{s['tag']} type={s['type']!r}>, expected <input type=range>")
            if s["min"] != "0" or s["max"] != str(n - 1) or s["step"] not in ("1", None):
                out.append(
                    f"slider {d}: min/max/step = {s['min']!r}/{s['max']!r}/{s['step']!r}, expected '0'/'{n - 1}'/'1'"
                )
        values = {s["driver"]: s["value"] for s in st["sliders"] if s["driver"] in self.drivers}
        if not values:
            return out
        if index is None:
            index = int(values[self.drivers[0]])
        for d, v in values.items():
            if v != str(index):
                out.append(f"slider {d}: value {v!r}, expected the sample index {index} (all sliders together)")
        i = index
        # joints
        by_name: dict[str, list[dict]] = {}
        for j in st["joints"]:
            by_name.setdefault(j["name"], []).append(j)
        for name in res.mechanism.joint_names:
            els = by_name.get(name, [])
            if len(els) != 1:
                out.append(f"joint {name}: {len(els)} elements with data-joint={name!r}, expected exactly one")
                continue
            e = els[0]
            if not e["inSvg"] or e["svgIsPlot"]:
                out.append(f"joint {name}: <{e['tag']}> is not inside the inline SVG drawing")
            x, y = res.xy(name)[i]
            want_x, want_y = rep(x), rep(y)
            if (e["x"], e["y"]) != (want_x, want_y):
                out.append(
                    f"joint {name} at index {i}: data-x/data-y = {e['x']!r}/{e['y']!r}, expected {want_x!r}/{want_y!r}"
                )
            elif want_x and not (e["w"] > 0 or e["h"] > 0):
                out.append(f"joint {name} at index {i}: assembled but its element has no drawn size")
        extra = sorted(set(by_name) - set(res.mechanism.joint_names))
        if extra:
            out.append(f"data-joint names not in the file: {extra}")
        # input values
        shown: dict[str | None, list[dict]] = {}
        for v in st["values"]:
            shown.setdefault(v["driver"], []).append(v)
        for d in self.drivers:
            els = shown.get(d, [])
            if len(els) != 1:
                out.append(f"input-value {d}: {len(els)} elements data-role=input-value data-driver={d!r}")
                continue
            want = rep(input_at(res, d, i))
            if els[0]["value"] != want:
                out.append(f"input-value {d} at index {i}: data-value={els[0]['value']!r}, expected {want!r}")
            if not els[0]["text"]:
                out.append(f"input-value {d} at index {i}: shows no text")
        # plot cursors
        for k, p in enumerate(st["plots"]):
            c = p["cursor"]
            if c is None:
                out.append(f"plot {k} ({p['title']!r}): no data-role=cursor element")
            elif c["index"] != str(i):
                out.append(f"plot {k} ({p['title']!r}): cursor data-index={c['index']!r}, expected '{i}'")
        return out

    def check(self, what: str, index: int | None = None) -> dict:
        """Wait (up to SETTLE_S) for the page to agree with Python at ``index``; assert; record points."""
        deadline = time.monotonic() + SETTLE_S
        while True:
            st = self.state()
            bad = self.problems(st, index)
            if not bad or time.monotonic() > deadline:
                break
            time.sleep(0.05)
        assert not bad, f"{self.name} after {what}:\n  " + "\n  ".join(bad[:25])
        i = int(next(s["value"] for s in st["sliders"] if s["driver"] == self.drivers[0]))
        for j in st["joints"]:
            if j["x"]:
                self.points.append((float(j["x"]), float(j["y"]), j["cx"], j["cy"], f"{j['name']}@{i} ({what})"))
        st["index"] = i
        return st

    def assert_one_transform(self) -> None:
        assert_similarity(self.points, self.name)


def assert_similarity(points: list, name: str) -> None:
    """All (x, y) -> (u, v) fit u = s x + tx, v = -s y + ty (s > 0) within PX_TOL px."""
    assert len(points) >= 3, f"{name}: only {len(points)} drawn joint positions recorded"
    x, y, u, v = (np.array([p[k] for p in points], float) for k in range(4))
    m = len(points)
    a = np.zeros((2 * m, 3))
    a[:m, 0], a[:m, 1] = x, 1.0
    a[m:, 0], a[m:, 2] = -y, 1.0
    b = np.concatenate([u, v])
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    s, tx, ty = sol
    r = np.hypot(s * x + tx - u, -s * y + ty - v)
    worst = int(np.argmax(r))
    assert s > 0, f"{name}: fitted scale {s} px/unit is not positive (the drawing is not y-up)"
    assert r[worst] < PX_TOL, (
        f"{name}: drawn joint centres are not one similarity transform (uniform scale, y up): "
        f"worst residual {r[worst]:.3f} px at {points[worst][4]} (file ({x[worst]}, {y[worst]}) drawn at "
        f"({u[worst]:.2f}, {v[worst]:.2f}) px, fit s={s:.4f} px/unit, t=({tx:.2f}, {ty:.2f})); "
        f"{int((r >= PX_TOL).sum())} of {m} points over {PX_TOL} px"
    )


@pytest.fixture
def open_report(browser, report_file):
    """``open_report(name)`` -> ReportPage; records requests, console errors, page errors."""
    contexts = []

    def _open(name: str) -> ReportPage:
        path = report_file(name)
        ctx = browser.new_context(viewport=VIEWPORT, accept_downloads=True)
        contexts.append(ctx)
        page = ctx.new_page()
        rp = ReportPage(name=name, page=page, url=path.as_uri(), path=path)
        ctx.on("request", lambda req: rp.requests.append(req.url))
        page.on("console", lambda msg: msg.type == "error" and rp.errors.append(f"console error: {msg.text}"))
        page.on("pageerror", lambda exc: rp.errors.append(f"page error: {exc}"))
        page.goto(rp.url, wait_until="load")
        rp.settle()
        return rp

    yield _open
    for ctx in contexts:
        ctx.close()


def wait_for(cond, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if cond():
            return True
        time.sleep(0.02)
    return cond()


# ============================================================================== tests
@pytest.mark.parametrize("name", ALL)
def test_self_contained_no_requests_no_errors(open_report, name):
    """Used with keys, mouse, play and the CSV download, the page asks for nothing outside itself."""
    rp = open_report(name)
    page = rp.page
    if rp.slider().count():
        rp.press("Home")
        rp.press("ArrowRight", 3)
        rp.press("End")
        rp.click_track(0.5)
        rp.drag_track(0.3, 0.7)
    play = page.locator('[data-action="play"]')
    if play.count():
        play.first.click()
        page.wait_for_timeout(300)
        play.first.click()
    csv_ctl = page.locator('[data-action="csv"]')
    if csv_ctl.count():
        try:
            with page.expect_download(timeout=3000):
                csv_ctl.first.click()
        except Exception:  # noqa: BLE001 - the CSV itself is test_csv_download's business
            pass
    rp.settle()
    page.wait_for_timeout(100)
    own = rp.url.split("#")[0]
    foreign = [u for u in rp.requests if u.split("#")[0] != own and not u.startswith(("data:", "blob:"))]
    assert not foreign, f"{name}: the page requested other files/hosts: {foreign[:10]}"
    assert not rp.errors, f"{name}: " + "; ".join(rp.errors[:10])


def test_page_size_seed000(report_file):
    size = report_file("seed000").stat().st_size
    assert size < MAX_PAGE_BYTES, f"seed000 report (361 samples) is {size} bytes, over {MAX_PAGE_BYTES}"


@pytest.mark.parametrize("name", ALL)
def test_keys_move_joints_exactly(open_report, name):
    """Home / ArrowRight / End / ArrowLeft: index, joints (repr-exact), input values, cursors; one transform."""
    rp = open_report(name)
    n = rp.n
    rp.check("loading")  # whatever sample it opens at, it must be consistent
    rp.press("Home")
    rp.check("Home", 0)
    rp.press("ArrowRight")
    rp.check("ArrowRight", 1)
    rp.press("ArrowRight", 2)
    rp.check("ArrowRight x2", 3)
    rp.press("End")
    rp.check("End", n - 1)
    rp.press("ArrowLeft")
    rp.check("ArrowLeft", n - 2)
    rp.press("ArrowLeft", 3)
    rp.check("ArrowLeft x3", n - 5)
    rp.assert_one_transform()


@pytest.mark.parametrize("name", ALL)
def test_mouse_moves_joints_exactly(open_report, name):
    """A click on the track and a drag along it move to about that fraction of the sweep, consistently."""
    rp = open_report(name)
    n = rp.n
    seen = []
    for frac in (0.25, 0.5, 0.75):
        rp.click_track(frac)
        st = rp.check(f"mouse click at {frac:.0%} of the track")
        seen.append(st["index"])
        assert abs(st["index"] - frac * (n - 1)) <= 0.05 * n, (
            f"{name}: a click at {frac:.0%} of the slider track gave index {st['index']} of 0..{n - 1}"
        )
    rp.drag_track(0.2, 0.6)
    st = rp.check("mouse drag from 20% to 60% of the track")
    assert abs(st["index"] - 0.6 * (n - 1)) <= 0.05 * n, f"{name}: a drag to 60% gave index {st['index']}"
    assert len(set(seen + [st["index"]])) >= 3, f"{name}: the mouse did not move the slider: indices {seen}"
    rp.assert_one_transform()


@pytest.mark.parametrize(
    "name",
    [n if n in ("slider_crank", "fivebar", "excavator") else pytest.param(n, marks=pytest.mark.long) for n in ALL],
)
def test_plot_cursors_follow_input(open_report, name):
    """Every plot's cursor has data-index = sample and its x is affine in the input value (and moves)."""
    rp = open_report(name)
    n, res, d0 = rp.n, rp.res, rp.drivers[0]
    st0 = rp.state()
    assert st0["plots"], f"{name}: no <svg data-role='plot'> on the page"
    for k, p in enumerate(st0["plots"]):
        assert p["tag"] == "svg", f"{name}: plot {k} is <{p['tag']}>, expected <svg>"
        assert p["title"], f"{name}: plot {k} has no data-title"
        assert p["n_cursors"] == 1, f"{name}: plot {k} ({p['title']!r}) has {p['n_cursors']} cursor elements"
    xs: dict[int, list[tuple[float, float, int]]] = {}
    rp.press("Home")
    for key, times in (("ArrowRight", 0), ("ArrowRight", 40), ("ArrowRight", 50)):
        if times:
            rp.press(key, times)
        st = rp.check(f"{key} x{times}")
        _collect(xs, st, res, d0)
    rp.click_track(0.7)
    _collect(xs, rp.check("mouse click at 70%"), res, d0)
    rp.press("End")
    _collect(xs, rp.check("End", n - 1), res, d0)
    for k, pts in xs.items():
        title = st0["plots"][k]["title"]
        u = np.array([p[0] for p in pts])
        cx = np.array([p[1] for p in pts])
        assert len(set(p[2] for p in pts)) >= 3
        a, b = np.polyfit(u, cx, 1)
        r = np.abs(a * u + b - cx)
        assert np.ptp(cx) > 1.0, f"{name}: cursor of plot {title!r} does not move: x = {cx.round(2).tolist()}"
        assert r.max() < PX_TOL, (
            f"{name}: cursor x of plot {title!r} is not affine in the input {d0}: inputs {u.tolist()}, "
            f"x {cx.round(3).tolist()} px, residuals {r.round(3).tolist()}"
        )


def _collect(xs, st, res, d0):
    for k, p in enumerate(st["plots"]):
        xs.setdefault(k, []).append((input_at(res, d0, st["index"]), p["cursor"]["cx"], st["index"]))


@pytest.mark.parametrize("name", ALL)
def test_plot_quantities(open_report, name):
    """Link angles and angular velocities are plotted; with mass properties, a torque and bearing loads."""
    rp = open_report(name)
    titles = [p["title"] or "" for p in rp.state()["plots"]]
    low = " | ".join(titles).lower()
    assert "angle" in low or "θ" in low, f"{name}: no link-angle plot among {titles}"
    assert any(w in low for w in ("omega", "ω", "angular veloc", "angular speed")), (
        f"{name}: no angular-velocity plot among {titles}"
    )
    if rp.res.forces is not None:
        assert any(w in low for w in ("torque", "t[", "driver force")), (  # cylinders and sliders push
            f"{name} has mass properties: no driver torque or force plot among {titles}"
        )
        assert any(w in low for w in ("load", "reaction", "force", "|f|", "bearing")), (
            f"{name} has mass properties: no bearing-load plot among {titles}"
        )


@pytest.mark.parametrize("name", ["seed000", "fivebar"])
def test_play_button(open_report, name):
    rp = open_report(name)
    page = rp.page
    play = page.locator('button[data-action="play"]')
    assert play.count() == 1, f"{name}: {play.count()} <button data-action=play> elements"
    rp.press("Home")
    start = rp.index()
    play.click()
    moved = wait_for(lambda: rp.index() != start, 10.0)  # polled: at once when it plays, 10 s on a busy machine
    assert moved, f"{name}: ten seconds after clicking play the slider is still at {start}"
    play.click()
    rp.settle()
    a = rp.index()
    page.wait_for_timeout(400)
    b = rp.index()
    assert a == b, f"{name}: after the second click on play the slider still moves ({a} -> {b})"
    rp.check("play then stop")
    rp.assert_one_transform()


@pytest.fixture(scope="module")
def downloaded_csv(browser, report_file):
    """``downloaded_csv(name)`` -> (header, rows, n_plots, error): the CSV the csv control downloads (once)."""
    got: dict[str, tuple] = {}

    def fetch(name: str) -> tuple:
        if name not in got:
            ctx = browser.new_context(viewport=VIEWPORT, accept_downloads=True)
            try:
                page = ctx.new_page()
                page.goto(report_file(name).as_uri(), wait_until="load")
                n_plots = page.locator('[data-role="plot"]').count()
                ctl = page.locator('[data-action="csv"]')
                if ctl.count() != 1:
                    got[name] = (None, None, n_plots, f"{ctl.count()} elements with data-action=csv, expected one")
                else:
                    with page.expect_download(timeout=30_000) as dl:
                        ctl.click()
                    text = Path(dl.value.path()).read_text(encoding="utf-8-sig")
                    rows = list(csv.reader(io.StringIO(text)))
                    got[name] = (rows[0] if rows else [], [r for r in rows[1:] if r], n_plots, None)
            finally:
                ctx.close()
        header, body, n_plots, error = got[name]
        if error:
            pytest.fail(f"{name}: {error}", pytrace=False)
        return header, body, n_plots

    return fetch


CSV_NAMES = ["seed000", "slider_crank", "seed003", "fivebar"]


@pytest.mark.parametrize("name", CSV_NAMES)
def test_csv_download_values(downloaded_csv, name):
    """One row per sample; every column that is a res.columns() name equals it (1e-12 rel), '' where NaN."""
    header, body, n_plots = downloaded_csv(name)
    res = analysis(name)
    cols = with_joint_speeds(res)
    assert len(header) == len(set(header)), f"{name}: CSV header repeats a column: {header}"
    assert len(body) == res.n_samples, f"{name}: CSV has {len(body)} rows, expected one per sample ({res.n_samples})"
    for d in driver_names(res):
        assert f"input:{d}" in header, f"{name}: CSV lacks the input column input:{d}"
    quantities = [h for h in header if not h.startswith("input:") and h not in ("assembled", "singular")]
    assert len(quantities) >= n_plots, f"{name}: {n_plots} plots but only {len(quantities)} CSV quantities"
    if res.forces is not None:
        missing = [c for c in cols if c.startswith("T[") and c not in header]
        assert not missing, f"{name}: the plotted driver torque {missing} is not in the CSV"
    bad = []
    for i, row in enumerate(body):
        assert len(row) == len(header), f"{name}: CSV row {i} has {len(row)} cells, the header {len(header)}"
    for c, h in enumerate(header):
        if h not in cols:
            continue  # test_csv_header_is_result_columns
        want = np.asarray(cols[h])
        for i, row in enumerate(body):
            cell, w = row[c].strip(), want[i]
            if want.dtype == bool:
                ok, shown = cell.lower() in (("true", "1") if w else ("false", "0")), repr(bool(w))
            elif math.isnan(float(w)):
                ok, shown = cell == "", "'' (NaN)"
            else:
                shown = repr(float(w))
                try:
                    ok = cell != "" and math.isclose(float(cell), float(w), rel_tol=1e-12, abs_tol=0.0)
                except ValueError:
                    ok = False
            if not ok:
                bad.append(f"{h}[{i}] = {cell!r}, expected {shown}")
    assert not bad, f"{name}: {len(bad)} CSV cells differ from res.columns(), e.g. " + "; ".join(bad[:8])


def with_joint_speeds(res):
    """res.columns() plus the plotted joint speeds |v|[J], computed here from the velocities."""
    cols = dict(res.columns())
    for j in res.mechanism.joint_names:
        if j not in res.mechanism.link("ground").joints:
            v = res.vxy(j)
            cols[f"|v|[{j}]"] = np.hypot(v[:, 0], v[:, 1])
    return cols


@pytest.mark.parametrize("name", CSV_NAMES)
def test_csv_header_is_result_columns(downloaded_csv, name):
    """Every CSV column is a name of res.columns() or a joint speed (so every value is checked against Python)."""
    header, _, _ = downloaded_csv(name)
    cols = with_joint_speeds(analysis(name))
    unknown = [h for h in header if h not in cols]
    assert not unknown, f"{name}: CSV columns that are not names of res.columns(): {unknown}"


def test_not_assembled_range_seed003(open_report):
    """Outside [86.78, 273.22] deg: empty joints and a message; back inside: joints drawn again."""
    rp = open_report("seed003")
    res = rp.res
    assert not res.assembled[86] and res.assembled[87] and res.assembled[273] and not res.assembled[274]

    def message_shown(st, where):
        shown = [m for m in st["messages"] if m["visible"] and m["text"]]
        assert shown, (
            f"seed003 at index {st['index']} ({where}): no visible data-role=message with text: {st['messages']}"
        )

    def joints_empty(st, where):
        full = [(j["name"], j["x"], j["y"]) for j in st["joints"] if j["x"] or j["y"]]
        assert not full, f"seed003 at index {st['index']} ({where}): joints not empty: {full}"

    rp.press("Home")
    st = rp.check("Home (0 deg)", 0)
    joints_empty(st, "Home")
    message_shown(st, "Home")
    rp.press("ArrowRight", 86)
    st = rp.check("ArrowRight to 86 deg", 86)
    joints_empty(st, "86 deg")
    message_shown(st, "86 deg")
    rp.press("ArrowRight")
    st = rp.check("ArrowRight to 87 deg (assembles)", 87)
    assert all(j["x"] and j["y"] for j in st["joints"]), f"seed003 at 87 deg: joints still empty: {st['joints']}"
    rp.click_track(0.5)
    st = rp.check("click at mid track (assembles)")
    assert res.assembled[st["index"]]
    rp.press("End")
    st = rp.check("End (360 deg)", rp.n - 1)
    joints_empty(st, "End")
    message_shown(st, "End")
    rp.press("ArrowLeft", 87)
    st = rp.check("ArrowLeft back to 273 deg (assembles)", 273)
    assert all(j["x"] and j["y"] for j in st["joints"]), f"seed003 at 273 deg: joints still empty: {st['joints']}"
    rp.assert_one_transform()
    # the shading and its sentence are the exact range's complement, not the samples' (review 17b)
    text = rp.page.locator('[data-role="gaps"]').text_content()
    assert re.fullmatch(
        r"Does not assemble for crank in \(0, 86\.78\d*\), \(273\.21\d*, 360\) deg \(shaded\)\.", text
    ), text
    plots = rp.page.locator('[data-role="plot"]')
    for k in range(plots.count()):
        assert plots.nth(k).locator('[data-role="gap"]').count() == 2


def test_message_cleared_when_assembled_seed003(open_report):
    """Back inside the range, no visible data-role=message still says it does not assemble."""
    rp = open_report("seed003")
    rp.press("Home")
    rp.check("Home", 0)
    rp.press("ArrowRight", 90)
    st = rp.check("ArrowRight to 90 deg", 90)
    shown = [m["text"] for m in st["messages"] if m["visible"] and m["text"]]
    assert not shown, f"seed003 at 90 deg (assembles): a message is still shown: {shown}"


JS_JOINTS_DRAWN = """
() => Object.fromEntries([...document.querySelectorAll('svg[data-role=mechanism] [data-joint]')].map(e => {
  const r = e.getBoundingClientRect();
  return [e.getAttribute('data-joint'), {x: e.getAttribute('data-x'), u: r.left + r.width / 2, v: r.top + r.height / 2,
    visible: getComputedStyle(e).visibility !== 'hidden'}];
}))
"""


def test_ground_joints_are_drawn_where_it_does_not_assemble_seed003(open_report):
    """The fixed pivots O1, O2 never move: at 0 deg (nothing assembles) they are drawn, at the very spot where
    they are drawn mid-sweep (where it assembles; within 0.01 px), with empty data-x/data-y; the moving joints
    are hidden there."""
    rp = open_report("seed003")
    ground = set(rp.res.mechanism.link("ground").joints)
    assert ground == {"O1", "O2"}
    rp.press("Home")
    at0 = rp.page.evaluate(JS_JOINTS_DRAWN)
    rp.click_track(0.5)
    assert rp.res.assembled[rp.index()], rp.index()
    mid = rp.page.evaluate(JS_JOINTS_DRAWN)
    for j, e in at0.items():
        assert e["x"] == "" and e["visible"] == (j in ground), (j, e)
        assert mid[j]["visible"] and mid[j]["x"], (j, mid[j])
        if j in ground:
            assert math.hypot(e["u"] - mid[j]["u"], e["v"] - mid[j]["v"]) < 0.01, (j, e, mid[j])


def test_two_sliders_move_together_fivebar(open_report):
    rp = open_report("fivebar")
    d1, d2 = rp.drivers
    assert (d1, d2) == ("crank1", "crank2")
    assert rp.slider(d1).count() == 1 and rp.slider(d2).count() == 1
    rp.press("Home", driver=d1)
    rp.check(f"Home on {d1}", 0)
    rp.press("ArrowRight", 5, driver=d2)
    rp.check(f"ArrowRight x5 on {d2}", 5)
    rp.press("End", driver=d2)
    rp.check(f"End on {d2}", rp.n - 1)
    rp.click_track(0.25, driver=d2)
    st = rp.check(f"click at 25% of {d2}")
    assert abs(st["index"] - 90) <= 18, f"fivebar: click at 25% of {d2} gave index {st['index']}"
    rp.drag_track(0.3, 0.8, driver=d1)
    st = rp.check(f"drag on {d1} to 80%")
    assert abs(st["index"] - 288) <= 18, f"fivebar: drag to 80% of {d1} gave index {st['index']}"
    rp.press("ArrowLeft", 2, driver=d1)
    rp.check(f"ArrowLeft x2 on {d1}", st["index"] - 2)
    rp.assert_one_transform()


def test_screenshot_for_docs(open_report, tmp_path):
    """A screenshot of the seed000 page at its middle input is not blank; LINKAGEKIT_SCREENSHOTS=1 keeps it
    as docs/images/report.png."""
    rp = open_report("seed000")
    mid = (rp.n - 1) // 2
    rp.press("Home")
    rp.press("ArrowRight", mid)
    rp.check("moving to the middle input", mid)
    keep = os.environ.get("LINKAGEKIT_SCREENSHOTS") == "1"
    out = ROOT / "docs" / "images" / "report.png" if keep else tmp_path / "report.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    rp.page.evaluate("() => { document.activeElement && document.activeElement.blur(); window.scrollTo(0, 0); }")
    rp.settle()
    rp.page.screenshot(path=str(out))  # the viewport: drawing, slider and plots
    from PIL import Image

    img = np.asarray(Image.open(out).convert("L"), dtype=float)
    # not blank: a drawing and plots give many dark pixels and a spread of grey levels
    assert (img < 128).mean() > 0.01 and img.std() > 20, ((img < 128).mean(), img.std())


# ------------------------------------------------- edge cases found by review (each broke the page)
def _page_of(browser, tmp_path, mech, argv_extra=()):
    """Open the report of ``mech`` (a Mechanism); returns (page, errors)."""
    import linkagekit as lk
    from linkagekit import cli

    src = tmp_path / "m.yaml"
    lk.save(mech, src)
    out = tmp_path / "m.html"
    assert cli.main(["report", str(src), "-o", str(out), *argv_extra]) == 0
    ctx = browser.new_context(viewport=VIEWPORT)
    page = ctx.new_page()
    errors: list[str] = []
    page.on("console", lambda msg: msg.type == "error" and errors.append(msg.text))
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    t0 = time.monotonic()
    page.goto(out.as_uri(), wait_until="load")
    return ctx, page, errors, time.monotonic() - t0


def test_a_constant_plot_does_not_hang_the_page(browser, tmp_path):
    """A crank alone: its joint speed is constant up to round-off (the tick loop never advanced)."""
    import linkagekit as lk

    mech = lk.Mechanism.from_dict(
        {
            "joints": {"A": [0, 0], "C": [0.3, 0.4]},
            "links": {"ground": ["A"], "crank": ["A", "C"]},
            "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
        }
    )
    ctx, page, errors, took = _page_of(browser, tmp_path, mech)
    try:
        assert not errors, errors
        assert took < 20, took  # a hung tick loop never loads; 20 s: a busy machine is not a hang
        got = page.locator('[data-joint="C"]').get_attribute("data-x")
        res = lk.analyze(mech)
        assert got == repr(float(res.xy("C")[0, 0]))
        ticks = page.evaluate("() => window.linkagekit.niceTicks(1.4999999999999996, 1.5000000000000002, 5).ticks")
        assert 2 <= len(ticks) <= 20 and all(abs(t - 1.5) < 0.2 for t in ticks), ticks
    finally:
        ctx.close()


def test_extent_of_long_arrays(browser, tmp_path):
    """The page's min/max over 500,000 values (Math.min.apply overflowed the stack from ~120,000)."""
    import linkagekit as lk

    ctx, page, errors, _ = _page_of(browser, tmp_path, lk.load(EXAMPLES / FILES["seed000"]))
    try:
        got = page.evaluate(
            "() => window.linkagekit.extent([Array.from({length: 500000}, (_, i) => i % 1000 - 3), [null, 7777]])"
        )
        assert got == [-3, 7777], got
        assert not errors, errors
    finally:
        ctx.close()


def test_many_series_keep_their_legends_inside_the_plot(browser, tmp_path):
    """Jansen's link angles: nine series; every legend entry lies inside its plot's box, none overlapping."""
    import linkagekit as lk

    ctx, page, errors, _ = _page_of(browser, tmp_path, lk.load(EXAMPLES / FILES["jansen"]))
    try:
        boxes = page.evaluate(
            """() => [...document.querySelectorAll('svg[data-role=plot]')].map(svg => {
                const o = svg.getBoundingClientRect();
                return [[o.left, o.right], [...svg.querySelectorAll('[data-legend]')].map(t => {
                    const b = t.getBoundingClientRect(); return [b.left, b.right, b.top, b.bottom]; })]; })"""
        )
        assert not errors, errors
        for (left, right), entries in boxes:
            assert entries
            for a in entries:
                assert left - 0.5 <= a[0] and a[1] <= right + 0.5, (a, left, right)
            for i, a in enumerate(entries):
                for b in entries[i + 1 :]:
                    overlap = min(a[1], b[1]) - max(a[0], b[0]) > 1 and min(a[3], b[3]) - max(a[2], b[2]) > 1
                    assert not overlap, (a, b)
    finally:
        ctx.close()


def test_plots_are_readable_at_a_phone_width(browser, tmp_path):
    """At 390 px a plot drawn 640 units wide was shrunk to 55 %: its text 6-8 px tall. It is drawn in the width it is
    shown in, so its text keeps its size (10-12 units: at least 10 px)."""
    import linkagekit as lk
    from linkagekit import cli

    src, out = tmp_path / "sc.yaml", tmp_path / "sc.html"
    lk.save(lk.load(Path(__file__).resolve().parents[1] / "examples" / "slider_crank.yaml"), src)
    assert cli.main(["report", str(src), "-o", str(out)]) == 0
    ctx = browser.new_context(viewport={"width": 390, "height": 800})
    try:
        page = ctx.new_page()
        page.goto(out.as_uri(), wait_until="load")
        sizes = """() => Array.from(document.querySelectorAll('svg[data-role=plot]')).map(s => {
              const h = Array.from(s.querySelectorAll('text')).filter(t => t.textContent)
                .map(t => t.getBoundingClientRect().height);
              return [s.getBoundingClientRect().width, Math.min(...h), Math.max(...h)]; })"""
        for width in (390, 1280, 390):  # drawn again when the width changes (a phone turned, a window resized)
            page.set_viewport_size({"width": width, "height": 800})
            page.wait_for_timeout(400)
            got = page.evaluate(sizes)
            assert got and all(w <= width and lo >= 10 and hi <= 20 for w, lo, hi in got), (width, got)
    finally:
        ctx.close()
