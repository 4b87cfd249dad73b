"""Target points for synthesis: CSV and SVG readers, the closing rule, and one-line errors for bad files."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from linkagekit.errors import InputError
from linkagekit.synthesis.targets import (
    MAX_FILE_BYTES,
    MAX_POINTS,
    Targets,
    read_targets,
    targets_from_array,
)

SVG_NS = 'xmlns="http://www.w3.org/2000/svg"'


def write(tmp_path: Path, name: str, body: str | bytes) -> Path:
    p = tmp_path / name
    if isinstance(body, bytes):
        p.write_bytes(body)
    else:
        p.write_text(body, encoding="utf-8")
    return p


def svg(d: str, extra: str = "") -> str:
    return f'<svg {SVG_NS} width="200" height="200"><g>{extra}<path d="{d}" fill="none"/></g></svg>'


def assert_one_line_error(exc: InputError, source: str | Path) -> str:
    msg = str(exc)
    assert msg.startswith(f"{source}: "), msg
    assert "\n" not in msg and "\r" not in msg
    assert len(msg) <= 300
    return msg


def expect_error(path: Path, **kwargs: object) -> str:
    with pytest.raises(InputError) as info:
        read_targets(path, **kwargs)  # type: ignore[arg-type]
    return assert_one_line_error(info.value, path)


# ---------------------------------------------------------------------- CSV, valid
def test_csv_xy(tmp_path: Path) -> None:
    p = write(tmp_path, "targets.csv", "x,y\n0,0\n1.5,0\n1.5,2\n-1e-3,2.25\n")
    t = read_targets(p)
    assert isinstance(t, Targets)
    assert t.xy.shape == (4, 2) and t.xy.dtype == float
    np.testing.assert_array_equal(t.xy, [[0, 0], [1.5, 0], [1.5, 2], [-1e-3, 2.25]])
    assert t.inputs is None and not t.closed and t.unit == "m" and t.source == str(p)
    assert len(t) == 4
    assert t.diagonal == pytest.approx(math.hypot(1.501, 2.25), rel=1e-12)


def test_csv_with_input_any_case_spaces_and_order(tmp_path: Path) -> None:
    p = write(tmp_path, "timed.csv", " Input , X ,y\n0, 1, 2\n90 ,3,4\n180,5,7\n")
    t = read_targets(p)
    np.testing.assert_array_equal(t.xy, [[1, 2], [3, 4], [5, 7]])
    assert t.inputs is not None
    np.testing.assert_array_equal(t.inputs, [0, 90, 180])
    assert t.timed and not t.closed


def test_comments_blank_lines_bom_and_crlf(tmp_path: Path) -> None:
    body = "# targets for the test\r\n\r\n  # indented comment\r\nx,y\r\n0,0\r\n\r\n# between\r\n1,0\r\n   \r\n0,1\r\n"
    p = write(tmp_path, "c.csv", b"\xef\xbb\xbf" + body.encode())
    t = read_targets(p)
    np.testing.assert_array_equal(t.xy, [[0, 0], [1, 0], [0, 1]])


def test_arrays_are_read_only(tmp_path: Path) -> None:
    t = read_targets(write(tmp_path, "t.csv", "x,y,input\n0,0,0\n1,0,10\n0,1,20\n"))
    with pytest.raises(ValueError):
        t.xy[0, 0] = 5.0
    assert t.inputs is not None
    with pytest.raises(ValueError):
        t.inputs[0] = 5.0
    src = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    t2 = targets_from_array(src)
    src[0, 0] = 9.0  # a copy is kept
    assert t2.xy[0, 0] == 0.0


@pytest.mark.parametrize("unit", ["mm", "cm", "m", "in"])
def test_units_kept(tmp_path: Path, unit: str) -> None:
    t = read_targets(write(tmp_path, "u.csv", "x,y\n0,0\n10,0\n0,10\n"), units=unit)
    assert t.unit == unit
    np.testing.assert_array_equal(t.xy, [[0, 0], [10, 0], [0, 10]])  # numbers are not converted


# ---------------------------------------------------------------------- closed curves
def test_closed_when_last_repeats_first(tmp_path: Path) -> None:
    t = read_targets(write(tmp_path, "closed.csv", "x,y\n0,0\n2,0\n2,1\n0,1\n0,0\n"))
    assert t.closed and len(t) == 4
    np.testing.assert_array_equal(t.xy[-1], [0, 1])


def test_closed_within_tolerance_and_open_outside(tmp_path: Path) -> None:
    # diagonal 5: 1e-9 * 5 = 5e-9 is the tolerance
    near = read_targets(write(tmp_path, "near.csv", "x,y\n0,0\n3,0\n3,4\n0,4\n4e-9,0\n"))
    assert near.closed and len(near) == 4
    far = read_targets(write(tmp_path, "far.csv", "x,y\n0,0\n3,0\n3,4\n0,4\n1e-6,0\n"))
    assert not far.closed and len(far) == 5


def test_closed_with_inputs_modulo_360(tmp_path: Path) -> None:
    t = read_targets(write(tmp_path, "a.csv", "x,y,input\n0,0,10\n1,0,100\n1,1,200\n0,0,370\n"))
    assert t.closed and len(t) == 3
    assert t.inputs is not None
    np.testing.assert_array_equal(t.inputs, [10, 100, 200])
    # the same point at another input: the curve is visited twice, not closed
    u = read_targets(write(tmp_path, "b.csv", "x,y,input\n0,0,10\n1,0,100\n1,1,200\n0,0,190\n"))
    assert not u.closed and len(u) == 4


def test_targets_from_array_closing_rule() -> None:
    square = [[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]]
    auto = targets_from_array(square)
    assert auto.closed and len(auto) == 4 and auto.source == "<memory>"
    forced_open = targets_from_array(square, closed=False)
    assert not forced_open.closed and len(forced_open) == 5
    forced_closed = targets_from_array(square[:-1], closed=True)
    assert forced_closed.closed and len(forced_closed) == 4
    assert targets_from_array(square, closed=True) == auto
    assert not targets_from_array(square[:-1]).closed
    timed = targets_from_array(square, inputs=[0, 90, 180, 270, -360])
    assert timed.closed and len(timed) == 4
    assert not targets_from_array(square, inputs=[0, 90, 180, 270, 1]).closed


def test_targets_from_array_errors() -> None:
    cases = [
        ([[0, 0], [1, 0]], {}, "2 target points; at least 3 are needed"),
        ([[0, 0], [1, 0], [0, 0]], {}, "2 target points once the last"),
        ([0, 1, 2], {}, "shape (m, 2)"),
        ([[0, 0], [1, 0], [0, math.nan]], {}, "point 3: y is not finite"),
        ([[0, 0], [1, 0], [0, 1]], {"inputs": [0, 1]}, "shape (3,)"),
        ([[0, 0], [1, 0], [0, 1]], {"inputs": [0, 1, math.inf]}, "point 3: input is not finite"),
        ([[1, 1], [1, 1], [1, 1]], {}, "no extent"),
        ([[-1e308, 0], [1e308, 0], [0, 1]], {}, "not a finite number"),
        ([["a", "b"], [1, 0], [0, 1]], {}, "not numbers"),
        ([[0, 0], [1, 0], [0, 1]], {"unit": "km"}, "unknown length unit 'km'"),
        ([[0, 0], [1, 0], [0, 1]], {"closed": "yes"}, "closed must be"),
    ]
    for xy, kwargs, fragment in cases:
        with pytest.raises(InputError) as info:
            targets_from_array(xy, source="pts", **kwargs)  # type: ignore[arg-type]
        msg = assert_one_line_error(info.value, "pts")
        assert fragment in msg, (fragment, msg)


# ---------------------------------------------------------------------- CSV, bad files
BAD_CSV = [
    ("abc.csv", "x,y\n0,0\n1,0\nabc,2\n", "line 4: 'abc' is not a number"),
    ("hdr.csv", "a,b\n0,0\n", "expected the header 'x,y' or 'x,y,input', got 'a,b'"),
    ("hdr2.csv", "x,y,z\n0,0,0\n", "expected the header"),
    ("hdr3.csv", "x,x\n0,0\n", "expected the header"),
    ("nohdr.csv", "0,0\n1,0\n0,1\n", "got '0,0'"),
    ("two.csv", "x,y\n0,0\n1,0\n", "2 target points; at least 3 are needed"),
    ("none.csv", "x,y\n# nothing\n", "no target points after the header"),
    ("nan.csv", "x,y\n0,0\nnan,1\n", "line 3: x is not finite (nan)"),
    ("inf.csv", "x,y,input\n0,0,0\n1,1,-inf\n", "line 3: input is not finite (-inf)"),
    ("cols.csv", "x,y\n0,0\n1,0,5\n0,1\n", "line 3: 3 values, expected 2 (x,y)"),
    ("cols2.csv", "x,y,input\n0,0,1\n1,0\n", "line 3: 2 values, expected 3"),
    ("emptycell.csv", "x,y\n0,0\n,1\n0,1\n", "line 3: x is empty"),
    ("same.csv", "x,y\n2,3\n2,3\n2,3\n2,3\n", "no extent"),
    ("quote.csv", 'x,y\n0,0\n"1,2\n', "line 3: not a CSV row"),
    ("comments.csv", "# only\n\n# comments\n", "no header line"),
    ("empty.csv", "", "empty file"),
    ("blank.csv", "\n  \n\n", "empty file"),
    ("nul.csv", b"x,y\n0,0\x00\n", "binary file"),
    ("latin.csv", b"x,y\n0,0\n1,\xe90\n", "not UTF-8 text (byte 10)"),
    ("random.csv", bytes(range(256)), "binary file"),
]


@pytest.mark.parametrize(("name", "body", "fragment"), BAD_CSV, ids=[c[0] for c in BAD_CSV])
def test_bad_csv(tmp_path: Path, name: str, body: str | bytes, fragment: str) -> None:
    msg = expect_error(write(tmp_path, name, body))
    assert fragment in msg, msg


def test_missing_file_and_directory(tmp_path: Path) -> None:
    assert "no such file" in expect_error(tmp_path / "missing.csv")
    (tmp_path / "dir.csv").mkdir()
    assert "is a directory" in expect_error(tmp_path / "dir.csv")


def test_too_large_file(tmp_path: Path) -> None:
    line = "# " + "c" * 1021 + "\n"  # 1024 bytes
    body = "x,y\n0,0\n1,0\n0,1\n" + line * (MAX_FILE_BYTES // len(line) + 1)
    assert "10 MiB" in expect_error(write(tmp_path, "big.csv", body))


def test_too_many_points(tmp_path: Path) -> None:
    body = "x,y\n" + "".join(f"{i % 7},{i % 5}\n" for i in range(MAX_POINTS + 1))
    msg = expect_error(write(tmp_path, "many.csv", body))
    assert f"line {MAX_POINTS + 2}: more than {MAX_POINTS} target points" in msg
    enough = write(tmp_path, "enough.csv", "x,y\n" + "".join(f"{i},{i % 5}\n" for i in range(MAX_POINTS)))
    assert len(read_targets(enough, smooth=False)) == MAX_POINTS  # every point read
    assert len(read_targets(enough)) == 400  # a drawing, smoothed, is taken at 400 points along it


@pytest.mark.parametrize("units", ["km", "M", "", None, 1])
def test_unknown_units(tmp_path: Path, units: object) -> None:
    msg = expect_error(write(tmp_path, "t.csv", "x,y\n0,0\n1,0\n0,1\n"), units=units)
    assert "unknown length unit" in msg


@pytest.mark.parametrize("points", [2, 0, -1, MAX_POINTS + 1, 3.5, True, "40"])
def test_bad_points(tmp_path: Path, points: object) -> None:
    assert "points must be" in expect_error(write(tmp_path, "t.svg", svg("M0 0 L 1 0 L 1 1")), points=points)


def test_not_a_path_argument() -> None:
    with pytest.raises(InputError, match="expected a file path"):
        read_targets(12)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="NUL byte"):
        read_targets("a\x00b.csv")


def test_long_quoted_values_are_shortened(tmp_path: Path) -> None:
    msg = expect_error(write(tmp_path, "long.csv", "x,y\n0,0\n1," + "z" * 5000 + "\n"))
    assert "…" in msg and len(msg) <= 300


# ---------------------------------------------------------------------- fuzz
def _check_reads_or_fails(name: str, data: bytes) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / name
        p.write_bytes(data)
        try:
            t = read_targets(p, points=5)
        except InputError as exc:  # anything else fails the test
            assert_one_line_error(exc, p)
        else:
            assert len(t) >= 3 and np.all(np.isfinite(t.xy)) and t.diagonal > 0


CSV_ALPHABET = "xyinput,XY#\n\r \t\"'0123456789.-+eEnaf_;\x00é"


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    name=st.sampled_from(["t.csv", "t.txt", "t.svg", "T.SVG"]),
    data=st.one_of(
        st.binary(max_size=300),
        st.text(max_size=300).map(lambda s: s.encode("utf-8", "surrogatepass")),
        st.text(alphabet=CSV_ALPHABET, max_size=300).map(lambda s: s.encode()),
        st.lists(
            st.lists(st.one_of(st.floats(), st.integers(), st.text(alphabet="0123456789.-e", max_size=6)), max_size=4),
            max_size=12,
        ).map(lambda rows: ("x,y,input\n" + "\n".join(",".join(map(str, r)) for r in rows)).encode()),
    ),
)
def test_fuzz_files_raise_only_input_error(name: str, data: bytes) -> None:
    _check_reads_or_fails(name, data)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    d=st.text(alphabet="MmLlHhVvCcSsQqTtAaZz0123456789.-+eE, \n", max_size=80),
    wrap=st.sampled_from(["plain", "ns", "transform"]),
)
def test_fuzz_svg_path_data_raises_only_input_error(d: str, wrap: str) -> None:
    body = {
        "plain": f'<svg><path d="{d}"/></svg>',
        "ns": svg(d),
        "transform": f'<svg><g transform="scale(2)"><path d="{d}"/></g></svg>',
    }[wrap]
    _check_reads_or_fails("fuzz.svg", body.encode())


# ---------------------------------------------------------------------- SVG
CIRCLE = "M 60 50 A 10 10 0 0 1 40 50 A 10 10 0 0 1 60 50 Z"  # centre (50, 50), radius 10, in SVG coordinates


def test_svg_circle_two_arcs(tmp_path: Path) -> None:
    n = 40
    t = read_targets(write(tmp_path, "circle.svg", svg(CIRCLE)), units="mm", points=n)
    assert len(t) == n and t.closed and t.inputs is None and t.unit == "mm"
    # y is negated: the centre is (50, -50)
    radius = np.hypot(t.xy[:, 0] - 50.0, t.xy[:, 1] + 50.0)
    assert np.max(np.abs(radius - 10.0)) < 1e-6
    # equally spaced in arc length: equal chords all round, the start not repeated at the end
    loop = np.vstack([t.xy, t.xy[:1]])
    chords = np.hypot(*np.diff(loop, axis=0).T)
    assert chords.min() > 0
    assert (chords.max() - chords.min()) / chords.mean() < 1e-3
    assert chords.mean() == pytest.approx(2 * 10.0 * math.sin(math.pi / n), rel=1e-3)
    # the start, and a quarter of the way round: sweep-flag 1 turns towards +y in SVG (down), -y here
    np.testing.assert_allclose(t.xy[0], [60.0, -50.0], atol=1e-9)
    np.testing.assert_allclose(t.xy[n // 4], [50.0, -60.0], atol=1e-6)
    assert t.xy[n // 4, 1] < -59.0


def test_svg_closed_without_z_and_open(tmp_path: Path) -> None:
    no_z = read_targets(write(tmp_path, "noz.svg", svg(CIRCLE[:-2])), points=12)
    assert no_z.closed and len(no_z) == 12
    half = read_targets(write(tmp_path, "half.svg", svg("M 60 50 A 10 10 0 0 1 40 50")), points=5)
    assert not half.closed
    r = 10 * math.sqrt(0.5)
    expected = np.array([[60, -50], [50 + r, -50 - r], [50, -60], [50 - r, -50 - r], [40, -50]])
    np.testing.assert_allclose(half.xy, expected, atol=1e-9)


def test_svg_lines_and_cubic_equal_arc_length(tmp_path: Path) -> None:
    d = "M 0 0 L 100 0 C 150 0 150 100 100 100 L 0 100"
    n = 41
    t = read_targets(write(tmp_path, "shape.svg", svg(d)), points=n)
    assert not t.closed and len(t) == n
    # an independent dense reference of the same curve, in the flipped frame
    u = np.linspace(0.0, 1.0, 100_001)[:, None]
    p0, p1, p2, p3 = (np.array(v, float) for v in ([100, 0], [150, 0], [150, 100], [100, 100]))
    cubic = (1 - u) ** 3 * p0 + 3 * (1 - u) ** 2 * u * p1 + 3 * (1 - u) * u**2 * p2 + u**3 * p3
    line1 = np.column_stack([np.linspace(0, 100, 100_001), np.zeros(100_001)])
    line2 = np.column_stack([np.linspace(100, 0, 100_001), np.full(100_001, 100.0)])
    ref = np.vstack([line1, cubic[1:], line2[1:]]) * [1.0, -1.0]
    s_ref = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ref, axis=0).T))])
    total = s_ref[-1]
    nearest = np.array([np.argmin(np.hypot(*(ref - p).T)) for p in t.xy])
    gaps = np.hypot(*(ref[nearest] - t.xy).T)
    assert gaps.max() < 1e-2  # every point is on the curve (to the reference's resolution)
    s = s_ref[nearest]
    np.testing.assert_allclose(np.diff(s), total / (n - 1), rtol=1e-3)
    np.testing.assert_allclose(t.xy[0], [0, 0], atol=1e-12)
    np.testing.assert_allclose(t.xy[-1], [0, -100], atol=1e-9)
    assert np.all(t.xy[:, 1] <= 1e-12)  # y flipped: the drawing is below the x axis
    assert t.xy[1, 0] == pytest.approx(total / (n - 1), rel=1e-4) and t.xy[1, 1] == 0.0


def test_svg_quadratic_and_rotated_elliptic_arc_follow_svg_path(tmp_path: Path) -> None:
    from svg.path import parse_path

    d = "M 10 80 Q 52.5 10 95 80 T 180 80 A 45 25 -30 1 0 10 80"  # closed by its end, no Z
    n = 60
    t = read_targets(write(tmp_path, "qa.svg", svg(d)), points=n)
    assert t.closed and len(t) == n
    # the reference: svg.path's own points, densely, in the flipped frame
    u = np.linspace(0.0, 1.0, 40_001)
    ref = np.concatenate([[seg.point(float(v)) for v in u] for seg in parse_path(d)[1:]])
    ref = np.column_stack([ref.real, -ref.imag])
    s_ref = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ref, axis=0).T))])
    total = s_ref[-1]
    nearest = np.array([np.argmin(np.hypot(*(ref - p).T)) for p in t.xy])
    assert np.hypot(*(ref[nearest] - t.xy).T).max() < 1e-2  # on the curve, to the reference's resolution
    steps = np.diff(np.append(s_ref[nearest], total))
    np.testing.assert_allclose(steps, total / n, rtol=1e-3)


def test_svg_first_path_with_d_and_no_namespace(tmp_path: Path) -> None:
    body = '<svg><rect width="3" height="3"/><path id="empty"/><path d="M0 0 H 4 V 3"/><path d="M9 9 L 1 1"/></svg>'
    t = read_targets(write(tmp_path, "plain.svg", body), points=3)
    np.testing.assert_allclose(t.xy, np.array([[0, 0], [3.5, 0], [4, -3]]), atol=1e-9)  # length 7: 0, 3.5, 7
    assert not t.closed


BAD_SVG = [
    ("tr.svg", svg("M0 0 L 1 0 L 1 1").replace("<path ", '<path transform="translate(3,4)" '), "transforms are not"),
    ("trg.svg", f'<svg {SVG_NS}><g transform="rotate(30)"><g><path d="M0 0 L1 0 L1 1"/></g></g></svg>', "ancestor <g>"),
    (
        "doctype.svg",
        '<?xml version="1.0"?>\n<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" '
        '"http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd">\n' + svg("M0 0 L1 0 L1 1"),
        "DOCTYPE declaration",
    ),
    (
        "lol.svg",
        '<!DOCTYPE svg [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;">]>'
        '<svg><path d="M0 0 L1 0 L1 1" id="&b;"/></svg>',
        "DOCTYPE declaration",
    ),
    ("entity.svg", '<svg><!ENTITY a "x"><path d="M0 0 L1 0 L1 1"/></svg>', "ENTITY declaration"),
    ("nopath.svg", f'<svg {SVG_NS}><circle r="3"/></svg>', "no <path> element"),
    ("notxml.svg", "<svg><path d='M0 0 L1 1'></svg>", "not valid XML"),
    ("sub.svg", svg("M0 0 L1 0 L1 1 Z M 5 5 L 6 6 L 5 6"), "2 subpaths"),
    ("bad_d.svg", svg("M 0 0 L 1"), "not valid path data"),
    ("start.svg", svg("L 1 1 L 2 0"), "must start with M"),
    ("emptyd.svg", svg("  "), "'d' attribute is empty"),
    ("dot.svg", svg("M 3 3 L 3 3"), "no length"),
    ("huge.svg", svg("M 0 0 L 1.5e308 0 L -1.5e308 0"), "numbers too large"),
    ("inf.svg", svg("M 0 0 L 1e999 0 L 0 1"), "numbers too large"),
    ("long.svg", svg("M 0 0 L 1e308 0 L 1e308 1e308"), "not a finite number"),
    ("moveonly.svg", svg("M 0 0 M 1 1"), "draws nothing"),
]


@pytest.mark.parametrize(("name", "body", "fragment"), BAD_SVG, ids=[c[0] for c in BAD_SVG])
def test_bad_svg(tmp_path: Path, name: str, body: str, fragment: str) -> None:
    msg = expect_error(write(tmp_path, name, body))
    assert fragment in msg, msg


def test_svg_trailing_move_is_ignored(tmp_path: Path) -> None:
    t = read_targets(write(tmp_path, "trail.svg", svg("M 0 0 L 2 0 L 2 2 Z M 7 7")), points=4)
    assert t.closed and len(t) == 4
    # perimeter 4 + 2*sqrt(2); four points a quarter of it apart from the start, the last on the Z segment
    step = (4 + 2 * math.sqrt(2)) / 4
    diag = (3 * step - 4) / math.sqrt(2)
    expected = [[0, 0], [step, 0], [2, -(2 * step - 2)], [2 - diag, -(2 - diag)]]
    np.testing.assert_allclose(t.xy, np.array(expected), atol=1e-9)


def test_a_dense_drawing_is_taken_at_400_of_its_smoothed_points(tmp_path):
    """A CSV drawing of 2000 points made a 10 s synthesis take 22 s (10^5 points: 1.5 GB), every evaluation costing
    in proportion to the targets. Smoothed (its 16 harmonics), it is taken at 400 of its points, evenly by index,
    said in the note: every fifth of the 2000 smoothed points, to rounding."""
    from linkagekit.synthesis.targets import SMOOTHED_POINTS, read_targets, smooth

    t = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
    xy = np.stack([np.cos(t) + 0.3 * np.cos(2 * t), 0.6 * np.sin(t)], 1)
    f = tmp_path / "d.csv"
    np.savetxt(f, xy, delimiter=",", header="x,y", comments="")
    got = read_targets(f)
    assert SMOOTHED_POINTS == 400 and got.xy.shape == (400, 2) and got.closed
    assert got.smoothed.endswith("; 400 of them taken, evenly by index")
    whole = smooth(np.loadtxt(f, delimiter=",", skiprows=1), closed=True)
    np.testing.assert_allclose(got.xy, whole[::5], rtol=0, atol=1e-12)
    assert read_targets(f, smooth=False).xy.shape == (2000, 2)  # --no-smooth: every point as it is


@pytest.mark.parametrize(
    "body, words",
    [
        ("x,y,input\n0,0,0\n1,1,0\n2,0,0\n", "targets 1 and 2 are at different places with one input (0 deg)"),
        ("x,y,input\n0,0,10\n1,1,90\n2,0,370\n", "targets 1 and 3 are at different places with one input (10 deg)"),
        ("x,y,input\n0,0,0\n1,1,1e300\n2,0,20\n", "target 2: an input of 1e+300 deg (at most 360000)"),
    ],
)
def test_timed_targets_a_mechanism_cannot_meet_are_refused(tmp_path: Path, body: str, words: str) -> None:
    """Timed targets all at one input were accepted (no mechanism meets two places at one input), and an input of
    1e300 made the table print every other input as 0. One line naming the targets, exit 2."""
    msg = expect_error(write(tmp_path, "t.csv", body))
    assert words in msg, msg


def test_timed_targets_at_one_place_and_one_input_are_fine(tmp_path: Path) -> None:
    """The same target twice (one place, one input modulo 360) is no contradiction."""
    t = read_targets(write(tmp_path, "t.csv", "x,y,input\n0,0,0\n1,1,90\n0,0,360\n2,0,180\n"))
    assert len(t) == 4 and t.timed


@pytest.mark.parametrize("cell", ["1_0", "\uff11\uff12", "0x10", "1e", "--1"])
def test_a_target_number_is_a_plain_ascii_number_as_in_a_mechanism_file(tmp_path, cell) -> None:  # type: ignore[no-untyped-def]
    """Review 18b: Python's ``float`` read ``1_0`` as 10 and fullwidth ``１２`` as 12, which a mechanism file and the
    command line refuse; each is now 'is not a number', naming the line."""
    message = expect_error(write(tmp_path, "t.csv", f"x,y\n0,0\n{cell},0\n0,1\n"))
    assert "line 3: " in message and "is not a number" in message
