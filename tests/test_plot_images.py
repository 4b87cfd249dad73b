"""Pictures tested like numbers: `linkagekit plot` draws what the solver computes, where it computes it.

Every check here reads pixels (or, for `plot_quantity`, the drawn line's data) and compares them
with an independent `lk.analyze` / `lk.modes` call, mapped to pixels by the transform the PNG
carries in its metadata (``linkagekit:transform`` = ``[sx, tx, sy, ty]``: column = sx x + tx,
row = sy y + ty, rows from the top).  Each pixel checker has a NEGATIVE control that proves it
can fail (shifted transform, blank image, a drawn-in chord, the wrong pose, ...).

Tolerances (pixels at ``--dpi 100``, at which these checks draw; the default is 200):

* curve colour: a pixel within RGB distance 60 of ``CURVE_COLOR`` (at least ~79 % curve colour
  over white; a 1.6 pt line always has fully covered pixels, so the curve's core passes);
* on-curve: every computed curve point within 2 px (Euclidean, pixel centres) of a curve pixel,
  for >= 98 % of the points NOT covered by something drawn on top of the curve at the drawn pose
  (see `occluded`: pins and labels, ground symbols, opaque bars, plate edges; covered points
  are at most 35 % of the curve) AND for >= 90 % of ALL points (no exclusion at all);
* no stray curve pixels: every curve-coloured pixel of the image within 3 px of the computed curve;
* off-curve: the curve shifted by 10 % of the image size, kept only where >= 6 px from every
  computed joint path and clear of the drawn links: no curve colour within 1 px, >= 95 % white;
* pins: a dark ring (luminance < 110 somewhere between radius 2.5 and 6 px on >= 14 of 16
  rays) around a bright centre (luminance > 200 at the joint's pixel and its 4 neighbours).
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from functools import cached_property
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.path import Path as MplPath
from PIL import Image, ImageDraw
from scipy import ndimage
from scipy.spatial import cKDTree

import linkagekit as lk
from helpers import dark_ring_rays, luminance
from linkagekit.cli import main
from linkagekit.viz import draw
from linkagekit.viz.scene import build_scene

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FILES = {
    "seed000": EXAMPLES / "seed000_fourbar.yaml",
    "jansen": EXAMPLES / "jansen_leg.yaml",
    "seed003": EXAMPLES / "seed003_ex21.yaml",
}
CURVE_DIST = 60.0  # RGB distance to CURVE_COLOR that counts as "curve colour"
ON_TOL = 2.0  # px: a computed curve point must have a curve pixel this close
STRAY_TOL = 3.0  # px: every curve pixel must be this close to the computed curve


# --------------------------------------------------------------------------- pixel helpers
def hex_rgb(h: str) -> np.ndarray:
    h = h.lstrip("#")
    return np.array([int(h[i : i + 2], 16) for i in (0, 2, 4)], float)


CURVE_RGB = hex_rgb(draw.CURVE_COLOR)


def read_png(path: Path) -> tuple[np.ndarray, list[float]]:
    im = Image.open(path)
    im.load()
    t = json.loads(im.text["linkagekit:transform"])
    assert len(t) == 4 and all(math.isfinite(v) for v in t)
    return np.asarray(im.convert("RGB"), float), t


def curve_mask(rgb: np.ndarray) -> np.ndarray:
    return np.linalg.norm(rgb - CURVE_RGB, axis=-1) < CURVE_DIST


def to_px(t: list[float], xy: np.ndarray) -> np.ndarray:
    """(n, 2) file-unit points -> (n, 2) pixel (column, row), continuous coordinates."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    return np.stack([t[0] * xy[:, 0] + t[1], t[2] * xy[:, 1] + t[3]], axis=-1)


