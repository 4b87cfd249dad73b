"""The benchmark scripts run (at a small size) and their correctness checks hold: they must not rot."""

import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(autouse=True)
def bench_path(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH))


def test_bench_positions(capsys):
    import bench_positions

    bench_positions.main(2000)
    assert "ratio" in capsys.readouterr().out


def test_bench_forces(capsys):
    import bench_forces

    bench_forces.main(500)
    assert "residual" in capsys.readouterr().out


def test_bench_designs(capsys, monkeypatch):
    import bench_designs

    monkeypatch.setattr(bench_designs, "LOOP_DESIGNS", 5)
    bench_designs.main((50,))
    out = capsys.readouterr().out
    assert "50 designs" in out and "linkagekit --help" in out


def test_bench_animate(capsys):
    import bench_animate

    bench_animate.main(4)
    out = capsys.readouterr().out
    assert "4 frames, GIF" in out and "ratio" in out


def test_bench_editor(capsys):
    """A few drag moves of the Jansen leg in the editor (Chromium); same browser policy as the page tests."""
    import os

    if os.environ.get("LINKAGEKIT_NO_BROWSER") == "1":
        pytest.skip("LINKAGEKIT_NO_BROWSER=1: the editor benchmark needs Chromium")
    import bench_editor

    got = bench_editor.main(steps=10)
    out = capsys.readouterr().out
    assert "of 10 answered" in out and "median" in out and "95th percentile" in out and "coarse request" in out
    assert 1 <= got["answered"] <= 10 and got["median_ms"] > 0


def test_bench_group(capsys):
    import bench_group

    got = bench_group.main(200)
    out = capsys.readouterr().out
    assert "triad, Newton" in out and "ratio" in out
    assert got["ratio"] > 1 and all(v > 0 for v in got.values())


def test_benchmarks_leave_no_module_cache():
    for name in (
        "bench_positions",
        "bench_forces",
        "bench_designs",
        "bench_animate",
        "bench_editor",
        "bench_group",
        "timing",
    ):
        sys.modules.pop(name, None)
