"""The command line: outputs per the spec, and one clear line with exit status 2 on bad input."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import linkagekit as lk
from linkagekit.cli import main

GOOD = """\
format: linkagekit/1
name: four-bar
units: {length: cm, angle: deg}
joints:
  A: [0, 0]
  B: [4, 1]
  C: [2, 0]
  D: [0.8206, 4.8589]
  P: [5.6182, 3.4509]
links:
  ground: [A, B]
  crank: [A, C]
  coupler: [C, D, P]
  rocker: [B, D]
drivers:
  - {link: crank, pivot: A, toward: C, angles: {start: 0, stop: 360, step: 10}, speed: 5}
"""


def write(tmp_path: Path, text: str, name: str = "m.yaml") -> str:
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


BAD_FILES = {
    "yaml syntax": (GOOD.replace("A: [0, 0]", "A: [0, 0"), "YAML syntax error"),
    "unknown joint": (GOOD.replace("rocker: [B, D]", "rocker: [B, X]"), "links.rocker: unknown joint 'X'"),
    "one-joint link": (GOOD.replace("rocker: [B, D]", "rocker: [B, D]\n  lonely: [P]"), "links.lonely"),
    "wrong drivers": (GOOD.replace("drivers:", "drivers:\n  - {link: rocker, pivot: B, toward: D}"), "drivers"),
    "non-numeric": (GOOD.replace("C: [2, 0]", "C: [two, 0]"), "joints.C[0]"),
    "unknown unit": (GOOD.replace("length: cm", "length: furlong"), "units.length"),
    "unknown key": (GOOD.replace("links:", "lynks: {}\nlinks:"), "lynks: unknown key"),
    # a review: a misspelt required key was reported as the missing one ("drivers: required key is missing")
    "misspelt key": (GOOD.replace("drivers:", "driverz:"), "driverz: unknown key (did you mean 'drivers'?)"),
    # review 16c: inside an entry a misspelt key had no hint, and a missing key hid the unknown one beside it
    "short misspelt key": (
        GOOD.replace("name: four-bar", "descr: four-bar"),
        "descr: unknown key (did you mean 'description'?)",
    ),
    "misspelt key of a driver": (
        GOOD.replace("angles:", "angle:"),
        "drivers[0].angle: unknown key (did you mean 'angles'?)",
    ),
    "misspelt key of a link": (
        GOOD.replace("coupler: [C, D, P]", "coupler: {joint: [C, D, P]}"),
        "links.coupler.joint: unknown key (did you mean 'joints'?)",
    ),
    "a key beside a missing one": (
        GOOD.replace("coupler: [C, D, P]", "coupler: {'true': [C, D, P]}"),
        "links.coupler.joints: required key is missing; 'true' beside it is not a key here",
    ),
    # review 16a: a typo in the ground's joints braces crank and coupler and frees the rocker; the count of pins
    # still says 1, and the planner said exit 1, "no triangulation order places B" (a valid mechanism it cannot solve)
    "a part loose, another braced": (
        GOOD.replace("ground: [A, B]", "ground: [A, D]"),
        "joint(s) B can move with every driver held",
    ),
    "no ground": (GOOD.replace("ground: [A, B]", "frame: [A, B]"), "no link named 'ground'"),
    "pivot not on link": (GOOD.replace("pivot: A", "pivot: B"), "drivers[0].pivot"),
    "coincident joints": (GOOD.replace("P: [5.6182, 3.4509]", "P: [2, 0]"), "at one spot"),
    "bad lengths": (
        GOOD.replace("coupler: [C, D, P]", "coupler: {joints: [C, D, P], lengths: {C-D: 1, C-P: 1, D-P: 5}}"),
        "cannot form a triangle",
    ),
    "not a mapping": ("- just\n- a list\n", "mapping"),
    # a review: one pair given twice (in either order) was taken, the last one silently winning
    "a length given twice": (
        GOOD.replace("coupler: [C, D, P]", "coupler: {joints: [C, D, P], lengths: {C-D: 5, D-C: 6}}"),
        "links.coupler.lengths.D-C: the length of D-C is given twice (as 'C-D' too)",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_files_exit_2_with_one_located_line(tmp_path, capsys, case):
    text, needle = BAD_FILES[case]
    path = write(tmp_path, text)
    for cmd in ("analyze", "check"):
        code, out, err = run([cmd, path], capsys)
        assert code == 2, (case, err)
        assert err.count("\n") == 1 and "Traceback" not in err
        assert needle in err and path in err, err


# review 16e: a pendulum whose end nothing holds (G5-E) beside a ternary body held by four legs: the pin count is
# right for the one crank and the group search takes both as one numerical group of balanced counts, so `check`
# said "valid" and "assembles for crank in nowhere"
LOOSE_IN_GROUP = """
format: linkagekit/1
units: {length: m, angle: deg}
joints: {O: [0, 0], A: [0.6, 0.8], P: [0.2, 3], G1: [2, 0], Q: [2.5, 3.1], G2: [4, 0], R: [4.3, 2.8],
         G3: [5, 0], S: [5.6, 3.3], G5: [7, 0], E: [7.5, 1]}