def pixel_index(pts: np.ndarray, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, cols, inside) of the pixels containing continuous points."""
    c = np.floor(pts[:, 0]).astype(int)
    r = np.floor(pts[:, 1]).astype(int)
    inside = (c >= 0) & (c < shape[1]) & (r >= 0) & (r < shape[0])
    return np.clip(r, 0, shape[0] - 1), np.clip(c, 0, shape[1] - 1), inside


def near_mask(mask: np.ndarray, pts: np.ndarray, tol: float) -> np.ndarray:
    """For each point: is a True pixel of `mask` within `tol` px (Euclidean, pixel centres)?"""
    if not mask.any():
        return np.zeros(len(pts), bool)
    dist = ndimage.distance_transform_edt(~mask)
    r, c, inside = pixel_index(pts, mask.shape)
    return inside & (dist[r, c] <= tol)


def densify(pts: np.ndarray, step: float = 0.5) -> np.ndarray:
    """Points every `step` px along a polyline (pixel coords), not across NaN breaks."""
    out = [pts[np.isfinite(pts).all(axis=1)]]
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        if not (np.isfinite(a).all() and np.isfinite(b).all()):
            continue
        k = int(np.ceil(np.linalg.norm(b - a) / step))
        if k > 1:
            out.append(a + np.linspace(0, 1, k + 1)[:, None] * (b - a))
    return np.concatenate(out) if out else np.zeros((0, 2))


def seg_dist(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(((p - a) @ ab) / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def ring_at(rgb: np.ndarray, c: float, r: float, rays: int = 16) -> tuple[int, float]:
    """(rays with a dark pixel between radius 2.5 and 6 px, darkest luminance of the pixel and its 4 neighbours)."""
    lum = luminance(rgb) if rgb.ndim == 3 else rgb  # an RGB image, or its luminance
    h, w = lum.shape
    dark = dark_ring_rays(lum, c, r, rays)
    ci, ri = int(math.floor(c)), int(math.floor(r))
    cross = [
        lum[ri + dr, ci + dc]
        for dr, dc in ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1))
        if 0 <= ri + dr < h and 0 <= ci + dc < w
    ]
    return dark, float(min(cross)) if len(cross) == 5 else 0.0


def is_pin(rgb: np.ndarray, c: float, r: float) -> bool:
    dark, centre = ring_at(rgb, c, r)
    return dark >= 14 and centre > 200


def pose_input(mech) -> float:
    """The reference pose's input angle, read off the file's joints (pivot -> toward)."""
    d = mech.drivers[0]
    v = mech.joints[d.toward] - mech.joints[d.pivot]
    a = math.atan2(v.imag, v.real)
    return math.degrees(a) if mech.angle_unit == "deg" else a


def occluded(mech, t: list[float], pose: dict[str, np.ndarray], pts: np.ndarray) -> np.ndarray:
    """Points (px) that something drawn ON TOP of the curves may cover at the drawn pose.

    Pins (radius ~5 px) + 2 px tolerance: 9 px around every joint; its label, up-right of it:
    a 20 x 22 px box; a ground pivot's triangle and hatching: 68 x 46 px box below it; a bar
    (5 pt = 7 px wide, opaque): 7 px from its segment; a plate's translucent edge (2.5 pt):
    5 px from each segment between its joints (its fill is translucent: the curve shows through
    it in curve colour, so the inside of a plate is NOT excluded).
    """
    ground = set(mech.link("ground").joints)
    ex = np.zeros(len(pts), bool)
    for j, q in pose.items():
        dc, dr = pts[:, 0] - q[0], pts[:, 1] - q[1]
        ex |= np.hypot(dc, dr) < 9
        ex |= (dc > -2) & (dc < 18) & (dr < 2) & (dr > -20)
        if j in ground:
            ex |= (np.abs(dc) < 34) & (dr > -10) & (dr < 36)
    for ln in mech.links:
        if ln.name == "ground":
            continue
        js = ln.joints
        width = 7.0 if len(js) == 2 else 5.0
        for i in range(len(js)):
            for k in range(i + 1, len(js)):
                ex |= seg_dist(pts, pose[js[i]], pose[js[k]]) < width
    return ex


def inside_plates(mech, pose: dict[str, np.ndarray], pts: np.ndarray) -> np.ndarray:
    out = np.zeros(len(pts), bool)
    for ln in mech.links:
        if ln.name != "ground" and len(ln.joints) >= 3:
            poly = np.array([pose[j] for j in ln.joints])
            c = poly.mean(axis=0)
            order = np.argsort(np.arctan2(poly[:, 1] - c[1], poly[:, 0] - c[0]))
            out |= MplPath(poly[order]).contains_points(pts, radius=6)  # either orientation
            out |= MplPath(poly[order]).contains_points(pts, radius=-6)
    return out


# --------------------------------------------------------------------------- the checker
class Drawn:
    """One `plot FILE -o OUT.png` with everything computed independently to check it."""

    def __init__(self, key: str, png: Path, angles: str | None = None, at: float | None = None):
        self.key, self.png = key, png
        self.mech = lk.load(FILES[key])
        if angles is None:
            self.res = lk.analyze(self.mech)
        else:
            a, b, s = (float(v) for v in angles.split(":"))
            self.res = lk.analyze(self.mech, {self.mech.drivers[0].name: np.arange(a, b + s / 2, s)})
        self.rgb, self.t = read_png(png)
        self.curves = build_scene(self.res).coupler_curves
        # the drawn pose: --at's input, else the file's own (read off its joints)
        shown = pose_input(self.mech) if at is None else at
        pose = lk.analyze(self.mech, {self.mech.drivers[0].name: [shown]})
        self.pose = {j: to_px(self.t, pose.xy(j))[0] for j in self.mech.joint_names}

    def curve_px(self, joint: str, t: list[float] | None = None) -> np.ndarray:
        """The joint's path as drawn: its samples, and the exact ends of the range inside the sweep (a path runs on
        to a dead point), in the sweep's order."""
        return to_px(self.t if t is None else t, self.path.xy(joint))

    @cached_property
    def path(self) -> Any:
        """The result over the sweep's inputs and the ends of the assembly range inside it (a hair inside)."""
        name = self.mech.drivers[0].name
        x = np.asarray(self.res.inputs[name], float)
        lo, hi = float(x.min()), float(x.max())
        ends = [
            u + d * 1e-10 * max(1.0, abs(u))
            for a, b in lk.check(self.mech).input_range
            for v, d in ((a, 1.0), (b, -1.0))
            for u in (v + 360.0 * k for k in range(-3, 4))
            if lo < u < hi
        ]
        return lk.analyze(self.mech, {name: np.sort(np.concatenate([x, ends]))}, rates=False, dynamics=False)

    def all_paths_tree(self) -> cKDTree:
        return cKDTree(np.concatenate([densify(self.curve_px(j)) for j in self.mech.joint_names]))

    def coupler_tree(self) -> cKDTree:
        return cKDTree(np.concatenate([densify(self.curve_px(j)) for j in self.curves]))


