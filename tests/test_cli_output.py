"""What the command line prints for a person: units in headers, round-off as 0, tables that fit
the terminal, names printed literally; and how fast it starts."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import linkagekit
from linkagekit.catalogue import KINDS, Catalogue, Owner, Quantity, UnitKind
from linkagekit.cli import (
    MAX_ROWS,
    NAN,
    Column,
    analysis_sections,
    analysis_tables,
    format_cells,
    format_csv,
    main,
    sample_rows,
    split_columns,
)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

# joint and link names that look like rich markup: they must print literally
BRACKETS = """\
format: linkagekit/1
name: "[bold]four-bar[/bold]"
units: {length: cm, angle: deg}
joints:
  A: [0, 0]
  B: [4, 1]
  C: [2, 0]
  "[/x]": [0.8206, 4.8589]
  "[bold]": [5.6182, 3.4509]
links:
  ground: [A, B]
  "[red]": [A, C]
  "[/link]": [C, "[/x]", "[bold]"]
  rocker: [B, "[/x]"]
drivers:
  - {link: "[red]", pivot: A, toward: C, angles: {start: 0, stop: 360, step: 10}, speed: 5}
"""


def run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def tables(text: str) -> list[tuple[str, list[str], list[list[str]]]]:
    """Parse the plain tables of the output: (title, headers, rows of cells), cut by the dashed rule."""
    lines = text.splitlines()
    found = []
    for i, line in enumerate(lines):
        if i < 2 or not line or set(line) - {"-", " "}:
            continue
        spans, pos = [], 0
        for part in line.split("  "):
            if part:
                spans.append((pos, pos + len(part)))
            pos += len(part) + 2

        def cut(s: str, spans: list[tuple[int, int]] = spans) -> list[str]:
            return [s[a:b].strip() for a, b in spans]

        rows = []
        for row in lines[i + 1 :]:
            if not row:
                break
            rows.append(cut(row.ljust(spans[-1][1])))
        found.append((lines[i - 2], cut(lines[i - 1].ljust(spans[-1][1])), rows))
    return found


def column(text: str, header: str) -> tuple[list[str], list[str]]:
    """The first input column and the column *header* of the first table that has it."""
    for _, heads, rows in tables(text):
        if header in heads:
            k = heads.index(header)
            return [r[0] for r in rows], [r[k] for r in rows]
    raise AssertionError(f"no column {header!r} in\n{text}")


# ---------------------------------------------------------------------------- analyze tables
def test_headers_carry_units(capsys):
    code, out, err = run(["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--angles", "0:360:90"], capsys)
    assert code == 0, err
    for head in (
        "crank [deg]",
        "D.x [cm]",
        "D.y [cm]",
        "D.vx [cm/s]",
        "D.ay [cm/s²]",
        "coupler.angle [deg]",
        "coupler.omega [rad/s]",
        "coupler.alpha [rad/s²]",
    ):
        assert head in out, head
    assert "A.x" not in out and "ground.angle" not in out  # the ground's joints and angle do not move


def test_force_headers_carry_units(capsys):
    code, out, err = run(["analyze", str(EXAMPLES / "slider_crank.yaml"), "--at", "0,90"], capsys)
    assert code == 0, err
    assert "crank [deg]" in out and "T[crank] [N·m]" in out and "input_power [W]" in out
    assert "|F|[O:ground>crank] [N]" in out and "B.x [m]" in out and "B.vx [m/s]" in out


def test_roundoff_prints_as_zero(capsys):
    code, out, _ = run(["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--angles", "0:360:90"], capsys)
    assert code == 0
    inputs, cx = column(out, "C.x [cm]")
    assert inputs == ["0", "90", "180", "270", "360"]
    assert cx == ["2", "0", "-2", "0", "2"]  # 2 cos(90 deg) = 1.2e-16 is round-off
    _, cy = column(out, "C.y [cm]")
    assert cy == ["0", "2", "0", "-2", "0"]
    assert "e-16" not in out and "e-17" not in out


def test_roundoff_of_a_single_sample_prints_as_zero_next_to_its_columns_of_one_unit(capsys):
    """With one sample a column's own largest value was its round-off: ``--at 90`` printed C.x = 1.22465e-16 and the
    slider-crank's rod.omega -2.75909e-16 (review 16c). The threshold is now also relative to the largest value of
    the section's columns of the same unit."""
    code, out, _ = run(["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--at", "90"], capsys)
    assert code == 0 and column(out, "C.x [cm]")[1] == ["0"] and column(out, "C.y [cm]")[1] == ["2"]
    code, out, _ = run(["analyze", str(EXAMPLES / "slider_crank.yaml"), "--at", "90"], capsys)
    assert code == 0 and "e-1" not in out
    assert column(out, "A.x [m]")[1] == ["0"] and column(out, "rod.omega [rad/s]")[1] == ["0"]
    assert column(out, "B.x [m]")[1] == ["0.0795299"] and column(out, "rod.alpha [rad/s²]")[1] == ["62.8695"]