links: {ground: [O, G1, G2, G3, G5], crank: [O, A], l1: [A, P], l2: [G1, Q], l3: [G2, R], l4: [G3, S],
        T: [P, Q, R, S], pendulum: [G5, E]}
drivers: [{link: crank, pivot: O, toward: A}]
"""


def test_a_loose_part_inside_a_numerical_group_is_refused_by_name(tmp_path, capsys):
    path = write(tmp_path, LOOSE_IN_GROUP)
    for cmd in ("check", "analyze"):
        code, _, err = run([cmd, path], capsys)
        assert code == 2 and err.count("\n") == 1, err
        assert f"{path}: joint(s) E can move with every driver held" in err, err
    # braced once, the body is a class-3 triad: the same file without its fourth leg and pendulum is solved
    doc = yaml.safe_load(LOOSE_IN_GROUP)
    for j in ("G3", "S", "G5", "E"):
        del doc["joints"][j]
    del doc["links"]["l4"], doc["links"]["pendulum"]
    doc["links"].update(ground=["O", "G1", "G2"], T=["P", "Q", "R"])
    code, out, err = run(["check", write(tmp_path, yaml.safe_dump(doc), "triad.yaml")], capsys)
    assert code == 0 and "placed numerically" in out, err


#: review 16e: with a slider or a cylinder the loose part was not modelled ("no triangulation order places F", exit 1)
LOOSE_SLIDER = """
format: linkagekit/1
units: {length: m, angle: deg}
joints: {O: [0, 0], A: [0.03, 0.04], B: [0.115, 0], C: [0.05, 0.1], G: [0.3, 0], F: [0.35, 0.05]}
links: {ground: [O, C, G], crank: [O, A], rod: [A, B], brace: [C, B], block: [B], pend: [G, F]}
sliders: [{link: block, on: ground, through: B, direction: [1, 0]}]
drivers: [{link: crank, pivot: O, toward: A}]
"""


@pytest.mark.parametrize("case", ["slider", "cylinder"])
def test_a_loose_part_beside_a_slider_or_cylinder_is_refused_by_name(tmp_path, capsys, case):
    """A pendulum (free end F or W) beside a slider-crank whose block is braced to the frame, or beside the excavator
    bucket whose bucket link is braced to the stick (a cylinder driver); without the brace and the pendulum, valid."""
    if case == "slider":
        free, text = "F", LOOSE_SLIDER
        fixed = (
            text.replace(", brace: [C, B]", "")
            .replace(", pend: [G, F]", "")
            .replace(", G: [0.3, 0], F: [0.35, 0.05]", "")
        )
        fixed = fixed.replace("ground: [O, C, G]", "ground: [O, C]")
    else:
        free, text = "W", (EXAMPLES / "excavator_bucket.yaml").read_text()
        fixed = text
        text = text.replace("joints:\n", "joints:\n  Z: [0, 0]\n  W: [0.3, 0.3]\n", 1)
        text = text.replace("ground: [K, F, E]", "ground: [K, F, E, Z]\n  pend: [Z, W]\n  brace: [K, H]")
    code, _, err = run(["check", write(tmp_path, text)], capsys)
    assert code == 2 and f"joint(s) {free} can move with every driver held" in err, err
    code, out, err = run(["check", write(tmp_path, fixed, "fixed.yaml")], capsys)
    assert code == 0 and ": valid;" in out, err


def test_free_joints_at_generic_positions_see_the_structure_not_the_pose():
    """A parallelogram posed flat moves to first order at its pose (B1 off the line), not at generic positions;
    the loose pendulum beside the braced body is free at both."""
    from linkagekit.plan import free_joints

    flat = {
        "format": "linkagekit/1",
        "joints": {"A0": [0, 0], "A1": [1, 0], "B0": [0.5, 0], "B1": [1.5, 0]},
        "links": {"ground": ["A0", "A1"], "crank": ["A0", "B0"], "coupler": ["B0", "B1"], "rocker": ["A1", "B1"]},
        "drivers": [{"link": "crank", "pivot": "A0", "toward": "B0"}],
    }
    m = lk.Mechanism.from_dict(flat)
    assert free_joints(m) == ("B1",) and free_joints(m, generic=True) == ()
    loose = lk.Mechanism.from_dict(yaml.safe_load(LOOSE_IN_GROUP))
    assert free_joints(loose) == ("E",) and free_joints(loose, generic=True) == ("E",)
    # whatever the unit: the Stephenson written in mm (4000 units) had every joint of its group free (review 17d)
    for doc, free in (
        (yaml.safe_load(LOOSE_IN_GROUP), ("E",)),
        (lk.load(EXAMPLES / "seed001_stephenson.yaml").to_dict(), ()),
    ):
        for scale in (1e-5, 1e3, 1e6):
            scaled = {**doc, "joints": {k: [scale * v[0], scale * v[1]] for k, v in doc["joints"].items()}}
            scaled["links"] = {k: v["joints"] if isinstance(v, dict) else v for k, v in doc["links"].items()}
            m = lk.Mechanism.from_dict(scaled)
            assert free_joints(m) == free_joints(m, generic=True) == free, scale


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--at", "0,abc"], "'abc' is not a number"),
        (["--angles", "0:360"], "START:STOP:STEP"),
        (["--angles", "0:360:0"], "STEP"),
        (["--angles", "0:x:1"], "'x' is not a number"),
        (["--at", "rocker=5"], "no driver named 'rocker'"),
        (["--at", "1", "--angles", "0:1:1"], "not both"),
        (["--format", "xml"], "xml"),
        (["--speed", "fast"], "'fast' is not a number"),
        (["--bogus"], "--bogus"),
    ],
)
def test_bad_arguments_exit_2(tmp_path, capsys, args, needle):
    code, out, err = run(["analyze", write(tmp_path, GOOD), *args], capsys)
    assert code == 2
    assert err.count("\n") == 1 and needle in err, err


def test_missing_file(capsys, tmp_path):
    code, _, err = run(["analyze", str(tmp_path / "nope.yaml")], capsys)
    assert code == 2 and "no such file" in err and "nope.yaml" in err


def test_json_result_follows_spec(tmp_path, capsys):
    code, out, _ = run(["analyze", write(tmp_path, GOOD), "--at", "0,90,400", "--format", "json"], capsys)
    assert code == 0
    doc = json.loads(out)
    assert doc["format"] == "linkagekit-result/1"
    assert doc["units"] == {"length": "cm", "angle": "deg", "time": "s", "force": "N", "torque": "N*m"}
    assert doc["inputs"] == {"crank": [0.0, 90.0, 400.0]}
    assert set(doc["joints"]) == set("ABCDP")
    for j in doc["joints"].values():
        assert set(j) >= {"x", "y", "vx", "vy", "ax", "ay"} and all(len(v) == 3 for v in j.values())
    assert doc["joints"]["C"]["x"][1] == pytest.approx(0.0, abs=1e-12)
    assert doc["joints"]["C"]["vx"][0] == pytest.approx(0.0, abs=1e-12)
    assert doc["joints"]["C"]["vy"][0] == pytest.approx(10.0)  # 2 cm * 5 rad/s
    assert doc["links"]["crank"]["angle"] == pytest.approx([0.0, 90.0, 40.0])
    assert "reactions" not in doc  # no masses, gravity or loads: no force output


def test_not_assembled_is_null_in_json(tmp_path, capsys, examples):
    code, out, _ = run(["analyze", str(examples / "seed003_ex21.yaml"), "--at", "0,180", "--format", "json"], capsys)
    doc = json.loads(out)
    assert doc["assembled"] == [False, True]
    assert doc["joints"]["B"]["x"][0] is None and doc["joints"]["B"]["x"][1] is not None
    assert doc["links"]["coupler"]["omega"][0] is None


def test_csv_and_table_and_output_file(tmp_path, capsys):
    path = write(tmp_path, GOOD)
    code, out, _ = run(["analyze", path, "--angles", "0:20:10", "--format", "csv"], capsys)
    rows = out.strip().splitlines()
    assert code == 0 and len(rows) == 4 and rows[0].startswith("input:crank,assembled,singular,A.x")
    code, out, _ = run(["analyze", path, "--angles", "0:20:10"], capsys)
    assert code == 0 and "joint positions" in out and "D.x" in out
    target = tmp_path / "r.json"
    code, out, _ = run(["analyze", path, "--format", "json", "-o", str(target)], capsys)
    assert code == 0 and out == "" and len(json.loads(target.read_text())["inputs"]["crank"]) == 37


def test_modes_json(capsys, examples):
    code, out, _ = run(
        ["modes", str(examples / "seed000_fourbar.yaml"), "--at", "0", "--mirrors", "--format", "json"], capsys
    )
    doc = json.loads(out)
    assert code == 0 and doc["format"] == "linkagekit-modes/1" and doc["input"] == {"crank": 0.0}
    assert doc["units"] == {"length": "cm", "angle": "deg"}  # the only JSON without them (review 16a)
    assert len(doc["modes"]) == 4 and all(m["assembled"] for m in doc["modes"])
    assert {tuple(m["signs"].items()) for m in doc["modes"]} == {(("D", 1),), (("D", -1),)}


def test_check_json(capsys, examples):
    code, out, _ = run(["check", str(examples / "seed000_fourbar.yaml"), "--format", "json"], capsys)
    doc = json.loads(out)
    assert code == 0 and doc["dof"] == 1 and doc["input_range"] == [[0.0, 360.0]]
    assert doc["grashof"] == "crank-rocker" and 0 < doc["transmission_angle"]["min"] < doc["transmission_angle"]["max"]


def test_several_drivers(capsys, examples):
    path = str(examples / "fivebar_two_drivers.yaml")
    code, out, err = run(
        ["analyze", path, "--at", "crank1=100,120", "--at", "crank2=50,60", "--format", "json"], capsys
    )
    assert code == 0, err
    doc = json.loads(out)
    assert doc["inputs"] == {"crank1": [100.0, 120.0], "crank2": [50.0, 60.0]}
    code, _, err = run(["analyze", path, "--at", "100"], capsys)
    assert code == 2 and "NAME=" in err


def test_class3_group_is_solved_numerically(tmp_path, capsys):
    # a class-3 Assur group (triad) on a crank: no triangulation order; the numerical group places it
    text = """