def on_curve_fractions(d: Drawn, rgb: np.ndarray, t: list[float]) -> dict[str, tuple[float, float, float]]:
    """Per coupler curve: (fraction matched among unoccluded points, fraction matched overall, fraction occluded)."""
    mask = curve_mask(rgb)
    out = {}
    for j in d.curves:
        p = d.curve_px(j, t)
        p = p[np.isfinite(p).all(axis=1)]
        ok = near_mask(mask, p, ON_TOL)
        ex = occluded(d.mech, t, d.pose, p)
        out[j] = (float(ok[~ex].mean()), float(ok.mean()), float(ex.mean()))
    return out


def curve_is_drawn(d: Drawn, rgb: np.ndarray, t: list[float]) -> bool:
    return all(a >= 0.98 and b >= 0.90 and ex <= 0.35 for a, b, ex in on_curve_fractions(d, rgb, t).values())


def off_curve_points(d: Drawn) -> np.ndarray:
    """The coupler curves shifted by 10 % of the image size, kept where nothing else is drawn."""
    h, w = d.rgb.shape[:2]
    base = np.concatenate([d.curve_px(j) for j in d.curves])
    base = base[np.isfinite(base).all(axis=1)]
    cand = np.concatenate([base + s for s in ([0.1 * w, 0], [-0.1 * w, 0], [0, 0.1 * h], [0, -0.1 * h])])
    keep = (cand[:, 0] > 5) & (cand[:, 0] < w - 5) & (cand[:, 1] > 0.09 * h) & (cand[:, 1] < h - 5)
    cand = cand[keep]
    far = d.all_paths_tree().query(cand)[0] >= 6.0
    cand = cand[far & ~occluded(d.mech, d.t, d.pose, cand) & ~inside_plates(d.mech, d.pose, cand)]
    return cand


def off_curve_report(rgb: np.ndarray, pts: np.ndarray) -> tuple[int, float]:
    """(points with curve colour within 1 px, fraction of points whose pixel is white)."""
    near = near_mask(curve_mask(rgb), pts, 1.5)
    r, c, _ = pixel_index(pts, rgb.shape)
    white = (rgb[r, c] > 245).all(axis=1)
    return int(near.sum()), float(white.mean())


def stray_curve_pixels(d: Drawn, rgb: np.ndarray) -> int:
    """Curve-coloured pixels farther than STRAY_TOL from every computed coupler curve."""
    rows, cols = np.nonzero(curve_mask(rgb))
    centres = np.stack([cols + 0.5, rows + 0.5], axis=-1)
    return int((d.coupler_tree().query(centres)[0] > STRAY_TOL).sum())


# --------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def outdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("plots")


@pytest.fixture(scope="module")
def drawn(outdir):
    cache: dict[str, Drawn] = {}

    def get(key: str, *extra: str, angles: str | None = None) -> Drawn:
        tag = key + "_" + "_".join(extra + ((angles,) if angles else ())).replace(":", "-").replace(",", "-")
        if tag not in cache:
            png = outdir / f"{tag}.png"
            args = ["plot", str(FILES[key]), "-o", str(png), "--dpi", "100", *extra]
            if angles:
                args += ["--angles", angles]
            assert main(args) == 0
            at = float(extra[extra.index("--at") + 1]) if "--at" in extra else None
            cache[tag] = Drawn(key, png, angles, at)
        return cache[tag]

    return get


