"""Limits that keep hostile or extreme input from hanging or exhausting the machine (issue 23, items 1-3).

* the numerical walk of a group follows a fixed grid over at most a turn either way of an
  angle driver (a crank's input is a direction, issue 29): a sample however far away is
  answered as its direction, in a bounded CPU time;
* files are read through a regular-file check and a byte limit (``/dev/zero``, a FIFO, a
  file over the limit: one line naming the file, never a hang or a memory error);
* the Python API refuses complex values and checks sizes before converting anything; the
  command line's ``--angles`` counts samples (not steps) against its limit.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

import linkagekit as lk
from linkagekit.api import prepare
from linkagekit.group import GRID_STEP
from linkagekit.positions import _walk_grid

ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]
TRIAD = ROOT / "examples" / "triad_six_modes.yaml"
FOURBAR = ROOT / "examples" / "seed000_fourbar.yaml"

#: CPU seconds a call may take before it counts as unbounded (generous: catches only the unbounded walk)
CPU_BUDGET = 20.0


def cpu(fn):
    """(fn(), CPU seconds it took)."""
    t = time.process_time()
    out = fn()
    return out, time.process_time() - t


# ---------------------------------------------------------------------- 1. the numerical walk
def test_walk_grid_is_at_most_a_turn_either_way():
    """However far the inputs, the grid the walk follows spans at most a turn either way of the pose's input
    (before issue 29: at most ten turns, and samples beyond were not reached)."""
    params = prepare(lk.load(TRIAD))
    _, grid = _walk_grid(params, np.radians([[[1e11, -1e11, 1e5, -30.0]]]))
    turn = 2 * math.pi / GRID_STEP
    assert len(grid.index) <= 2 * math.ceil(turn) + 3 and grid.index.min() >= -turn - 1 and grid.index.max() <= turn + 1


def _reduced(at: float) -> float:
    return float(np.mod(at, 360.0))  # exact for a float


@pytest.mark.parametrize("at", [1e11, -1e11, 1e5, 1e12])
def test_far_input_of_a_class3_group_is_its_direction_in_bounded_time(at):
    """Before: 1e11 deg was a MemoryError (745 GiB of walk samples) and 1e5 deg took minutes; then (ten turns of
    reach) it was not assembled. A crank's input is a direction: the answer is that of the same direction in
    [0, 360), to the precision the input carries (its conversion to radians rounds by about 1e-16 of it)."""
    mech = lk.load(TRIAD)
    res, spent = cpu(lambda: lk.analyze(mech, np.array([at, -30.0, _reduced(at)])))
    assert res.assembled[1] and res.assembled[0] == res.assembled[2]
    size = max(abs(p) for p in mech.joints.values())
    tol = 1e-9 * size + 1e-15 * math.radians(abs(at)) * 10 * size
    for j in mech.joints:
        assert abs(res.x(j)[0] - res.x(j)[2]) <= tol and abs(res.y(j)[0] - res.y(j)[2]) <= tol, j
    assert spent < CPU_BUDGET


def test_far_input_through_the_command_line_is_its_direction(capsys):
    import json

    from linkagekit.cli import main

    assert main(["analyze", str(TRIAD), "--at", "1e11", "--format", "json"]) == 0
    far = json.loads(capsys.readouterr().out)
    assert main(["analyze", str(TRIAD), "--at", "280", "--format", "json"]) == 0
    near = json.loads(capsys.readouterr().out)
    assert far["assembled"] == near["assembled"] == [True]


def test_far_inputs_numerical_fourbar():
    """A crank-rocker forced onto the numerical group agrees with the closed form (1e-9 of its size) however many
    turns away (before issue 29, beyond ten turns the samples were not reached)."""
    mech = lk.load(FOURBAR)
    x0 = float(np.degrees(prepare(mech).pose_inputs[0, 0]))
    reach = 3600.0
    x = x0 + np.array([reach - 0.5, -reach + 0.5, 17.0, reach - 200.3, reach + 0.5, -reach - 0.5, 1e7 + 0.25])
    num, spent = cpu(lambda: lk.analyze(mech, x, method="numerical", rates=False))
    closed = lk.analyze(mech, x, rates=False)
    assert closed.assembled.all() and num.assembled.all()
    size = max(abs(p) for p in mech.joints.values())
    for j in mech.joints:
        got = num.x(j) + 1j * num.y(j)
        want = closed.x(j) + 1j * closed.y(j)
        assert np.max(np.abs(got - want)) <= 1e-9 * size, j
    assert spent < CPU_BUDGET


# ---------------------------------------------------------------------- 2. reading files
def _hang_guard(seconds: float = 20.0):
    """A SIGALRM that turns a hang into a failure (a FIFO opened for reading blocks for ever without care)."""
    import contextlib
    import signal

    @contextlib.contextmanager
    def guard():
        def fire(signum, frame):
            raise TimeoutError("no answer: the reader blocked")

        old = signal.signal(signal.SIGALRM, fire)
        signal.setitimer(signal.ITIMER_REAL, seconds)
        try:
            yield
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, old)

    return guard()


def _read_mechanism(path) -> str:
    from linkagekit.errors import MechanismFileError

    with _hang_guard(), pytest.raises(MechanismFileError) as exc:
        lk.load(path)
    return str(exc.value)


def _read_targets(path) -> str:
    from linkagekit.errors import InputError

    with _hang_guard(), pytest.raises(InputError) as exc:
        lk.read_targets(path)
    return str(exc.value)


@pytest.mark.skipif(not __import__("os").path.exists("/dev/zero"), reason="needs /dev/zero")
def test_dev_zero_is_refused_before_reading():
    """Before: read until memory ran out (internal error)."""
    (msg_m, spent_m), (msg_t, spent_t) = (
        cpu(lambda: _read_mechanism("/dev/zero")),
        cpu(lambda: _read_targets("/dev/zero")),
    )
    assert msg_m == "/dev/zero: not a regular file (a character device): not a mechanism file"
    assert msg_t == "/dev/zero: not a regular file (a character device): not a target file"
    assert spent_m < 1.0 and spent_t < 1.0


@pytest.mark.skipif(not hasattr(__import__("os"), "mkfifo"), reason="needs FIFOs")
@pytest.mark.parametrize("name", ["m.yaml", "t.csv"])
def test_fifo_is_refused_without_waiting(tmp_path, name):
    """Before: open() of a FIFO with no writer blocked for ever."""
    import os

    fifo = tmp_path / name
    os.mkfifo(fifo)
    msg = _read_mechanism(fifo) if name == "m.yaml" else _read_targets(fifo)
    kind = "mechanism" if name == "m.yaml" else "target"
    assert msg == f"{fifo}: not a regular file (a FIFO): not a {kind} file"


def test_too_large_mechanism_file_says_so(tmp_path):
    """Before: 'not a usable path' (the size error was caught as a ValueError)."""
    from linkagekit.files import MAX_FILE_BYTES

    big = tmp_path / "big.yaml"
    big.write_bytes(b"#" * (MAX_FILE_BYTES + 1))
    assert _read_mechanism(big) == f"{big}: more than 4194304 bytes (4 MiB), more than a mechanism file may have"
    ok = tmp_path / "ok.yaml"  # exactly at the limit: read (and then refused for what it holds, not its size)
    ok.write_bytes(b"#" * MAX_FILE_BYTES)
    assert "bytes" not in _read_mechanism(ok)


def test_cli_names_the_file_and_exits_2(tmp_path, capsys):
    import os

    from linkagekit.cli import main

    fifo = tmp_path / "pipe.yaml"
    os.mkfifo(fifo)
    with _hang_guard():
        assert main(["check", str(fifo)]) == 2
        assert main(["check", str(tmp_path)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err == [
        f"linkagekit: error: {fifo}: not a regular file (a FIFO): not a mechanism file",
        f"linkagekit: error: {tmp_path}: is a directory, not a mechanism file",
    ]


def _with(key: str, value) -> dict:
    import yaml

    data = yaml.safe_load(FOURBAR.read_text(encoding="utf-8"))
    data[key] = value
    return data


@pytest.mark.parametrize(
    ("key", "value", "code"),
    [
        ("name", "evil\u202etxt.exe", "U+202E"),
        ("name", "clear\x1b[2Jscreen", "U+001B"),
        ("name", "two\nlines", "U+000A"),
        ("name", "zero\u200bwidth", "U+200B"),
        ("description", "right-to-left \u202e mark", "U+202E"),
        ("description", "bell \x07", "U+0007"),
    ],
)
def test_mechanism_name_and_description_refuse_control_characters(key, value, code):
    """Before: the name was printed raw to the terminal (joint names were already refused)."""
    from linkagekit.errors import MechanismFileError

    with pytest.raises(MechanismFileError) as exc:
        lk.Mechanism.from_dict(_with(key, value), source="m.yaml")
    msg = str(exc.value)
    assert msg.startswith(
        f"m.yaml: {key}: a {'name' if key == 'name' else 'description'} with control or format characters"
    )
    assert code in msg and msg.isprintable()


def test_joint_names_are_refused_alike():
    from linkagekit.errors import MechanismFileError

    data = _with("name", "ok")
    data["joints"]["A\u202e"] = data["joints"].pop("A")
    with pytest.raises(MechanismFileError, match="a name with control or format characters"):
        lk.Mechanism.from_dict(data, source="m.yaml")


def test_printable_names_and_multiline_descriptions_are_kept():
    m = lk.Mechanism.from_dict(_with("description", "line one\n\tline two é ü 中"), source="m.yaml")
    assert m.description == "line one\n\tline two é ü 中"
    m = lk.Mechanism.from_dict(_with("name", "Vierfach-Gelenk ü (t = +1) 中"), source="m.yaml")
    assert m.name == "Vierfach-Gelenk ü (t = +1) 中"


# ---------------------------------------------------------------------- 3. the API and the command line
def _pose(mech) -> np.ndarray:
    return np.array([[p.real, p.imag] for p in mech.joints.values()])[None]


@pytest.mark.parametrize(
    "kwargs",
    [
        {"poses": "complex"},
        {"inputs": np.array([10.0 + 1e-3j])},
        {"inputs": {"crank": [10.0, 20.0 + 0j]}},
        {"inputs": [0.0, 1.0], "speed": np.array([1.0 + 2j])},
        {"inputs": [0.0], "acceleration": [3j]},
        {"inputs": [0.0], "signs": np.array([1.0 + 1j, 1.0])},
    ],
)
def test_complex_values_are_refused(kwargs):
    """Before: the imaginary part was dropped silently (poses) or with a ComplexWarning."""
    from linkagekit.errors import InputError

    mech = lk.load(FOURBAR)
    kw = dict(kwargs)
    if kw.get("poses") == "complex":
        kw["poses"] = _pose(mech) + 1j
    inputs = kw.pop("inputs", None)
    with pytest.raises(InputError, match="expected real .*, got complex values"):
        lk.analyze(mech, inputs, **kw)
    if "poses" in kw:
        with pytest.raises(InputError, match="got complex values"):
            next(lk.analyze_chunks(mech, None, poses=kw["poses"]))


@pytest.mark.parametrize("dtype", [float, np.int64, np.float32, bool])
def test_sizes_are_checked_before_converting(dtype):
    """Before: MemoryError (the float conversion and isfinite of 10^11 values) before the size check."""
    from linkagekit.errors import InputError

    mech = lk.load(FOURBAR)
    huge = np.broadcast_to(np.ones((), dtype), (10**11,))
    (_, spent) = cpu(lambda: pytest.raises(InputError, lk.analyze, mech, {"crank": huge}))
    with pytest.raises(InputError, match=r"100000000000 samples\), more than linkagekit.api.MAX_RESULT_BYTES"):
        lk.analyze(mech, {"crank": huge})
    with pytest.raises(InputError, match=r"speed\[crank\]: 100000000000 values for 2 samples"):
        lk.analyze(mech, [0.0, 1.0], speed=huge)
    assert spent < 1.0


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("0:100000:1", "100001 samples, more than the command line takes (100000)"),
        ("0:1000000:1", "1000001 samples, more than the command line takes (100000)"),
        ("0:1e12:1e-3", "over 1000000 samples, more than the command line takes (100000)"),
        ("0:1:1e-300", "over 1000000 samples, more than the command line takes (100000)"),
    ],
)
def test_angles_count_samples_against_the_limit(text, message):
    """Before: 0:100000:1 (100,001 samples) was accepted, and refusals printed counts as 1e+05."""
    from linkagekit.cli import _range
    from linkagekit.errors import InputError

    with pytest.raises(InputError) as exc:
        _range(text, "--angles")
    assert str(exc.value).startswith(f"--angles: {message}")


def test_a_time_range_over_the_limit_points_to_the_api_that_simulates():
    """Review 18b: ``simulate --time 0:1:1e-6`` suggested lk.analyze_chunks, which does not simulate."""
    from linkagekit.cli import _range
    from linkagekit.errors import InputError

    with pytest.raises(InputError, match=r"the Python API \(lk\.simulate\) for more$"):
        _range("0:1:1e-6", "--time")
    with pytest.raises(InputError, match=r"the Python API \(lk\.analyze_chunks\) for more$"):
        _range("0:360:1e-4", "--angles")


def test_angles_at_the_limit_are_accepted():
    from linkagekit.cli import MAX_SAMPLES, _range

    x = _range("0:99999:1", "--angles")
    assert len(x) == MAX_SAMPLES and x[0] == 0.0 and x[-1] == 99999.0
    assert _range("0:360:0.5", "--angles").tolist() == [0.5 * i for i in range(721)]


def test_file_sweep_over_the_limit_prints_a_whole_number(tmp_path, capsys):
    from linkagekit.cli import main

    f = tmp_path / "long.yaml"
    f.write_text(
        FOURBAR.read_text(encoding="utf-8").replace(
            "angles: {start: 0, stop: 360, step: 1}", "angles: {start: 0, stop: 100000, step: 1}"
        ),
        encoding="utf-8",
    )
    assert "stop: 100000" in f.read_text(encoding="utf-8")
    assert main(["analyze", str(f)]) == 2
    assert main(["plot", str(f), "-o", str(tmp_path / "p.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("the file's sweep has 100001 samples, more than the command line takes (100000)") == 2


def test_report_reads_the_source_again_under_the_same_guard(tmp_path):
    """The page shows the file's text, read again after loading: a FIFO or device there gives None at once."""
    import os

    from linkagekit.cli import _source_text

    src = tmp_path / "m.yaml"
    src.write_text("name: x\n", encoding="utf-8")
    assert _source_text(str(src)) == "name: x\n"
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    assert _source_text(str(fifo)) is None  # does not wait for a writer
    assert _source_text("/dev/zero") is None  # not read at all
    big = tmp_path / "big.yaml"
    big.write_bytes(b"#" * ((4 << 20) + 1))
    assert _source_text(str(big)) is None