joints: {A: [0,0], B: [6,0], G: [3,-3], C: [1,1], D: [2,4], E: [5,4], F: [3.5,6]}
links:
  ground: [A, B, G]
  crank: [A, C]
  l1: [C, D]
  l2: [B, E]
  l3: [G, F]
  tri: [D, E, F]
drivers: [{link: crank, pivot: A, toward: C}]
"""
    code, out, _ = run(["check", write(tmp_path, text)], capsys)
    assert code == 0 and "numerically" in out.splitlines()[0] and "D, E, F" in out


def test_slider_inside_a_class3_group_is_solved_numerically(tmp_path, capsys):
    # a triad whose third leg is a block sliding on the ground: a slider inside a class-3 group (refused before
    # issue 29; tests/test_group_sliders.py checks its numbers)
    text = """
joints: {A: [0,0], B: [6,0], C: [1,1], D: [2,4], E: [5,4], F: [3.5,6]}
links:
  ground: [A, B]
  crank: [A, C]
  l1: [C, D]
  l2: [B, E]
  block: [F]
  tri: [D, E, F]
sliders:
  - {link: block, on: ground, through: F, direction: [1, 0]}
drivers: [{link: crank, pivot: A, toward: C}]
"""
    code, out, _ = run(["analyze", write(tmp_path, text), "--at", "45,60", "--format", "json"], capsys)
    joints = json.loads(out)["joints"]
    assert (
        code == 0 and joints["F"]["x"][0] == pytest.approx(3.5, abs=1e-12) and joints["F"]["y"][1] == pytest.approx(6)
    )


def test_a_cylinder_inside_a_class3_group_is_solved(tmp_path, capsys):
    # a triad whose third leg is a cylinder: a cylinder driver inside a class-3 group, refused (exit 1, "no
    # triangulation order") until the group took cylinders; tests/test_group_cylinders.py checks its numbers
    text = """