def test_missing_values_and_states(capsys):
    code, out, _ = run(["analyze", str(EXAMPLES / "seed003_ex21.yaml"), "--at", "0,180"], capsys)
    assert code == 0
    title, heads, rows = tables(out)[0]
    assert heads[:2] == ["crank [deg]", "state"]
    assert rows[0][1] == "not assembled" and set(rows[0][2:]) == {NAN}
    assert rows[1][1] == "ok" and NAN not in rows[1]
    code, out, _ = run(["analyze", str(EXAMPLES / "seed003_ex22.yaml"), "--at", "0,60"], capsys)
    _, heads, rows = tables(out)[0]
    assert [r[1] for r in rows] == ["singular", "ok"]


def test_names_that_look_like_markup_print_literally(tmp_path, capsys):
    path = tmp_path / "brackets.yaml"
    path.write_text(BRACKETS)
    code, out, err = run(["analyze", str(path), "--at", "0,90"], capsys)
    assert code == 0, err
    assert "[bold]four-bar[/bold]: joint positions" in out
    for head in ("[red] [deg]", "[/x].x [cm]", "[bold].y [cm]", "[/x].vx [cm/s]", "[/link].omega [rad/s]"):
        assert head in out, head
    code, out, err = run(["modes", str(path), "--at", "0", "--mirrors"], capsys)
    assert code == 0, err
    assert "[/x]+" in out and "[/x]-" in out and "[/link]+" in out and "[bold].x [cm]" in out
    code, out, err = run(["check", str(path)], capsys)
    assert code == 0, err
    assert out.startswith("[bold]four-bar[/bold]: valid") and "[red]" in out and "[/x]" in out


@pytest.mark.parametrize("width", [80, 60, 200])
def test_tables_fit_the_terminal(monkeypatch, capsys, width):
    monkeypatch.setenv("COLUMNS", str(width))
    code, out, _ = run(["analyze", str(EXAMPLES / "jansen_leg.yaml")], capsys)
    assert code == 0
    assert max(len(line) for line in out.splitlines()) <= width
    found = tables(out)
    assert found and all(heads[:2] == ["crank [deg]", "state"] for _, heads, _ in found)
    heads = [h for _, hs, _ in found for h in hs[2:]]
    for j in "MULVWF":  # every moving joint, every coordinate, once
        for c in ("x", "y", "vx", "vy", "ax", "ay"):
            assert heads.count(f"{j}.{c} [cm]" if len(c) == 1 else f"{j}.{c} [cm/s{'²' if c[0] == 'a' else ''}]") == 1


def test_long_sweep_shows_a_subset(capsys):
    code, out, _ = run(["analyze", str(EXAMPLES / "seed000_fourbar.yaml")], capsys)
    assert code == 0
    for _, _, rows in tables(out):
        assert len(rows) == MAX_ROWS and rows[0][0] == "0" and rows[-1][0] == "360"
    notes = [line for line in out.splitlines() if "--format csv" in line]
    assert len(notes) == 1 and "37 of 361 samples" in notes[0]
    code, out, _ = run(["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--format", "csv"], capsys)
    assert len(out.splitlines()) == 362


def test_long_sweep_table_is_fast(capsys):
    main(["analyze", str(EXAMPLES / "seed000_fourbar.yaml")])  # imports, caches
    capsys.readouterr()
    t = time.process_time()  # CPU time: a busy machine does not fail it
    assert main(["analyze", str(EXAMPLES / "seed000_fourbar.yaml")]) == 0
    assert time.process_time() - t < 0.5
    assert "37 of 361" in capsys.readouterr().out


