"""`linkagekit animate`: frame counts, frames that show the solved pose, MP4 through ffmpeg, atomic output.

Where the pins are in a frame is checked against an independent `lk.analyze` at that frame's
input (frames evenly spaced over the sweep, ends included: ``np.linspace(start, stop, N)``).

The pixel transform of a frame is DERIVED FROM THE PICTURE, not taken from the drawing code:
pins (white discs closed by a dark ring) are found by image analysis, and a similarity
``column = s x + tx``, ``row = -s y + ty`` (drawn to scale, y up) is fitted so that the
moving joints solved at the inputs of TWO frames (0 and 20) land on pins found in those
frames (every pin/joint pairing is tried; the winner must put every moving joint of both
frames on a pin, distinct joints >= 8 px apart, residual < 1 px).  The frames checked
(5, 13, 27, 33, 39) are not the ones fitted, so a frame drawn at the wrong pose, place or
scale misses.  Nothing of the figure layout (axes box, margins, limits, dpi) is used.  The
first choice, fitting to the static ground pivots' pins, is impossible: those pins are hidden
under the moving bars in the frames (see `test_gif_ground_pins_are_visible`).
Tolerance: a pin found within 1.5 px of every predicted joint.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image
from scipy import ndimage

import linkagekit as lk
import linkagekit.viz.animate as anim
from helpers import dark_ring_rays, luminance
from linkagekit.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FOURBAR = EXAMPLES / "seed000_fourbar.yaml"
PIN_TOL = 1.5


# --------------------------------------------------------------------------- image helpers
def gif_frames(path: Path) -> list[np.ndarray]:
    im = Image.open(path)
    out = []
    for i in range(im.n_frames):
        im.seek(i)
        out.append(np.asarray(im.convert("RGB"), float))
    return out


def find_pins(rgb: np.ndarray) -> np.ndarray:
    """Centres (column, row) of the pins: small white blobs (4-connected, luminance > 235,
    6 to 45 px, at most 8 px across) closed by a dark ring on >= 14 of 16 rays."""
    lum = luminance(rgb)
    labels, n = ndimage.label(lum > 235)
    found = []
    for k, sl in enumerate(ndimage.find_objects(labels), start=1):
        if sl is None:
            continue
        hh, ww = sl[0].stop - sl[0].start, sl[1].stop - sl[1].start
        if hh > 8 or ww > 8:
            continue
        rows, cols = np.nonzero(labels[sl] == k)
        if not 6 <= rows.size <= 45:
            continue
        c, r = cols.mean() + sl[1].start + 0.5, rows.mean() + sl[0].start + 0.5
        if dark_ring_rays(lum, c, r) >= 14:
            found.append((c, r))
    return np.array(found).reshape(-1, 2)


def moving_joints(mech) -> list[str]:
    ground = set(mech.link("ground").joints)
    return [j for j in mech.joint_names if j not in ground]


def solved(mech, value: float) -> dict[str, complex]:
    res = lk.analyze(mech, {mech.drivers[0].name: [float(value)]})
    assert bool(res.assembled[0])
    return {j: complex(*res.xy(j)[0]) for j in mech.joint_names}


def fit_transform(mech, shots: list[tuple[np.ndarray, float]]) -> list[float]:
    """[sx, tx, sy, ty] fitted to the pins found in some frames, each at its known input.

    Drawn to scale with y up: column = s x + tx, row = -s y + ty.  Every pair of (moving
    joint, pin found) in the first frame proposes a transform; the one under which every
    moving joint of every given frame has a pin within PIN_TOL wins and is refined by least
    squares; its residual must stay below 1 px.  A transform that puts two joints closer than
    8 px (one pin for several joints) is not a candidate.  Fails (AssertionError) when none fits.
    """
    moving = moving_joints(mech)
    data = [(find_pins(f), solved(mech, v)) for f, v in shots]
    pins0, pos0 = data[0]
    # pins are ~10 px wide: distinct joints must land >= 8 px apart (no collapsed fit)
    closest = min(abs(pos[a] - pos[b]) for _, pos in data for a in moving for b in moving if a < b)
    best: tuple[int, list[float]] | None = None
    for j1, j2 in ((a, b) for a in moving for b in moving if a != b):
        z1, z2 = pos0[j1], pos0[j2]
        for p1 in pins0:
            for p2 in pins0:
                if p1 is p2:
                    continue
                dz = z2 - z1
                s = ((p2[0] - p1[0]) * dz.real - (p2[1] - p1[1]) * dz.imag) / abs(dz) ** 2
                if s * closest < 8:
                    continue
                t = [s, p1[0] - s * z1.real, -s, p1[1] + s * z1.imag]
                hits = sum(
                    len(pins) > 0 and np.min(np.linalg.norm(pins - to_px(t, pos[j]), axis=1)) <= PIN_TOL
                    for pins, pos in data
                    for j in moving
                )
                if best is None or hits > best[0]:
                    best = (hits, t)
    assert best is not None and best[0] == len(moving) * len(data), best
    t = best[1]
    a, b = [], []
    for pins, pos in data:
        for j in moving:
            z = pos[j]
            c, r = pins[np.argmin(np.linalg.norm(pins - to_px(t, z), axis=1))]
            a += [[z.real, 1, 0], [-z.imag, 0, 1]]
            b += [c, r]
    (s, tx, ty), *_ = np.linalg.lstsq(np.array(a), np.array(b), rcond=None)
    resid = np.array(a) @ np.array([s, tx, ty]) - np.array(b)
    assert s > 0 and np.abs(resid).max() < 1.0, resid
    return [float(s), float(tx), float(-s), float(ty)]


def to_px(t: list[float], z: complex) -> np.ndarray:
    return np.array([t[0] * z.real + t[1], t[2] * z.imag + t[3]])


def predicted(mech, value: float, t: list[float], joints: list[str] | None = None) -> dict[str, np.ndarray]:
    pos = solved(mech, value)
    return {j: to_px(t, pos[j]) for j in (joints or moving_joints(mech))}


def pins_missing(frame: np.ndarray, joints: dict[str, np.ndarray]) -> list[str]:
    """The joints with no pin found within PIN_TOL of their pixel."""
    pins = find_pins(frame)
    return [j for j, p in joints.items() if not len(pins) or np.min(np.linalg.norm(pins - p, axis=1)) > PIN_TOL]


def with_sweep(tmp_path: Path, start: float, stop: float, step: float) -> Path:
    d = yaml.safe_load(FOURBAR.read_text())
    d["drivers"][0]["angles"] = {"start": start, "stop": stop, "step": step}
    p = tmp_path / "fourbar.yaml"
    p.write_text(yaml.safe_dump(d))
    return p


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


# --------------------------------------------------------------------------- GIF
@pytest.fixture(scope="module")
def gif40(tmp_path_factory) -> tuple[Path, list[np.ndarray]]:
    out = tmp_path_factory.mktemp("anim") / "fourbar.gif"
    assert main(["animate", str(FOURBAR), "-o", str(out), "--frames", "40"]) == 0
    return out, gif_frames(out)


def test_gif_has_the_frames_asked_and_they_differ(gif40):
    path, frames = gif40
    assert Image.open(path).n_frames == 40 == len(frames)
    shapes = {f.shape for f in frames}
    assert len(shapes) == 1
    for i in range(39):
        assert np.abs(frames[i] - frames[i + 1]).max() > 50, f"frames {i} and {i + 1} are alike"
    assert (luminance(frames[0]) < 100).mean() > 0.002  # not blank


def test_gif_plays_at_the_frame_rate_asked(gif40):
    """A GIF stores frame times in hundredths of a second: 24 fps (41.7 ms) was written as 40 ms, 30 fps as 30 ms
    (33.3 fps). The times alternate so that the frames end on time: 40 frames at 24 fps play 1.667 s."""
    path, _ = gif40
    with Image.open(path) as im:
        times = []
        for k in range(im.n_frames):
            im.seek(k)
            times.append(im.info["duration"])
    assert set(times) == {40, 50} and abs(sum(times) - 40 * 1000 / 24) <= 5


@pytest.fixture(scope="module")
def fitted(gif40) -> list[float]:
    """The pixel transform of the frames, fitted to frames 0 and 20 only (see the module docstring)."""
    _, frames = gif40
    values = np.linspace(0.0, 360.0, 40)
    return fit_transform(lk.load(FOURBAR), [(frames[0], values[0]), (frames[20], values[20])])


@pytest.mark.parametrize("k", [5, 13, 27, 33, 39])
def test_gif_frame_shows_the_pose_at_its_input(gif40, fitted, k):
    """Frame k (not one the transform was fitted to) has its pins where lk.analyze puts the joints."""
    _, frames = gif40
    mech = lk.load(FOURBAR)
    values = np.linspace(0.0, 360.0, 40)  # the file's sweep 0..360 in 40 frames, ends included
    assert pins_missing(frames[k], predicted(mech, values[k], fitted)) == []
    # NEGATIVE: the pose of another frame does not fit this frame, nor this pose 6 px off
    other = (k + 3) % 39
    assert len(pins_missing(frames[k], predicted(mech, values[other], fitted))) >= 2
    shifted = {j: p + [6.0, 0.0] for j, p in predicted(mech, values[k], fitted).items()}
    assert pins_missing(frames[k], shifted) == list(shifted)


def test_gif_ground_pins_are_visible(gif40, fitted):
    """The ground pivots' pins show in every frame, on top of the links, as in `plot`.

    (A moving bar drawn over the static background would hide the pin it turns about.)
    """
    _, frames = gif40
    mech = lk.load(FOURBAR)
    ground = {j: to_px(fitted, mech.joints[j]) for j in mech.link("ground").joints}
    hidden = {k: pins_missing(frames[k], ground) for k in (0, 10, 20, 30)}
    assert all(not v for v in hidden.values()), f"ground pins hidden in frames: {hidden}"


def test_gif_frames_carry_the_coupler_curve(gif40, fitted):
    """The path of P (computed by lk.analyze) is drawn in curve colour in every frame (palette-quantised)."""
    from linkagekit.viz.draw import CURVE_COLOR

    _, frames = gif40
    mech = lk.load(FOURBAR)
    curve = lk.analyze(mech, {"crank": np.arange(0.0, 361.0, 2.0)}).xy("P")
    px = np.stack([fitted[0] * curve[:, 0] + fitted[1], fitted[2] * curve[:, 1] + fitted[3]], axis=-1)
    rgb = np.array([int(CURVE_COLOR[i : i + 2], 16) for i in (1, 3, 5)], float)
    for k in (0, 20):
        mask = np.linalg.norm(frames[k] - rgb, axis=-1) < 60
        dist = ndimage.distance_transform_edt(~mask)
        near = dist[np.floor(px[:, 1]).astype(int), np.floor(px[:, 0]).astype(int)] <= 2
        assert near.mean() >= 0.9, (k, near.mean())
        shifted = dist[np.floor(px[:, 1]).astype(int) + 6, np.floor(px[:, 0]).astype(int) + 6] <= 2
        assert shifted.mean() < 0.5  # NEGATIVE


def test_gif_frames_where_it_does_not_assemble_show_no_mechanism(tmp_path):
    """seed003 assembles for crank in ~[86.78, 273.22] deg: frames outside show only the ground."""
    src = EXAMPLES / "seed003_ex21.yaml"
    mech = lk.load(src)
    out = tmp_path / "ex21.gif"
    assert main(["animate", str(src), "-o", str(out), "--angles", "0:350:10"]) == 0
    frames = gif_frames(out)
    values = np.arange(0.0, 351.0, 10.0)
    assert len(frames) == len(values) == 36
    t = fit_transform(mech, [(frames[9], values[9]), (frames[18], values[18])])
    assert pins_missing(frames[12], predicted(mech, values[12], t)) == []
    # the drawing's box: every joint over the assembled sweep, plus 15 px (the note below it has letters)
    res = lk.analyze(mech, {"crank": values})
    allxy = np.concatenate([res.xy(j) for j in mech.joint_names])
    allxy = allxy[np.isfinite(allxy).all(axis=1)]
    px = np.stack([t[0] * allxy[:, 0] + t[1], t[2] * allxy[:, 1] + t[3]], axis=-1)
    lo, hi = px.min(axis=0), px.max(axis=0)
    lo, hi = lo - 15, hi + 15
    ground = np.array([to_px(t, mech.joints[j]) for j in mech.link("ground").joints])
    for k in (0, 3, 8, 28, 35):  # 0, 30, 80, 280, 350 deg: not assembled
        assert not bool(res.assembled[k])
        pins = find_pins(frames[k])
        pins = pins[((pins >= lo) & (pins <= hi)).all(axis=1)]
        assert len(pins) == len(ground), (k, pins)  # only the ground pivots (nothing covers them here)
        assert all(np.min(np.linalg.norm(ground - p, axis=1)) <= PIN_TOL for p in pins)
    # frames differ even where it does not assemble (the note names the input)
    assert np.abs(frames[0] - frames[3]).max() > 50


def test_fit_is_not_circular(gif40):
    """The fit needs pins at the right poses: it fails on a blank frame and with the wrong inputs."""
    _, frames = gif40
    mech = lk.load(FOURBAR)
    blank = np.full_like(frames[0], 255.0)
    assert len(find_pins(blank)) == 0
    with pytest.raises(AssertionError):
        fit_transform(mech, [(blank, 0.0), (blank, 180.0)])
    values = np.linspace(0.0, 360.0, 40)
    with pytest.raises(AssertionError):
        fit_transform(mech, [(frames[0], values[3]), (frames[20], values[23])])


@pytest.mark.parametrize(("sweep", "expected"), [((0, 90, 10), 36), ((0, 360, 10), 37)])
def test_default_frame_count_is_the_sweep_samples_at_least_36(tmp_path, sweep, expected):
    src = with_sweep(tmp_path, *sweep)
    mech = lk.load(src)
    assert len(mech.drivers[0].sweep.values()) == (10 if expected == 36 else 37)
    out = tmp_path / "a.gif"
    assert main(["animate", str(src), "-o", str(out)]) == 0
    frames = gif_frames(out)
    assert len(frames) == expected == Image.open(out).n_frames
    # evenly over the file's sweep, ends included: fitted on two frames, checked on three others
    values = np.linspace(sweep[0], sweep[1], expected)
    t = fit_transform(mech, [(frames[0], values[0]), (frames[expected // 2], values[expected // 2])])
    for k in (expected // 4, 3 * expected // 4, expected - 1):
        assert pins_missing(frames[k], predicted(mech, values[k], t)) == [], (k, values[k])
        assert pins_missing(frames[k], predicted(mech, values[k - 2], t)) != [], (k, values[k])


# --------------------------------------------------------------------------- MP4
def test_mp4_frame_count(tmp_path, capsys):
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    if anim.find_ffmpeg() is None:
        pytest.skip("no ffmpeg")
    out = tmp_path / "a.mp4"
    assert main(["animate", str(FOURBAR), "-o", str(out), "--frames", "40", "--angles", "0:360:10"]) == 0
    assert capsys.readouterr().err == ""
    n, secs = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert n == 40
    assert secs == pytest.approx(40 / 24, abs=0.1)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4"]


def test_mp4_without_ffmpeg_says_how_to_get_it(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(anim, "find_ffmpeg", lambda: None)
    out = tmp_path / "a.mp4"
    code = main(["animate", str(FOURBAR), "-o", str(out), "--angles", "0:360:10"])
    _, err = capsys.readouterr()
    assert code == 1  # a missing tool, not bad input
    line = one_line(err)
    assert "ffmpeg" in line and "install" in line, line
    assert list(tmp_path.iterdir()) == []  # no partial output


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["-o", "{d}/a.avi"], ".gif"),
        (["-o", "{d}/a.gif", "--frames", "1"], "--frames"),
        # an animation has at least 36 frames (the contract's `animate`): --frames took 2 to 35 as well
        (["-o", "{d}/a.gif", "--frames", "35"], "--frames: expected 36 to 1000 frames, got 35"),
        (["-o", "{d}/a.gif", "--fps", "0"], "--fps"),
        (["-o", "{d}/nodir/a.gif", "--angles", "0:360:10"], "a.gif"),
    ],
)
def test_bad_animate_arguments_exit_2(tmp_path, capsys, args, needle):
    code = main(["animate", str(FOURBAR), *(a.format(d=tmp_path) for a in args)])
    _, err = capsys.readouterr()
    assert code == 2, err
    assert needle in one_line(err)
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- atomic output
def failing_frames(after: int, exc: BaseException):
    """A Frames.__iter__ that fails after ``after`` frames."""
    real = anim.Frames.__iter__

    def frames(self):
        for i, f in enumerate(real(self)):
            if i == after:
                raise exc
            yield f

    return frames


@pytest.mark.parametrize(
    ("suffix", "exc"),
    [
        (".gif", RuntimeError("boom")),
        (".gif", KeyboardInterrupt()),
        (".mp4", OSError(errno.ENOSPC, "No space left on device")),
        (".mp4", RuntimeError("boom")),
    ],
)
def test_failure_midway_leaves_the_previous_file(tmp_path, capsys, monkeypatch, suffix, exc):
    if suffix == ".mp4" and anim.find_ffmpeg() is None:
        pytest.skip("no ffmpeg")
    out = tmp_path / f"a{suffix}"
    previous = b"the previous animation " * 100
    out.write_bytes(previous)
    os.chmod(out, 0o640)
    monkeypatch.setattr(anim.Frames, "__iter__", failing_frames(5, exc))
    code = main(["animate", str(FOURBAR), "-o", str(out), "--angles", "0:360:10"])
    _, err = capsys.readouterr()
    assert code in (1, 2)
    one_line(err)
    assert out.read_bytes() == previous
    assert oct(os.stat(out).st_mode & 0o777) == oct(0o640)
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]  # no temporary file left

    # and with the real frames the same call replaces it whole
    monkeypatch.undo()
    assert main(["animate", str(FOURBAR), "-o", str(out), "--angles", "0:360:10"]) == 0
    assert out.read_bytes() != previous
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]
    if suffix == ".gif":
        assert Image.open(out).n_frames == 37