joints: {A: [0,0], B: [6,0], G: [3,8], C: [1,1], D: [2,4], E: [5,4], F: [3.5,6]}
links:
  ground: [A, B, G]
  crank: [A, C]
  l1: [C, D]
  l2: [B, E]
  tri: [D, E, F]
drivers: [{link: crank, pivot: A, toward: C}, {cylinder: [G, F], name: lift}]
"""
    code, out, err = run(["check", write(tmp_path, text)], capsys)
    assert code == 0 and not err and "D, E, F placed numerically" in out and "cylinder G-F" in out
    code, out, _ = run(
        ["analyze", write(tmp_path, text), "--at", "crank=45", "--at", "lift=2.2", "--format", "json"], capsys
    )
    doc = json.loads(out)
    assert code == 0 and doc["assembled"] == [True]
    assert abs(complex(doc["joints"]["F"]["x"][0] - 3, doc["joints"]["F"]["y"][0] - 8)) == pytest.approx(2.2, abs=1e-10)


def test_real_executable_prints_no_traceback(tmp_path):
    bad = write(tmp_path, GOOD.replace("A: [0, 0]", "A: [0, 0"))
    proc = subprocess.run([sys.executable, "-m", "linkagekit.cli", "analyze", bad], capture_output=True, text=True)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr and proc.stderr.count("\n") == 1


def test_json_and_yaml_files_are_equivalent(tmp_path, capsys):
    import yaml

    data = yaml.safe_load(GOOD)
    a = run(["analyze", write(tmp_path, GOOD), "--format", "json"], capsys)[1]
    b = run(["analyze", write(tmp_path, json.dumps(data), "m.json"), "--format", "json"], capsys)[1]
    assert json.loads(a)["joints"] == json.loads(b)["joints"]
    assert np.isfinite(json.loads(a)["joints"]["D"]["x"][0])


def test_method_numerical_gives_the_closed_form_numbers(tmp_path, capsys, examples):
    """--method numerical (Newton continued from the pose) prints the numbers of the default method (JSON, 1e-9)."""
    f = str(examples / "seed001_stephenson.yaml")
    a = json.loads(run(["analyze", f, "--format", "json"], capsys)[1])
    code, out, _ = run(["analyze", f, "--format", "json", "--method", "numerical"], capsys)
    b = json.loads(out)
    assert code == 0 and a["joints"].keys() == b["joints"].keys()
    for j in a["joints"]:
        for k in ("x", "y"):
            x, y = np.array(a["joints"][j][k], float), np.array(b["joints"][j][k], float)
            assert np.allclose(x, y, rtol=0, atol=1e-9 * max(1.0, np.nanmax(np.abs(x)))), (j, k)


def test_ground_angle_is_converted_once(examples):
    """The ground's angle is its shape's direction A -> B in the file's unit (seed 000: atan(1/4) in degrees)."""
    import linkagekit as lk

    res = lk.analyze(lk.load(examples / "seed000_fourbar.yaml"), {"crank": [0.0, 30.0]})
    assert np.allclose(res.angle("ground"), np.degrees(np.arctan2(1.0, 4.0)), rtol=0, atol=1e-12)
    assert np.allclose(res.angle("crank"), [0.0, 30.0], rtol=0, atol=1e-12)