def test_table_to_a_file(tmp_path, capsys):
    target = tmp_path / "t.txt"
    code, out, _ = run(["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "-o", str(target)], capsys)
    assert code == 0 and out == ""
    text = target.read_text(encoding="utf-8")
    assert "D.x [cm]" in text and max(len(line) for line in text.splitlines()) <= 80


def test_negative_values_are_values(capsys):
    code, out, err = run(
        ["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--at", "-90,0", "--speed", "-2", "--format", "json"],
        capsys,
    )
    assert code == 0, err
    doc = json.loads(out)
    assert doc["inputs"] == {"crank": [-90.0, 0.0]} and doc["joints"]["C"]["vy"][1] == pytest.approx(-4.0)
    code, out, err = run(["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--angles", "-90:90:90"], capsys)
    assert code == 0, err
    assert column(out, "C.x [cm]")[0] == ["-90", "0", "90"]


# ---------------------------------------------------------------------------- modes and check
def test_modes_table(capsys):
    code, out, err = run(["modes", str(EXAMPLES / "seed000_fourbar.yaml"), "--at", "0"], capsys)
    assert code == 0, err
    _, heads, rows = tables(out)[0]
    assert heads[:3] == ["#", "signs", "assembled"] and "D.x [cm]" in heads
    assert [r[1] for r in rows] == ["D+", "D-"] and rows[0][2] == "yes (pose)"
    assert "crank = 0 deg" in out and "2 distinct assembled configuration(s) of 2." in out
    # where no mode assembles the pose's is still marked, as the JSON's "reference" is (review 19b: only there)
    path = str(EXAMPLES / "nongrashof_rocker.yaml")
    code, out, err = run(["modes", path, "--at", "180"], capsys)
    assert code == 0 and [r[2] for r in tables(out)[0][2]] == ["no (pose)", "no"], err
    code, out, err = run(["modes", path, "--at", "180", "--format", "json"], capsys)
    assert [m["reference"] for m in json.loads(out)["modes"]] == [True, False]


def test_modes_mirrors_without_links_to_mirror(capsys):
    path = str(EXAMPLES / "slider_crank.yaml")
    code, out, err = run(["modes", path, "--at", "0", "--mirrors"], capsys)
    assert code == 0, err
    _, heads, rows = tables(out)[0]
    assert heads[:4] == ["#", "signs", "mirrors", "assembled"] and {r[2] for r in rows} == {"-"}
    code, out, err = run(["modes", path, "--at", "0", "--mirrors", "--format", "json"], capsys)
    assert code == 0, err
    assert all("mirrors" not in m for m in json.loads(out)["modes"])


def test_modes_arguments(capsys):
    path = str(EXAMPLES / "seed000_fourbar.yaml")
    # without --at, the pose's input (as plot --modes; it was refused: review 19c): its pose's mode first
    code, out, err = run(["modes", path], capsys)
    assert code == 0 and "assembly modes at crank = 0 deg" in out, err
    assert out == run(["modes", path, "--at", "0"], capsys)[1]
    code, out, err = run(["modes", str(EXAMPLES / "fivebar_two_drivers.yaml"), "--format", "json"], capsys)
    assert code == 0, err  # the pose: crank1 from A (0, 0) to C (-15, 25.98), crank2 from B (50, 0) to D (65, 25.98)
    assert json.loads(out)["input"] == pytest.approx({"crank1": 120.0, "crank2": 60.0}, abs=1e-9)
    code, _, err = run(["modes", path, "--at", "0,10"], capsys)
    assert code == 2 and err.count("\n") == 1 and "one value" in err
    code, _, err = run(["modes", str(EXAMPLES / "fivebar_two_drivers.yaml"), "--at", "crank1=100"], capsys)
    assert code == 2 and err.count("\n") == 1 and "every driver" in err


def test_check_text(capsys):
    code, out, err = run(["check", str(EXAMPLES / "seed000_fourbar.yaml")], capsys)
    assert code == 0, err
    assert "1 degree(s) of freedom" in out and "Solve plan" in out
    assert "Assembles for crank in [0.000000, 360.000000] deg" in out and "crank-rocker" in out
    assert "Transmission angle: min" in out


# ---------------------------------------------------------------------------- arguments, help, version
def test_version(capsys):
    code, out, err = run(["--version"], capsys)
    assert code == 0 and out == f"linkagekit {linkagekit.__version__}\n" and err == ""


def test_no_arguments_prints_the_help(capsys):
    code, out, _ = run([], capsys)
    assert code == 0 and out.startswith("usage: linkagekit") and "analyze" in out and "check" in out


@pytest.mark.parametrize("command", [[], ["analyze"], ["modes"], ["check"]])
def test_help_is_plain(capsys, command):
    code, out, err = run([*command, "--help"], capsys)
    assert code == 0 and err == "" and out.startswith("usage: linkagekit")
    assert "<bool>" not in out and "<list" not in out and "[bold]" not in out
    if command == ["analyze"]:
        for text in (
            "START:STOP:STEP",
            "V1,V2,...",
            "{table,csv,json}",
            "{natural,vector-loop,numerical}",
            "-o OUT",
            "--static",
        ):
            assert text in out, text
    if command == ["modes"]:
        assert "--mirrors" in out and "{table,json}" in out


@pytest.mark.parametrize(
    "args,needle",
    [
        (["analyze"], "FILE"),
        (["frobnicate"], "frobnicate"),
        (["analyze", "x.yaml", "--format"], "--format"),
        (["check", "x.yaml", "--format", "csv"], "csv"),
        (["analyze", "x.yaml", "--form", "json"], "--form"),  # no abbreviations
        (["--bogus"], "--bogus"),
    ],
)
def test_usage_errors_are_one_line(capsys, args, needle):
    code, out, err = run(args, capsys)
    assert code == 2 and out == ""
    assert err.startswith("linkagekit: error: ") and err.count("\n") == 1 and needle in err, err


def test_unexpected_exception_is_one_line(monkeypatch, capsys):
    def boom(path):
        raise RuntimeError("boom\nsecond line")

    monkeypatch.setattr(linkagekit, "load", boom)
    code, out, err = run(["check", "whatever.yaml"], capsys)
    assert code == 1 and err == "linkagekit: internal error: RuntimeError: boom second line\n"


def test_start_up_imports_nothing_heavy():
    code = (
        "import linkagekit.cli, sys; "
        "print(any(m in sys.modules for m in ('numpy', 'typer', 'rich', 'pydantic', 'yaml')))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "False"


def test_help_does_not_load_the_library():
    code = (
        "import sys; from linkagekit.cli import main; main(['--help']); main(['analyze', '--help']); "
        "print(sorted(m for m in ('numpy', 'typer', 'rich', 'pydantic', 'yaml') if m in sys.modules))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip().splitlines()[-1] == "[]"


# ---------------------------------------------------------------------------- formatting functions
def test_format_cells():
    values = np.array([2.0, 2 * math.cos(math.pi / 2), np.nan, -0.0, 123456789.0, 1.5e-3, -np.inf])
    assert format_cells(values) == ["2", "0", NAN, "0", "1.23457e+08", "0.0015", "-inf"]
    # the threshold is relative to the column's largest magnitude: small columns keep their digits
    assert format_cells([1e-20, 3e-21]) == ["1e-20", "3e-21"]
    assert format_cells([np.nan, np.nan]) == [NAN, NAN]
    assert format_cells([1.0, 1e-13, 5.0], rows=[1, 2]) == ["0", "5"]


def test_format_csv():
    cols = {
        "input:crank": np.array([0.0, 90.0]),
        "assembled": np.array([True, False]),
        "singular": np.array([False, False]),
        "D.x": np.array([0.1 + 0.2, np.nan]),
        "a,b": np.array([1.0, 2.0]),
    }
    assert format_csv(cols).splitlines() == [
        'input:crank,assembled,singular,D.x,"a,b"',
        "0.0,true,false,0.30000000000000004,1.0",
        "90.0,false,false,,2.0",
    ]


@pytest.mark.parametrize("n", [1, 2, 36, 37, 38, 100, 361, 1000, 100_001])
def test_sample_rows(n):
    rows = sample_rows(n)
    assert rows[0] == 0 and rows[-1] == n - 1 and rows == sorted(set(rows))
    assert len(rows) == min(n, MAX_ROWS)
    if n > MAX_ROWS:
        gaps = np.diff(rows)
        assert gaps.max() - gaps.min() <= 1


def synthetic(n: int, joints: str = "ABCDEFGH") -> tuple[dict[str, np.ndarray], dict[str, str]]:
    t = np.linspace(0, 2 * np.pi, n)
    cols: dict[str, np.ndarray] = {"input:crank": np.degrees(t), "assembled": t < 5, "singular": t == t[1]}
    units = {"input:crank": "deg", "assembled": "", "singular": ""}
    for k, j in enumerate(joints):
        for c, f, u in (("x", np.cos, "mm"), ("y", np.sin, "mm"), ("vx", np.cos, "mm/s"), ("vy", np.sin, "mm/s")):
            cols[f"{j}.{c}"] = np.where(t < 5, (k + 1) * 1000 * f(t), np.nan)
            units[f"{j}.{c}"] = u
    cols["bar.angle"], units["bar.angle"] = np.degrees(t), "deg"
    cols["T[crank]"], units["T[crank]"] = -np.sin(t), "N·m"
    cols["F[B:ground>bar].fx"], units["F[B:ground>bar].fx"] = np.cos(t), "N"
    return cols, units


def synthetic_catalogue(cols: dict[str, np.ndarray], units: dict[str, str], ground: str = "A") -> Catalogue:
    """The catalogue of the synthetic columns, entry by entry (what each column is, not parsed from its name)."""
    kind = {(k.owner, k.component): k for k in KINDS}
    what = {"input:crank": (Owner.DRIVER, "input", "crank"), "assembled": (Owner.MECHANISM, "assembled", "")}
    what |= {"singular": (Owner.MECHANISM, "singular", ""), "bar.angle": (Owner.LINK, "angle", "bar")}
    what |= {
        "T[crank]": (Owner.DRIVER, "torque", "crank"),
        "F[B:ground>bar].fx": (Owner.REACTION, "fx", "B:ground>bar"),
    }
    out = []
    for name in cols:
        owner, component, owner_name = what.get(name) or (Owner.JOINT, name[2:], name[0])
        k = kind[owner, component]
        out.append(Quantity(name, k, owner_name, 0, k.unit or UnitKind.ANGLE, units[name], owner_name == ground, None))
    return Catalogue(tuple(out))


def test_analysis_tables_on_synthetic_columns():
    cols, units = synthetic(361)
    sections = analysis_sections(synthetic_catalogue(cols, units), "demo")
    assert [title for title, _ in sections][:2] == ["demo: joint positions", "joint velocities"]
    assert sections[0][1][0] == ["B.x", "B.y"] and sections[-1][1] == [["T[crank]"]]  # no .fx in tables
    t = time.process_time()  # CPU time: a busy machine does not fail it
    text = analysis_tables(cols, units, sections, inputs={"input:crank": "crank"}, width=80)
    assert time.process_time() - t < 0.5
    lines = text.splitlines()
    assert max(map(len, lines)) <= 80
    assert "B.x [mm]" in text and "H.vy [mm/s]" in text and "T[crank] [N·m]" in text and "A.x" not in text
    assert "F[B:ground>bar].fx" not in text
    found = tables(text)
    assert all(heads[:2] == ["crank [deg]", "state"] and len(rows) == MAX_ROWS for _, heads, rows in found)
    states = [r[1] for r in found[0][2]]
    assert states[0] == "ok" and states[-1] == "not assembled"
    assert lines[-1] == "37 of 361 samples shown, evenly spaced; --format csv gives all of them."
    # x and y of a joint stay in one table
    for _, heads, _ in found:
        for h in heads[2:]:
            if h.endswith(".x [mm]"):
                assert h.replace(".x", ".y") in heads


def test_split_columns_keeps_groups_and_width():
    fixed = [Column("crank [deg]", ["0"]), Column("state", ["ok"], left=True)]
    groups = [[Column(f"{j}.{c} [cm]", ["-1.23457e+06"]) for c in "xy"] for j in "ABCDE"]
    for width in (40, 60, 80, 120):
        parts = split_columns(fixed, groups, width)
        for part in parts:
            cols = [*fixed, *part]
            assert sum(c.width for c in cols) + 2 * (len(cols) - 1) <= width
        assert [c.header for part in parts for c in part] == [c.header for g in groups for c in g]
    # a header too long for any table is cut, not left to overflow
    long = [[Column("a_very_long_joint_name_that_does_not_fit.vx [cm/s]", ["1"])]]
    (part,) = split_columns(fixed, long, 40)
    assert part[0].header.endswith("…") and sum(c.width for c in [*fixed, *part]) + 4 <= 40


def test_no_samples():
    cols = {"input:crank": np.array([]), "assembled": np.array([], bool), "C.x": np.array([])}
    text = analysis_tables(
        cols, {"input:crank": "deg", "C.x": "cm"}, [("joint positions", [["C.x"]])], inputs={"input:crank": "crank"}
    )
    assert "C.x [cm]" in text and "samples shown" not in text


def test_closed_pipe_is_quiet(monkeypatch, capsys):
    class Gone:
        encoding = "utf-8"

        def write(self, text: str) -> int:
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self) -> None:
            pass

    monkeypatch.setattr(sys, "stdout", Gone())
    assert main(["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--format", "csv"]) == 1
    assert capsys.readouterr().err == ""
