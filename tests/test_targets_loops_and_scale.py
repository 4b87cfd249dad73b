"""Hand-drawn loops listed without repeating their first point, ``--no-smooth``, and the range of target sizes.

The expected values come from the points written here (a curve of a few harmonics is its own
low-pass image; a dropped point is a gap of two steps), not from the code under test.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest

from linkagekit.cli import _synthesize_command, build_parser, main
from linkagekit.errors import InputError
from linkagekit.synthesis.run import make_problem
from linkagekit.synthesis.targets import MAX_DIAGONAL, MIN_DIAGONAL, read_targets, smooth


def _csv(path: Path, xy: np.ndarray) -> Path:
    np.savetxt(path, xy, delimiter=",", header="x,y", comments="", fmt="%.17g")
    return path


def _curve(n: int, stop: float = 2 * np.pi) -> np.ndarray:
    """A loop of harmonics 1, 2 and -3 (all below the cut of 16), ``n`` points from 0 up to ``stop`` (excluded)."""
    t = np.linspace(0, stop, n, endpoint=False)
    z = 3 * np.exp(1j * t) + 0.8 * np.exp(2j * t) + 0.3j * np.exp(-3j * t) + (5 - 2j)
    return np.c_[z.real, z.imag]


def test_a_dense_loop_without_its_first_point_repeated_is_closed_and_stays_put(tmp_path: Path) -> None:
    xy = _curve(80)
    t = read_targets(_csv(tmp_path / "loop.csv", xy))
    assert t.closed and len(t) == 80 and "closed curve" in t.smoothed
    # its harmonics are below the cut, so the periodic filter gives it back (rounding only)
    assert np.max(np.hypot(*(t.xy - xy).T)) <= 1e-12 * t.diagonal
    assert np.max(np.hypot(*(smooth(xy, closed=True) - xy).T)) <= 1e-12 * t.diagonal


def test_a_dense_loop_missing_a_few_points_is_open(tmp_path: Path) -> None:
    """Points 77..79 of 80 left off: the end gap spans 4 steps, not one (3.8 times the longest step, measured)."""
    t = read_targets(_csv(tmp_path / "c.csv", _curve(80)[:77]))
    assert not t.closed and "open curve" in t.smoothed


def test_a_short_list_is_never_closed_by_the_gap_rule(tmp_path: Path) -> None:
    t = read_targets(_csv(tmp_path / "few.csv", _curve(30)))
    assert not t.closed and not t.smoothed


def test_no_smooth_keeps_every_point_exactly(tmp_path: Path) -> None:
    xy = _curve(60) + np.random.default_rng(1).normal(0, 0.05, (60, 2))  # wiggles smoothing would remove
    f = _csv(tmp_path / "drawn.csv", xy)
    assert np.max(np.abs(read_targets(f).xy - xy)) > 1e-3
    t = read_targets(f, smooth=False)
    assert t.closed and t.smoothed == "" and np.array_equal(t.xy, xy)


def test_no_smooth_is_a_path_option_and_part_of_the_repeat_command(tmp_path: Path, capsys) -> None:
    args: argparse.Namespace = build_parser().parse_args(["synthesize", "a.csv", "--no-smooth", "-o", "o.yaml"])
    assert "--no-smooth" in _synthesize_command(args).split()
    f = _csv(tmp_path / "p.csv", _curve(5))
    assert main(["synthesize", str(f), "--task", "motion", "--no-smooth", "-o", str(tmp_path / "o.yaml")]) == 2
    assert "--no-smooth: goes with --task path" in capsys.readouterr().err


def test_no_smooth_refuses_more_points_than_it_takes_before_the_search(tmp_path: Path, capsys, monkeypatch) -> None:
    # a review: 10000 hand-drawn points with --no-smooth ran 25 s of --seconds 3 (the atlas's answer is placed
    # and checked on every point before the clock is read); 2000 are taken, 2001 refused in one line
    from linkagekit.synthesis.targets import MAX_UNSMOOTHED

    monkeypatch.chdir(tmp_path)  # a short path: a long one is shortened in the message
    f = _csv(tmp_path / "drawn.csv", _curve(MAX_UNSMOOTHED + 1))
    out = tmp_path / "o.yaml"
    assert main(["synthesize", "drawn.csv", "--no-smooth", "--seconds", "1", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("linkagekit: error: drawn.csv: 2001 points; --no-smooth takes at most 2000 as they are")
    assert "\n" not in err and not out.exists()
    assert len(read_targets(f, smooth=False)) == 2001  # the library still reads every point


def test_smoothing_large_finite_numbers_does_not_overflow() -> None:
    xy = _curve(64)
    out = smooth(1e306 * xy, closed=False) / 1e306
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out, smooth(xy, closed=False), rtol=0, atol=1e-11)


@pytest.mark.parametrize(
    ("factor", "ok"),
    [
        (MIN_DIAGONAL * 1.01, True),
        (MIN_DIAGONAL * 0.99, False),
        (MAX_DIAGONAL * 0.99, True),
        (MAX_DIAGONAL * 1.01, False),
    ],
)
def test_the_range_of_target_sizes(tmp_path: Path, factor: float, ok: bool) -> None:
    """A right triangle of diagonal exactly ``factor`` (legs 0.6 and 0.8 of it, from the origin)."""
    xy = factor * np.array([[0.0, 0.0], [0.8, 0.0], [0.0, 0.6]])
    f = _csv(tmp_path / "tri.csv", xy)
    if ok:
        assert read_targets(f).diagonal == pytest.approx(factor, rel=1e-12)
        make_problem(xy)
    else:
        with pytest.raises(
            InputError, match=r"^.*tri\.csv: the targets' diagonal is .* synthesis takes 1e-06 to 1e\+06"
        ):
            read_targets(f)
        with pytest.raises(InputError, match="^targets: the targets' diagonal"):
            make_problem(xy)


@pytest.mark.parametrize("offset", [2e9, 1e7 * 1.0])
def test_targets_too_far_from_the_origin_are_refused(tmp_path: Path, offset: float) -> None:
    """2e9 is beyond every coordinate's limit (1e9); 1e7 of a diagonal of 1 is beyond 1e6 diagonals."""
    xy = np.array([[0.0, 0.0], [0.8, 0.0], [0.0, 0.6]]) + offset
    with pytest.raises(InputError, match=r"far\.csv: a target coordinate of magnitude"):
        read_targets(_csv(tmp_path / "far.csv", xy))
    read_targets(_csv(tmp_path / "near.csv", xy - offset + 1e5))  # 1e5 diagonals away: fine


def test_a_refusal_of_the_targets_scale_says_what_is_wrong(tmp_path: Path) -> None:
    """Review 18a: beside a point at 1e300, (2, 0) counted as a repeat of (0, 0), and the line said two points were
    left 'once the last, a repeat of the first, is dropped'; the scale is checked first. A coordinate just over the
    limit was printed as the limit itself ('magnitude 1e+09 ... at most 1e+09')."""
    with pytest.raises(InputError, match=r"huge\.csv: the targets' diagonal is 1e\+300 m"):
        read_targets(_csv(tmp_path / "huge.csv", np.array([[0.0, 0.0], [1e300, 1.0], [2.0, 0.0]])))
    with pytest.raises(InputError, match=r"far\.csv: a target coordinate of magnitude 1000000001 m"):
        read_targets(_csv(tmp_path / "far.csv", np.array([[1000000001.0, 0.0], [1e9 - 1, 0.0], [1e9, 1.0]])))