def test_at_and_angles_mix_across_drivers(capsys):
    """``--angles crank1=... --at crank2=75`` was refused ('give --at or --angles, not both'); each driver takes one
    of them, and the answer is that of ``--angles crank2=75:75:1`` (a single value is held over the sweep)."""
    five = str(Path(__file__).resolve().parents[1] / "examples" / "fivebar_two_drivers.yaml")
    base = ["analyze", five, "--format", "json", "--angles", "crank1=0:40:10"]
    code, mixed, err = run([*base, "--at", "crank2=75"], capsys)
    assert code == 0, err
    code, swept, err = run([*base, "--angles", "crank2=75:75:1"], capsys)
    assert code == 0 and json.loads(mixed) == json.loads(swept)
    assert len(json.loads(mixed)["inputs"]["crank2"]) == 5


def test_the_script_exits_though_a_thread_it_started_still_waits():
    """After Ctrl-C the line 'interrupted' was printed, then the process hung: the interpreter's exit joins every
    thread, and a killed worker pool's manager thread can wait for ever on a worker that is gone. The script exits
    with its status whatever threads still run (here one that waits for ever, started before the command)."""
    bad = Path(__file__).resolve().parent / "no-such-file.yaml"
    script = (
        "import sys, threading; threading.Thread(target=threading.Event().wait).start(); "
        f"sys.argv = ['linkagekit', 'check', {str(bad)!r}]; from linkagekit.cli import main; main()"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=30)  # it hung
    assert done.returncode == 2 and "no-such-file.yaml" in done.stderr


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_a_method_that_does_not_apply_names_the_file_and_the_option(capsys):
    """The vector-loop method's refusal named the mechanism only ("Jansen's Strandbeest leg: the vector-loop method
    handles ..."): the command line says which file and which option, in one line, exit 2."""
    leg = str(EXAMPLES / "jansen_leg.yaml")
    code, out, err = run(["analyze", leg, "--method", "vector-loop"], capsys)
    assert code == 2 and out == ""
    assert err.startswith(f"linkagekit: error: {leg}: --method vector-loop: a joint joins three or more links: the")
    assert err.count("\n") == 1


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full on this machine")
@pytest.mark.parametrize("args", [["analyze", str(EXAMPLES / "seed000_fourbar.yaml")], ["--version"]])
def test_an_output_that_cannot_be_written_is_one_clear_line(args):
    """``linkagekit analyze FILE > /dev/full`` printed 'internal error: OSError: [Errno 28] ...' (and ``--version``
    exited 0, argparse swallowing the error): one line saying the output cannot be written, and why; exit 2, as
    ``-o /dev/full`` (session 9: it was exit 1 and 'cannot write the output', while ``-o`` gave 2)."""
    script = f"import sys; sys.argv = ['linkagekit', *{args!r}]; from linkagekit.cli import main; main()"
    with open("/dev/full", "w") as full:
        done = subprocess.run(
            [sys.executable, "-c", script], stdout=full, stderr=subprocess.PIPE, text=True, timeout=60
        )
    assert done.returncode == 2
    assert done.stderr == "linkagekit: error: standard output: cannot write: No space left on device\n"