@pytest.mark.parametrize(
    "value", ["12", ["0", "90"], np.array(["1"]), [None], np.array(["2026-01-01"], dtype="datetime64[D]")]
)
def test_inputs_that_are_not_numbers_are_refused(value):
    """A string that reads as a number is still not one: the input is refused in one line, never parsed."""
    mech = lk.load("examples/seed000_fourbar.yaml")
    with pytest.raises(lk.InputError, match="expected numbers"):
        lk.analyze(mech, {"crank": value})


def test_analyze_answers_far_samples_as_their_direction(capsys):
    """A sample many turns of a crank from the pose's input answers as its direction, with no note (before issue
    29 it was not assembled and a note said the walk did not go that far)."""
    from linkagekit import cli

    assert cli.main(["analyze", "examples/triad_six_modes.yaml", "--at", "1e11,60,-5000", "--format", "csv"]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    assert cli.main(["analyze", "examples/triad_six_modes.yaml", "--at", "280,60,40", "--format", "csv"]) == 0
    near, _ = capsys.readouterr()
    for far_row, near_row in zip(out.splitlines()[1:], near.splitlines()[1:], strict=True):
        a, b = far_row.split(",")[1:], near_row.split(",")[1:]
        assert a[:2] == b[:2] == ["true", "false"]  # assembled, not singular
        assert np.allclose([float(v) for v in a[2:]], [float(v) for v in b[2:]], rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize(
    "text",
    ["[" * 25000 + "]" * 25000, "- " * 25000 + "x", "{a: " * 25000 + "1" + "}" * 25000],
    ids=["flow sequences", "block sequences", "flow maps"],
)
def test_yaml_nested_beyond_the_c_parsers_recursion_is_refused_not_a_crash(tmp_path, text):
    """25000 levels of ``[`` (50 kB) crashed the interpreter: libyaml composes recursively in C (a segmentation
    fault, exit status 139, no message; ``lk.load`` took a notebook down with it). Refused from the parser's events
    before anything is composed: one line, exit status 2. (A separate process: a crash must not take pytest's.)"""
    import subprocess
    import sys

    f = tmp_path / "deep.yaml"
    f.write_text(text)
    p = subprocess.run(
        [sys.executable, "-c", "from linkagekit.cli import main; import sys; sys.exit(main())", "check", str(f)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 2, (p.returncode, p.stderr[-300:])
    # ours, or (PyYAML 6.0.4 and later, flow collections) its scanner's own limit of 1000, met first
    line = p.stderr.splitlines()
    assert len(line) == 1 and line[0].startswith(f"linkagekit: error: {f}"), p.stderr
    assert "nested too deep (at most 32 levels)" in line[0] or "exceeded maximum nesting depth" in line[0], p.stderr


def test_yaml_collections_count_once_against_the_values_limit(tmp_path):
    """The parser's events were counted with each collection's end as a second value: 110000 empty lists (a
    file the composed count accepts) were refused as 'more than 200000 values'. Ends do not count."""
    from linkagekit.files import MAX_VALUES, _bounded_events

    _bounded_events("[" + ", ".join(["[]"] * 110_000) + "]", "f.yaml")  # 110001 values: fine
    with pytest.raises(lk.MechanismFileError, match=f"more than {MAX_VALUES} values"):
        _bounded_events("[" + ", ".join(["[]"] * 200_000) + "]", "f.yaml")


@pytest.mark.parametrize("name", ["seed000_fourbar.yaml", "triad_six_modes.yaml"])
def test_a_mechanism_below_1e30_of_its_unit_is_refused_and_one_just_above_is_solved(name):
    """Review 18b: with no least size, a four-bar scaled to 1e-160 m said "assembled" with null positions (the squares
    of its lengths underflow below 1e-154), and a triad at 1e-200 was an internal error (LinAlgError) in ``analyze``
    and in the editor. A mechanism spanning less than 1e-30 of its unit is refused in one line naming ``joints``; at
    1e-29 (and at 1e-12, review 18d: a slider's joints 1e-12 apart were refused at a first bound of 1e-9) the
    positions are the unscaled ones scaled, to 1e-9 of the size."""
    from linkagekit.errors import MechanismFileError

    d = lk.load(ROOT / "examples" / name).to_dict()
    d.pop("lengths", None)
    d["links"] = {k: (v["joints"] if isinstance(v, dict) else v) for k, v in d["links"].items()}
    base = lk.Mechanism.from_dict(d)
    size = max(abs(complex(*a) - complex(*b)) for a in d["joints"].values() for b in d["joints"].values())
    driver = base.drivers[0].name
    want = lk.analyze(base, {driver: [0.0, 20.0]}, rates=False)

    def scaled(f: float) -> dict:  # type: ignore[type-arg]
        return {**d, "joints": {k: [f * v[0], f * v[1]] for k, v in d["joints"].items()}}

    with pytest.raises(MechanismFileError, match=r"joints: they span .* less than 1e-30 (mm|cm|m|in): scale"):
        lk.Mechanism.from_dict(scaled(1e-160 / size))
    for small in (1e-29, 1e-12):
        f = small / size
        got = lk.analyze(lk.Mechanism.from_dict(scaled(f)), {driver: [0.0, 20.0]}, rates=False)
        assert np.array_equal(got.assembled, want.assembled)
        for j in base.joint_names:
            a, b = got.point(j), f * want.point(j)
            ok = np.isfinite(b)
            assert np.array_equal(np.isfinite(a), ok) and np.all(np.abs(a[ok] - b[ok]) <= 1e-9 * small)


def test_a_batch_design_too_small_to_solve_is_flagged_not_garbage():
    """Review 18d: ``lk.analyze(poses=...)`` with a design at 1e-160 said "assembled" with NaN positions (a file that
    small is refused); such a design of a batch is flagged as not assembling, the others solved as alone."""
    d = lk.load(ROOT / "examples" / "seed000_fourbar.yaml").to_dict()
    d["links"] = {k: (v["joints"] if isinstance(v, dict) else v) for k, v in d["links"].items()}
    mech = lk.Mechanism.from_dict(d)
    p = mech.pose_array()
    res = lk.analyze(mech, {"crank": [0.0, 30.0]}, poses=np.stack([p, p * 1e-160, p * 1e-25]), rates=False)
    assert res.assembled.tolist() == [[True, True], [False, False], [True, True]]
    assert np.all(np.isnan(res.point("D")[1])) and np.allclose(res.point("D")[2], 1e-25 * res.point("D")[0])