# --------------------------------------------------------------------------- the curves
@pytest.mark.parametrize("key", ["seed000", "jansen", "seed003"])
def test_coupler_curves_are_drawn_where_computed(drawn, key):
    d = drawn(key)
    expected = {"seed000": ("P",), "jansen": ("W", "F"), "seed003": ("P",)}[key]
    assert set(d.curves) == set(expected)
    t = d.t
    assert t[0] > 0 and t[2] < 0 and abs(t[0] + t[2]) < 1e-9 * abs(t[0])  # to scale, y up
    fr = on_curve_fractions(d, d.rgb, t)
    for j, (unocc, overall, ex) in fr.items():
        assert ex <= 0.35, (j, ex)
        assert unocc >= 0.98, (j, fr)
        assert overall >= 0.90, (j, fr)
    assert stray_curve_pixels(d, d.rgb) == 0

    # NEGATIVE: the same checker fails with the transform shifted by 6 px, and on a blank image
    for dc, dr in ((6, 0), (-6, 0), (0, 6), (0, -6)):
        shifted = [t[0], t[1] + dc, t[2], t[3] + dr]
        assert not curve_is_drawn(d, d.rgb, shifted), (dc, dr, on_curve_fractions(d, d.rgb, shifted))
    blank = np.full_like(d.rgb, 255.0)
    assert not curve_is_drawn(d, blank, t)
    assert max(v[1] for v in on_curve_fractions(d, blank, t).values()) == 0.0


@pytest.mark.parametrize("key", ["seed000", "jansen", "seed003"])
def test_points_off_the_curve_are_background(drawn, key):
    d = drawn(key)
    pts = off_curve_points(d)
    assert len(pts) >= 100, len(pts)
    curve_hits, white = off_curve_report(d.rgb, pts)
    assert curve_hits == 0
    assert white >= 0.95, white
    # NEGATIVE: the same checker on points ON the curve (away from occluders) reports curve colour
    on = np.concatenate([d.curve_px(j) for j in d.curves])
    on = on[np.isfinite(on).all(axis=1)]
    on = on[~occluded(d.mech, d.t, d.pose, on)]
    hits, white_on = off_curve_report(d.rgb, on)
    assert hits >= 0.98 * len(on) and white_on < 0.05


def gap_chord(d: Drawn) -> tuple[np.ndarray, np.ndarray]:
    """Pixel points on the segment joining the curve's ends across the gap, away from the curve."""
    x = d.res.inputs[d.mech.drivers[0].name]
    ok = np.asarray(d.res.assembled, bool)
    p = to_px(d.t, d.res.xy("P"))  # at the samples
    # the samples on either side of the gap, in input order modulo a turn
    order = np.argsort(np.mod(x, 360.0), kind="stable")
    okm = ok[order]
    # last assembled sample before the gap and first after it (cyclically)
    i_last = order[np.flatnonzero(okm)[-1]]
    i_first = order[np.flatnonzero(okm)[0]]
    assert np.mod(x[i_last], 360) == pytest.approx(273, abs=1) and np.mod(x[i_first], 360) == pytest.approx(87, abs=1)
    a, b = p[i_last], p[i_first]
    seg = a + np.linspace(0, 1, int(np.linalg.norm(b - a)) * 2 + 1)[:, None] * (b - a)
    far = d.coupler_tree().query(seg)[0] > 5.0
    return seg[far], np.array([a, b])


@pytest.mark.parametrize("angles", [None, "180:540:1"])
def test_seed003_curve_is_broken_where_it_does_not_assemble(drawn, angles):
    """Not assembled outside ~[86.78, 273.22] deg: no curve pixel across the gap.

    With the file's sweep (0..360) the gap is at both ends of the sample array; with
    --angles 180:540:1 it is in the middle (samples 274..446), where a line that skipped NaNs
    would draw the chord from P(273) to P(447) = P(87).
    """
    d = drawn("seed003", angles=angles)
    ok = np.asarray(d.res.assembled, bool)
    assert 0 < ok.sum() < ok.size
    if angles is not None:
        assert ok[0] and ok[-1]  # the gap is inside the sample array
    assert curve_is_drawn(d, d.rgb, d.t)  # the assembled part is there
    chord, ends = gap_chord(d)
    assert len(chord) > 200, len(chord)
    assert not near_mask(curve_mask(d.rgb), chord, 1.5).any()
    assert stray_curve_pixels(d, d.rgb) == 0
    # NEGATIVE: draw the chord in curve colour -> both checks fail
    im = Image.fromarray(d.rgb.astype(np.uint8))
    ImageDraw.Draw(im).line([tuple(ends[0]), tuple(ends[1])], fill=draw.CURVE_COLOR, width=2)
    bad = np.asarray(im, float)
    assert near_mask(curve_mask(bad), chord, 1.5).mean() > 0.9
    assert stray_curve_pixels(d, bad) > 100