def test_atlas_without_an_action_names_the_choices(capsys):
    """``linkagekit atlas`` said 'the following arguments are required: action' while the usage shows
    ``{build,info}``: the message names the choices."""
    code, out, err = run(["atlas"], capsys)
    assert code == 2 and out == ""
    assert "{build,info}" in err and ": action" not in err and err.count("\n") == 1


def test_check_of_a_sweep_with_more_samples_than_it_evaluates(tmp_path, capsys, monkeypatch):
    # a review: a 600-byte file whose own sweep had 3.6e7 samples took GBs in check (the change points followed
    # the branch through every sample) and died with "internal error: MemoryError"; over the command line's cap
    # (100000 samples) check says the change points and the peak loads were not computed and reports the rest
    import linkagekit.checks as checks

    text = Path("examples/motor_fourbar.yaml").read_text().replace("step: 2}", "step: 0.001}")
    path = write(tmp_path, text, "fine.yaml")

    def refuse(*args, **kwargs):  # the sweep must not be evaluated at all
        raise AssertionError("the file's sweep was evaluated")

    monkeypatch.setattr(checks, "along_sweep", refuse)
    monkeypatch.setattr(checks, "analyze", refuse)
    code, out, err = run(["check", path], capsys)
    assert (code, err) == (0, "")
    why = "the file's sweep has 360001 samples, more than check evaluates (100000)"
    assert f"Change points: not followed ({why})" in out
    assert f"not computed: {why}" in out and "Transmission angle: min 61.4398" in out
    code, out, _ = run(["check", path, "--format", "json"], capsys)
    rep = json.loads(out)
    assert code == 0 and rep["change_points"] is None and rep["change_points_skipped"] == why
    assert rep["dynamics"]["skipped"] == why and rep["input_range"] == [[0.0, 360.0]]


