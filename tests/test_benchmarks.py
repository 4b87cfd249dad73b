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


@pytest.mark.long
def test_bench_editor(capsys):
    """A few drag moves of the Jansen leg in the editor (Chromium); same browser policy as the page tests."""
    import os

    if os.environ.get("LINKAGEKIT_NO_BROWSER") == "1":
        pytest.skip("LINKAGEKIT_NO_BROWSER=1: the editor benchmark needs Chromium")
    import bench_editor

    rows = bench_editor.main(steps=10, enforce=False, repeat=3)  # timings on a busy machine say nothing: no goal here
    out = capsys.readouterr().out
    assert "of 10 answered" in out and "median" in out and "95th percentile" in out and "coarse request" in out
    assert [r["example"] for r in rows] == [case[0] for case in bench_editor.CASES]
    for got in rows:
        assert 1 <= got["answered"] <= 10 and got["median_ms"] > 0 and "goal_ms" in got


def test_bench_group(capsys):
    import bench_group

    got = bench_group.main(200, designs=50)  # a smoke test: the goals' sizes are the script's
    out = capsys.readouterr().out
    assert "triad, Newton" in out and "ratio" in out
    assert got["ratio"] > 1 and all(v > 0 for v in got.values())


def test_bench_synthesis(capsys):
    """The synthesis benchmark at a small size: its equality checks (hand kernel, compile + solve, and pylinkage's
    positions when the optional bench dependencies are installed) hold, and it prints every row."""
    import bench_synthesis

    ns = bench_synthesis.main(50, chunk=20, repeat=1, loop_designs=5)
    out = capsys.readouterr().out
    assert "50 four-bar designs" in out and "hand NumPy kernel" in out and "synthesis objective" in out
    assert all(v > 0 for v in ns.values())
    if "pylinkage" in ns:
        assert "positions equal to ours" in out and "ratio pylinkage / this" in out
    else:
        assert "pylinkage" in out and "not installed" in out


def test_bench_threads(capsys):
    import bench_threads

    ratio = bench_threads.main(6)
    out = capsys.readouterr().out
    assert "one BLAS thread (linkagekit)" in out and "ratio" in out and ratio > 0


def test_bench_recovery(capsys):
    import bench_recovery

    rows = bench_recovery.main(1, seconds=0.5, workers=1)
    out = capsys.readouterr().out
    assert len(rows) == 3 and "within 0.1 % in 0.5 s" in out
    assert all(r[2] >= 0 and r[3] > 0 for r in rows)


def test_bench_long_tests(capsys):
    """The long runs moved out of the suite are all there; one runs (one random triad); a check that does not
    reach its goal is one FAILED line with its message and makes main return its name (the script exits 1)."""
    import bench_long_tests

    names = ["fourbar-0", "fourbar-1", "fourbar-2", "watt2", "stephenson3", "forced-numerical", "triads", "marked"]
    assert list(bench_long_tests.checks()) == names
    assert bench_long_tests.main(["triads"], table=bench_long_tests._group_checks(1, 1)) == []
    assert "1 random cases" in capsys.readouterr().out

    def short() -> str:
        raise AssertionError("0.25 > 0.1 % of the diagonal\nmore detail")

    assert bench_long_tests.main(table={"short": short, "fine": lambda: "ok"}) == ["short"]
    out = capsys.readouterr().out.splitlines()
    assert "FAILED short: AssertionError: 0.25 > 0.1 % of the diagonal" in out
    assert out[-1] == "FAILED: 1 of 2 checks held; failed: short"
    with pytest.raises(SystemExit, match="no check named"):
        bench_long_tests.main(["nothing"])


def test_bench_synthesis_without_pylinkage(capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "pylinkage", None)  # as if not installed
    import bench_synthesis

    ns = bench_synthesis.main(20, repeat=1)
    out = capsys.readouterr().out
    assert "pylinkage not installed" in out and "lk.analyze" in out
    assert not any(k.startswith("pylinkage") for k in ns)


def test_benchmarks_leave_no_module_cache():
    for name in (
        "bench_positions",
        "bench_forces",
        "bench_designs",
        "bench_animate",
        "bench_editor",
        "bench_group",
        "bench_synthesis",
        "bench_recovery",
        "bench_long_tests",
        "test_synthesis",
        "test_group",
        "timing",
    ):
        sys.modules.pop(name, None)


def test_bench_burmester(capsys):
    import bench_burmester

    bench_burmester.main(2, seed=1)
    out = capsys.readouterr().out
    assert "generator listed" in out and "2/2" in out