# --------------------------------------------------------------------------- the pose
@pytest.mark.parametrize(
    ("key", "at", "other"), [("seed000", 45, 135), ("seed000", 250, 160), ("seed003", 150, 240), ("jansen", 120, 210)]
)
def test_pins_sit_at_the_solved_joints(drawn, key, at, other):
    d = drawn(key, "--at", str(at))
    name = d.mech.drivers[0].name
    sol = lk.analyze(d.mech, {name: [float(at)]})
    assert bool(sol.assembled[0])
    pins = {j: to_px(d.t, sol.xy(j))[0] for j in d.mech.joint_names}
    for j, (c, r) in pins.items():
        assert is_pin(d.rgb, c, r), (j, ring_at(d.rgb, c, r))
    # the title names the drawn input (and no 'does not assemble' note): read from the figure
    # NEGATIVE: 6 px off, or the joints at another input, are not all pins
    for dc, dr in ((6, 0), (-6, 0), (0, 6), (0, -6)):
        still = [j for j, (c, r) in pins.items() if is_pin(d.rgb, c + dc, r + dr)]
        assert len(still) <= len(pins) // 2, (dc, dr, still)
    wrong = lk.analyze(d.mech, {name: [float(other)]})
    moved = [j for j in d.mech.joint_names if np.linalg.norm(to_px(d.t, wrong.xy(j))[0] - pins[j]) > 10]
    assert moved
    assert not all(is_pin(d.rgb, *to_px(d.t, wrong.xy(j))[0]) for j in moved)
    # the curves are still drawn, under the pose drawn at V
    assert curve_is_drawn(d, d.rgb, d.t), on_curve_fractions(d, d.rgb, d.t)


def test_default_pose_is_the_files_pose(drawn):
    """Without --at the mechanism is drawn at the pose's input (read off the file's joints)."""
    for key in ("seed000", "seed003"):
        d = drawn(key)
        for j, (c, r) in d.pose.items():
            assert is_pin(d.rgb, c, r), (key, j, ring_at(d.rgb, c, r))


@pytest.mark.parametrize("key", ["seed000", "jansen"])
def test_at_the_pose_input_draws_the_ground_as_without_at(drawn, key):
    """`plot --at V` with V the pose's own input draws the same ground symbols as `plot`.

    The ground does not move: each pivot's triangle and hatching must be drawn once, at the
    size of the drawing.  Compared pixel by pixel in a box around each ground pivot (same
    transform in both pictures, same pose, so nothing else differs there).
    """
    plain = drawn(key)
    v = pose_input(plain.mech)
    at = drawn(key, "--at", f"{v:.12g}")
    assert at.t == pytest.approx(plain.t, rel=1e-12, abs=1e-9)
    h, w = plain.rgb.shape[:2]
    for j in plain.mech.link("ground").joints:
        c, r = plain.pose[j]
        box = (slice(max(int(r) - 10, 0), min(int(r) + 40, h)), slice(max(int(c) - 40, 0), min(int(c) + 40, w)))
        differ = int((np.abs(plain.rgb[box] - at.rgb[box]).max(axis=-1) > 40).sum())
        assert differ == 0, f"ground pivot {j}: {differ} pixels differ (ground symbol drawn twice at two sizes?)"


def test_ground_is_drawn_when_the_sweep_never_assembles(outdir):
    """seed003 does not assemble for crank in [0, 80]: the picture still shows the (fixed) ground pivots."""
    png = outdir / "never.png"
    assert main(["plot", str(FILES["seed003"]), "--angles", "0:80:5", "-o", str(png), "--dpi", "100"]) == 0
    rgb, t = read_png(png)
    mech = lk.load(FILES["seed003"])
    for j in mech.link("ground").joints:
        z = mech.joints[j]
        c, r = to_px(t, np.array([[z.real, z.imag]]))[0]
        assert is_pin(rgb, c, r), (j, ring_at(rgb, c, r))


# --------------------------------------------------------------------------- assembly modes
def render(fig: Figure) -> np.ndarray:
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].astype(float)


def panel_pins(ax, lum: np.ndarray, joints: dict[str, tuple[float, float]]) -> tuple[int, int]:
    """(joints checked, joints with a pin) of one mode on one panel; joints within 10 px of another are skipped."""
    h = lum.shape[0]
    names = [j for j, v in joints.items() if v is not None]
    disp = ax.transData.transform(np.array([joints[j] for j in names], float))
    px = np.stack([disp[:, 0], h - disp[:, 1]], axis=-1)
    checked = hit = 0
    for k in range(len(names)):
        others = np.delete(px, k, axis=0)
        if len(others) and np.min(np.linalg.norm(others - px[k], axis=1)) < 10:
            continue
        checked += 1
        hit += is_pin(lum, *px[k])
    return checked, hit