@pytest.mark.parametrize(
    "command", [["analyze"], ["check"], ["modes", "--at", "30"], ["simulate", "--time", "0:1:0.5"]]
)
def test_an_output_naming_the_input_file_is_refused(tmp_path, capsys, monkeypatch, command):
    # a review: `analyze victim.yaml -o victim.yaml` replaced the mechanism file with the command's output (exit 0)
    monkeypatch.chdir(tmp_path)
    write(tmp_path, GOOD, "victim.yaml")
    (tmp_path / "link.yaml").symlink_to(tmp_path / "victim.yaml")
    for out in ("victim.yaml", "./victim.yaml", str(tmp_path / "victim.yaml"), "link.yaml"):
        code, stdout, err = run([command[0], "victim.yaml", *command[1:], "-o", out], capsys)
        head, tail = "linkagekit: error: -o ", ": is the input file victim.yaml; give another\n"
        assert (code, stdout) == (2, "") and err.startswith(head) and err.endswith(tail), err
        named = err[len(head) : -len(tail)]  # the path as given, or (a long one) its end after an ellipsis
        assert named == out or (named.startswith("…") and out.endswith(named[1:]) and len(named) > 20), named
    assert (tmp_path / "victim.yaml").read_text() == GOOD
    if command[0] != "simulate":  # GOOD has no masses to simulate
        assert run([command[0], "victim.yaml", *command[1:], "-o", "out.txt"], capsys)[0] == 0