@pytest.mark.parametrize("mirrors", [False, True])
def test_modes_panels_match_lk_modes(outdir, mirrors, capsys):
    path = EXAMPLES / "seed004_stephenson1.yaml"
    mech = lk.load(path)
    name = mech.drivers[0].name
    found = lk.modes(mech, {name: 60.0}, mirrors=mirrors)
    distinct = [m for m in found.modes if m.assembled and m.same_as is None]
    assert len(distinct) == found.distinct == (16 if mirrors else 4)

    # the command line: a non-blank picture
    out = outdir / f"modes_{mirrors}.png"
    mirror = ["--mirrors"] if mirrors else []
    assert main(["plot", "--modes", "--at", "60", str(path), "-o", str(out), "--dpi", "100", *mirror]) == 0
    assert capsys.readouterr().err == ""
    img = np.asarray(Image.open(out).convert("RGB"), float)
    assert (luminance(img) < 100).mean() > 0.002 and (img.min(axis=-1) < 200).mean() > 0.01

    fig = draw.modes_figure(mech, {name: 60.0}, mirrors=mirrors, dpi=100)
    rgb = render(fig)
    assert rgb.shape == img.shape  # the same figure as the command's
    np.testing.assert_array_equal(rgb, img)
    lum = luminance(rgb)
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert len(panels) == found.distinct
    # each panel shows exactly one distinct mode, each mode on exactly one panel
    matched = []
    for ax in panels:
        fits = []
        for i, m in enumerate(distinct):
            checked, hit = panel_pins(ax, lum, m.joints)
            if checked >= 0.75 * len(mech.joint_names) and hit == checked:
                fits.append(i)
        assert len(fits) == 1, (ax.get_title(), fits)
        m = distinct[fits[0]]
        for j, s in m.signs.items():  # the title names the mode's signs
            assert f"{j}{'+' if s > 0 else '-'}" in ax.get_title()
        assert ("(pose)" in ax.get_title()) == bool(m.reference)
        matched.append(fits[0])
    assert sorted(matched) == list(range(len(distinct)))


# --------------------------------------------------------------------------- quantities
def test_plot_quantity_cli_makes_a_picture(outdir, capsys):
    out = outdir / "q.png"
    assert main(["plot", str(FILES["seed000"]), "-q", "coupler.omega", "-q", "angles", "-o", str(out)]) == 0
    assert capsys.readouterr().err == ""
    img = np.asarray(Image.open(out).convert("RGB"), float)
    assert img.shape[0] > 300 and (img.min(axis=-1) < 200).mean() > 0.01