def test_two_files_a_synthesis_writes_that_are_one_are_refused(tmp_path, capsys, monkeypatch):
    """``--checkpoint`` naming the ``-o`` or ``--plot`` file: each write replaced the other (review 16a)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text("x,y\n0,0\n1,0.2\n2,0.1\n3,0.4\n")
    for extra, words in (
        (["-o", "a.yaml", "--checkpoint", "a.yaml"], "--checkpoint a.yaml: is also -o's file"),
        (["-o", "a.yaml", "--plot", "p.png", "--checkpoint", "./p.png"], "--checkpoint ./p.png: is also --plot's file"),
        (["-o", "t.csv"], "-o t.csv: is the input file t.csv"),
    ):
        code, out, err = run(["synthesize", "t.csv", *extra, "--seconds", "1"], capsys)
        assert (code, out) == (2, "") and words in err and err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv"]


@pytest.mark.parametrize("extra", [[], ["--modes", "--at", "30"], ["-q", "angles"]])
def test_a_long_name_is_cut_in_the_pictures_title(tmp_path, capsys, monkeypatch, extra):
    # a review: `plot` of a file with a 100 kB name took 10 s (1 MB: 112 s) laying out the whole name as the title
    from linkagekit.viz import draw

    titles = []
    monkeypatch.setattr(draw, "save_figure", lambda fig, *a, **k: titles.append(fig._suptitle.get_text()))
    path = write(tmp_path, GOOD.replace("name: four-bar", "name: " + "ab " * 50_000))
    code, _, err = run(["plot", path, "-o", str(tmp_path / "p.png"), *extra], capsys)
    assert (code, err) == (0, "")
    (title,) = titles
    assert 80 <= len(title) < 130 and "ab ab" in title and "…" in title


def test_pivots_and_lengths_take_a_leading_minus_as_a_value(tmp_path, capsys):
    # a review: `--pivots -1:1,-1:1` gave "argument --pivots: expected one argument" (as --angles -90:90:1 once did)
    from linkagekit.cli import _attach_negative_values, build_parser

    argv = ["synthesize", "t.csv", "-o", "o.yaml", "--pivots", "-1:1,-1:1", "--lengths", "-1:5"]
    args = build_parser().parse_args(_attach_negative_values(argv))
    assert (args.pivots, args.lengths) == ("-1:1,-1:1", "-1:5")
    src = write(tmp_path, "x,y\n0,0\n1,0\n1,1\n0,1\n0.5,1.5\n", "t.csv")
    code, _, err = run(["synthesize", src, "--lengths", "-1:5", "-o", str(tmp_path / "o.yaml")], capsys)
    assert (code, err) == (2, "linkagekit: error: --lengths: lengths are not negative\n")


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="no /proc on this machine")
def test_an_output_in_a_directory_that_takes_no_new_file_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    """Review 18b: ``synthesize -o /proc/x.yaml`` failed only after its whole search (the directory exists); the
    directory is tried, by creating and removing a temporary file there, before any work."""
    from unittest import mock

    monkeypatch.chdir(tmp_path)
    write(tmp_path, "x,y\n0,0\n1,0\n1,1\n0,1\n0.5,1.5\n", "t.csv")
    with mock.patch("linkagekit.synthesis.run.synthesize", side_effect=AssertionError("searched")):
        code, _, err = run(["synthesize", "t.csv", "--seconds", "1", "-o", "/proc/x.yaml"], capsys)
    assert code == 2 and err.startswith("linkagekit: error: -o /proc/x.yaml: cannot write there: ")
    assert len(err.splitlines()) == 1 and not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize("command", [["synthesize", "t.csv"], ["plot", "m.yaml"], ["synthesize", "t.csv", "--plot"]])
def test_an_output_that_is_a_directory_is_refused_before_any_work(tmp_path, capsys, monkeypatch, command):
    # a review: `synthesize ... -o DIR.yaml` ran the whole search (60 s by default) before "cannot write"
    monkeypatch.chdir(tmp_path)
    write(tmp_path, "x,y\n0,0\n1,0\n1,1\n0,1\n0.5,1.5\n", "t.csv")
    write(tmp_path, GOOD)
    (tmp_path / "d.yaml").mkdir()
    (tmp_path / "d.png").mkdir()
    out = "d.png" if command[0] == "plot" or command[-1] == "--plot" else "d.yaml"
    argv = [*command, out, "-o", "o.yaml"] if command[-1] == "--plot" else [*command, "-o", out]
    option = "--plot" if command[-1] == "--plot" else "-o"
    code, _, err = run(argv, capsys)
    assert (code, err) == (2, f"linkagekit: error: {option} {out}: cannot write there: it is a directory\n")


@pytest.mark.parametrize(("command", "out"), [("plot", "p.png"), ("report", "r.html"), ("animate", "a.gif")])
def test_a_sweep_too_long_for_a_picture_names_the_file(tmp_path, capsys, monkeypatch, command, out):
    # a review: "the file's sweep has 3600001 samples, ..." named no file (analyze's message did)
    monkeypatch.chdir(tmp_path)  # a short path: a long one is shortened in the message
    write(tmp_path, GOOD.replace("step: 10}", "step: 0.001}"), "fine.yaml")
    code, _, err = run([command, "fine.yaml", "-o", out], capsys)
    assert code == 2 and err.startswith("linkagekit: error: fine.yaml: the file's sweep has 360001 samples, more than")


@pytest.mark.parametrize("command", [["check"], ["analyze"], ["synthesize", "-o", "o.yaml"]])
def test_an_empty_path_is_said_to_be_empty(tmp_path, capsys, monkeypatch, command):
    # a review: `check ""` said ".: is a directory, not a mechanism file" (Path("") is the current directory)
    import linkagekit as lk

    monkeypatch.chdir(tmp_path)
    code, _, err = run([command[0], "", *command[1:]], capsys)
    assert (code, err) == (2, "linkagekit: error: the file path is empty: give the file to read\n")
    with pytest.raises(lk.InputError, match="^load: the file path is empty$"):
        lk.load("")