@pytest.mark.parametrize(
    ("key", "name"),
    [("seed000", "coupler.omega"), ("seed000", "P.x"), ("seed003", "rocker.omega"), ("seed003", "P.vy")],
)
def test_plot_quantity_line_is_the_column(key, name):
    res = lk.analyze(lk.load(FILES[key]))
    fig = Figure()
    ax = fig.add_subplot()
    assert draw.plot_quantity(ax, res, name) is ax
    (line,) = ax.get_lines()
    x, y = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
    np.testing.assert_allclose(x, res.inputs[res.mechanism.drivers[0].name], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(y, res.columns()[name], rtol=1e-12, atol=1e-12, equal_nan=True)
    if key == "seed003":
        assert np.isnan(y).any()  # the gap is a gap


def drawn_segments_jump(x: np.ndarray, y: np.ndarray, limit: float) -> bool:
    """Does the polyline draw a segment that jumps by more than `limit` in y?"""
    fin = np.isfinite(x) & np.isfinite(y)
    both = fin[:-1] & fin[1:]
    return bool((np.abs(np.diff(y))[both] > limit).any())


@pytest.mark.parametrize(("key", "link"), [("seed000", "crank"), ("seed003", "crank"), ("jansen", "crank")])
def test_link_angle_is_broken_at_the_wrap(key, link):
    res = lk.analyze(lk.load(FILES[key]))
    col = np.asarray(res.columns()[f"{link}.angle"], float)
    fin = np.isfinite(col[:-1]) & np.isfinite(col[1:])
    wraps = int((np.abs(np.diff(col))[fin] > 180).sum())
    assert wraps >= 1  # the crank turns through +-180: the column jumps
    assert drawn_segments_jump(res.inputs["crank"], col, 180)  # NEGATIVE: the raw column would
    fig = Figure()
    ax = fig.add_subplot()
    draw.plot_quantity(ax, res, f"{link}.angle")
    (line,) = ax.get_lines()
    x, y = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
    assert not drawn_segments_jump(x, y, 180)
    # the line is the column with exactly one break (NaN point) per wrap
    inserted = np.isnan(x)
    assert inserted.sum() == wraps
    np.testing.assert_allclose(x[~inserted], res.inputs["crank"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(y[~inserted], col, rtol=0, atol=1e-12, equal_nan=True)
    # and the samples on both sides of each break are the ones across the wrap
    for i in np.flatnonzero(inserted):
        assert abs(y[i + 1] - y[i - 1]) > 180


# --------------------------------------------------------------------------- formats and errors
@pytest.mark.parametrize("extra", [[], ["--modes", "--at", "30"], ["-q", "coupler.angle"]])
def test_svg_and_pdf_are_valid(outdir, extra, capsys):
    tag = "_".join(extra).replace("-", "").replace(".", "")
    svg, pdf = outdir / f"v{tag}.svg", outdir / f"v{tag}.pdf"
    sweep = [] if "--modes" in extra else ["--angles", "0:360:10"]  # --modes draws one input
    assert main(["plot", str(FILES["seed000"]), *sweep, "-o", str(svg), *extra]) == 0
    assert main(["plot", str(FILES["seed000"]), *sweep, "-o", str(pdf), *extra]) == 0
    assert capsys.readouterr().err == ""
    root = ET.parse(svg).getroot()
    assert root.tag.rsplit("}", 1)[-1] == "svg"
    assert len(list(root.iter())) > 20
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF-") and b"%%EOF" in data[-64:] and len(data) > 2000
    assert sorted(p.name for p in outdir.iterdir() if p.name.startswith(".")) == []  # no temporary left


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["-o", "{d}/x.jpg"], ".png"),
        (["-q", "no.such", "-o", "{d}/x.png"], "no.such"),
        (["--mirrors", "-o", "{d}/x.png"], "--modes"),
        (["--modes", "-q", "crank.angle", "-o", "{d}/x.png"], "--modes"),
        (["-o", "{d}/no_such_dir/x.png"], "x.png"),
        (["-o", "{d}/a_file/x.png"], "x.png"),
        (["--at", "abc", "-o", "{d}/x.png"], "--at"),
    ],
)
def test_bad_outputs_exit_2_with_one_line(tmp_path, capsys, args, needle):
    (tmp_path / "a_file").write_text("not a directory")
    argv = ["plot", str(FILES["seed000"]), "--angles", "0:360:30", *(a.format(d=tmp_path) for a in args)]
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2, (code, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert needle in lines[0], lines[0]
    assert out == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file"]  # nothing written


# --------------------------------------------------------------------------- the pose off the sweep grid, size, dpi
def solved_at_pose(mech) -> tuple[dict[str, float], lk.Result]:
    """Each driver's pose input, read off the file's joints (not from linkagekit), and the solve there."""
    values = {}
    for d in mech.drivers:
        if d.ends is not None:
            a, b = (mech.joints[j] for j in d.ends)
            values[d.name] = abs(b - a)
        else:
            values[d.name] = pose_input(mech) if len(mech.drivers) == 1 else math.nan
    res = lk.analyze(mech, {k: [v] for k, v in values.items()})
    assert bool(res.assembled[0])
    return values, res


@pytest.mark.parametrize(
    ("name", "expected"), [("slider_crank.yaml", {"crank": 53.130102354156}), ("excavator_boom.yaml", None)]
)
def test_default_drawing_is_at_the_poses_own_input_off_the_sweep_grid(outdir, name, expected):
    """slider_crank's pose is at 53.13 deg (sweep 0:360:1) and the excavator's cylinders at 2.3998 and
    3.2822 m (sweeps step 0.011 and 0.009 from the stroke's start): neither is a sample of the sweep, and
    each is drawn where the file puts it, every joint a pin at the solver's position there."""
    mech = lk.load(EXAMPLES / name)
    values, sol = solved_at_pose(mech)
    if expected:
        assert values == pytest.approx(expected, abs=1e-9)
    sweep = lk.analyze(mech)
    for k, v in values.items():
        assert np.min(np.abs(np.asarray(sweep.inputs[k]) - v)) > 1e-4  # off the grid
    png = outdir / f"pose_{name}.png"
    assert main(["plot", str(EXAMPLES / name), "-o", str(png), "--dpi", "100"]) == 0
    rgb, t = read_png(png)
    pins = {j: to_px(t, sol.xy(j))[0] for j in mech.joint_names}
    assert all(is_pin(rgb, c, r) for c, r in pins.values()), {j: ring_at(rgb, c, r) for j, (c, r) in pins.items()}
    # NEGATIVE: the first sample of the sweep (where it was drawn before) is not what is drawn
    first = {j: to_px(t, sweep.xy(j)[:1])[0] for j in mech.joint_names}
    moved = [j for j in mech.joint_names if np.linalg.norm(first[j] - pins[j]) > 10]
    assert moved and not all(is_pin(rgb, *first[j]) for j in moved)


def test_default_picture_is_at_least_1200_px_on_its_long_side(outdir):
    for name in ("slider_crank.yaml", "excavator_boom.yaml", "jansen_leg.yaml"):
        png = outdir / f"default_{name}.png"
        assert main(["plot", str(EXAMPLES / name), "-o", str(png)]) == 0
        w, h = Image.open(png).size
        assert w == 1200 and max(w, h) >= 1200, (name, w, h)
    png = outdir / "default_modes.png"
    assert (
        main(["plot", "--modes", "--mirrors", "--at", "60", str(EXAMPLES / "seed004_stephenson1.yaml"), "-o", str(png)])
        == 0
    )
    w, h = Image.open(png).size
    assert w == 4 * 640  # four panels a row, 3.2 in at 200 dpi each: each panel is readable
    q = outdir / "default_q.png"
    assert main(["plot", str(FILES["seed000"]), "-q", "angles", "-q", "coupler.omega", "-o", str(q)]) == 0
    assert Image.open(q).size[0] == 1200


def test_dpi_and_size_set_the_pixels_and_the_transform(outdir):
    """--size W keeps the drawing's aspect; --size WxH is exact; --dpi scales the picture at a fixed size
    in inches.  The transform in the PNG scales with them: the same file point lands on the same
    fraction of the picture."""
    path = str(EXAMPLES / "slider_crank.yaml")
    got = {}
    for tag, extra in {
        "base": [],
        "dpi": ["--dpi", "100"],
        "w": ["--size", "900"],
        "wh": ["--size", "1000x400"],
    }.items():
        png = outdir / f"size_{tag}.png"
        assert main(["plot", path, "-o", str(png), *extra]) == 0
        rgb, t = read_png(png)
        got[tag] = (rgb.shape[1], rgb.shape[0], t)
    (w0, h0, t0), (w1, h1, t1) = got["base"], got["dpi"]
    assert (w1, h1) == (w0 // 2, h0 // 2) and t1[0] == pytest.approx(t0[0] / 2, rel=1e-9)
    w2, h2, t2 = got["w"]
    assert w2 == 900 and h2 == round(900 * h0 / w0) and t2[0] == pytest.approx(t0[0] * 0.75, rel=1e-9)
    assert got["wh"][:2] == (1000, 400)
    # every picture shows the whole mechanism at its pose: each joint's pixel lies inside it
    _, sol = solved_at_pose(lk.load(EXAMPLES / "slider_crank.yaml"))
    for w, h, t in got.values():
        px = to_px(t, np.concatenate([sol.xy(j) for j in sol.mechanism.joint_names]))
        assert np.all((px > 0) & (px < [w, h])), (w, h, px)


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--dpi", "5"], "--dpi"),
        (["--size", "12x"], "--size"),
        (["--size", "0"], "--size"),
        (["--size", "20000"], "pixels"),
    ],
)
def test_bad_dpi_or_size_is_one_line(tmp_path, capsys, args, needle):
    code = main(["plot", str(EXAMPLES / "slider_crank.yaml"), "-o", str(tmp_path / "x.png"), *args])
    err = capsys.readouterr().err
    assert code == 2 and needle in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x.png").exists()


def test_a_quantity_that_is_rounding_is_drawn_flat_not_zoomed_into():
    """The parallelogram's coupler only translates: its angular velocity is 0 and its angle constant, to rounding
    (1e-13). ``plot -q`` zoomed into the rounding: full-height jags under a '1e-13' offset label (the tables print 0).
    Drawn as the constant it is: the zero on a (-1, 1) axis, a constant within 5 % of its size, no offset; a quantity
    that moves keeps matplotlib's own range."""
    from linkagekit.viz import draw

    res = lk.analyze(lk.load(EXAMPLES / "seed003_ex22.yaml"), {"crank": np.arange(0.0, 171.0, 1.0)})
    omega = np.asarray(res.columns()["coupler.omega"], float)
    assert 0 < np.nanmax(np.abs(omega)) < 1e-9  # rounding, not exactly 0
    fig = draw.quantities_figure(res, [["coupler.omega"], ["coupler.angle"], ["crank.angle"]])
    a, b, c = fig.axes[:3]
    assert a.get_ylim() == (-1.0, 1.0)
    angle = np.asarray(res.columns()["coupler.angle"], float)
    lo, hi = b.get_ylim()
    if np.nanmax(np.abs(angle)) >= draw.PLOT_ROUNDOFF:
        assert abs((lo + hi) / 2 - np.nanmean(angle)) < 1e-9 and abs(hi - lo - 0.1 * np.nanmax(np.abs(angle))) < 1e-9
    else:
        assert (lo, hi) == (-1.0, 1.0)
    lo, hi = c.get_ylim()
    assert lo < 1.0 and hi > 169.0 and (lo, hi) != (-1.0, 1.0)  # the crank turns 170 deg: drawn as matplotlib does
