"""Command-line defects an attack found (session 9): each test fails on the code before its fix.

Every bad input is one line on stderr naming the file, option, joint or link, exit status 2.
"""

from __future__ import annotations

import functools
import json
import os
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from linkagekit.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

FOURBAR = """\
format: linkagekit/1
name: four-bar
joints:
  A: [0, 0]
  B: [4, 1]
  C: [2, 0]
  D: [0.8206, 4.8589]
  E: [3, 7]
links:
  ground: [A, B]
  crank: [A, C]
  coupler: {joints: [C, D], lengths: {C-D: COUPLER}}
  rocker: [B, D]
  extra: {joints: [D, E], lengths: {D-E: EXTRA}}
  out: [B, E]
drivers:
  - {link: crank, pivot: A, toward: C}
"""


def run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def write(tmp_path: Path, text: str, name: str = "m.yaml") -> str:
    """Write ``text`` to ``name`` in ``tmp_path``, the working directory of these tests (``here``): a short path, as
    a long one (xdist's) is shortened in the messages."""
    (tmp_path / name).write_text(text)
    return name


@pytest.fixture(autouse=True)
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    return tmp_path


# ---------------------------------------------------------------- 2. a pose that does not assemble
@pytest.mark.parametrize(
    ("coupler", "extra", "named"),
    [
        # the coupler (20) is longer than crank + ground + rocker: D cannot be placed (step 3, after A, B and C)
        ("20", "6", "joint D of links 'coupler', 'rocker' cannot be placed (step 3 of the plan: D = circle(C, 20) x"),
        # D closes; the extra link (30) cannot reach E from D with 'out' from B: step 4
        ("5", "30", "joint E of links 'extra', 'out' cannot be placed (step 4 of the plan: E = circle(D, 30) x"),
    ],
)
@pytest.mark.parametrize("command", [["check"], ["analyze"], ["modes", "--at", "0"]])
def test_a_pose_that_does_not_assemble_names_the_joint_links_and_step(tmp_path, capsys, command, coupler, extra, named):
    """Given lengths that cannot close at the pose's input said 'the mechanism does not assemble at its reference
    pose's input (given lengths that do not close, or a degenerate pose ...)': no joint, link or step was named."""
    path = write(tmp_path, FOURBAR.replace("COUPLER", coupler).replace("EXTRA", extra))
    code, out, err = run([command[0], path, *command[1:]], capsys)
    assert (code, out) == (2, "")
    assert err.startswith(f"linkagekit: error: {path}: does not assemble at its reference pose's input: {named}")
    assert err.count("\n") == 1 and err.endswith(": no solution with the given lengths)\n")


def test_a_slider_whose_rod_cannot_reach_its_line_names_the_rod(tmp_path, capsys):
    """The circle-and-line step names its joint and its one link."""
    text = (EXAMPLES / "slider_crank.yaml").read_text().replace("A-B: 0.0939414711402797", "A-B: 0.01")
    path = write(tmp_path, text)
    code, out, err = run(["check", path], capsys)
    assert (code, out) == (2, "")
    assert err.startswith(
        f"linkagekit: error: {path}: does not assemble at its reference pose's input: joint B of link 'rod' cannot "
        "be placed (step 3 of the plan: B = circle(A, 0.01) x line of slider 0: no solution"
    )
    assert err.count("\n") == 1


def test_a_numerical_group_that_does_not_assemble_at_the_pose_is_refused(tmp_path, capsys):
    """A class-3 triad whose given length cannot close was accepted: `check` said 'assembles nowhere', exit 0, and
    `analyze` gave every sample not assembled. It is refused as a closed-form step is, naming the group's joints and
    links."""
    text = (EXAMPLES / "triad_six_modes.yaml").read_text()
    path = write(tmp_path, text.replace("l1: [A, J1]", "l1: {joints: [A, J1], lengths: {A-J1: 60}}"))
    for command in (["check", path], ["analyze", path, "--at", "0"]):
        code, out, err = run(command, capsys)
        assert (code, out) == (2, "")
        assert err == (
            f"linkagekit: error: {path}: does not assemble at its reference pose's input: joints J1, J2, J3 of links "
            "'l1', 'l2', 'l3', 'tern' cannot be placed (step 3 of the plan: J1, J2, J3 placed numerically: "
            "no solution with the given lengths)\n"
        )
        assert err.count("\n") == 1
    good = write(tmp_path, text.replace("l1: [A, J1]", "l1: {joints: [A, J1], lengths: {A-J1: 10.02}}"), "ok.yaml")
    assert run(["check", good], capsys)[0] == 0  # a length that closes is taken, as before


# ---------------------------------------------------------------- 1. an output that cannot be written
FULL = Path("/dev/full")
needs_full = pytest.mark.skipif(not FULL.is_char_device(), reason="no /dev/full on this machine")


def _script(args: list[str], stdout: object) -> subprocess.CompletedProcess[str]:
    """The ``linkagekit`` script (``main()`` without arguments, as installed) with ``args`` and this stdout."""
    script = f"import sys; sys.argv = ['linkagekit', *{args!r}]; from linkagekit.cli import main; main()"
    return subprocess.run(
        [sys.executable, "-c", script], stdout=stdout, stderr=subprocess.PIPE, text=True, timeout=120, check=False
    )


@needs_full
@pytest.mark.parametrize("fmt", ["table", "csv", "json"])
def test_a_full_device_fails_alike_on_standard_output_and_on_o(fmt):
    """``analyze FILE > /dev/full`` exited 1 ('cannot write the output: ...') while ``-o /dev/full`` exited 2: both
    are one line naming where the output went, and why, exit 2."""
    args = ["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--format", fmt]
    with FULL.open("w") as full:
        piped = _script(args, full)
    given = _script([*args, "-o", str(FULL)], subprocess.DEVNULL)
    assert (piped.returncode, piped.stderr) == (
        2,
        "linkagekit: error: standard output: cannot write: No space left on device\n",
    )
    assert (given.returncode, given.stderr) == (
        2,
        "linkagekit: error: -o /dev/full: cannot write: No space left on device\n",
    )
    assert FULL.is_char_device()


def _reader(fifo: Path, limit: int | None, got: list[bytes]) -> threading.Thread:
    """A thread that reads ``fifo`` (``limit`` bytes then closes it, or to its end) into ``got``."""

    def read() -> None:
        with fifo.open("rb") as fh:
            got.append(fh.read(limit) if limit is not None else fh.read())

    t = threading.Thread(target=read, daemon=True)
    t.start()
    return t


def test_a_picture_through_a_link_to_a_pipe_is_written_into_the_pipe(here, capsys):
    """``plot -o out.svg`` where out.svg is a link to a FIFO (or to ``/dev/full``, ``/dev/null``) replaced the
    link's target with a regular file: as root it replaced the device ``/dev/full`` itself. A device or a pipe is
    written in place; the FIFO stays a FIFO and its reader gets the picture."""
    fifo = here / "fifo"
    os.mkfifo(fifo)
    (here / "out.svg").symlink_to(fifo)
    got: list[bytes] = []
    reader = _reader(fifo, None, got)
    code, out, err = run(["plot", str(EXAMPLES / "seed000_fourbar.yaml"), "-o", "out.svg"], capsys)
    reader.join(30)
    assert (code, out, err) == (0, "", "")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and (here / "out.svg").is_symlink()
    assert got and got[0].startswith(b"<?xml") and got[0].rstrip().endswith(b"</svg>")


def test_a_reader_gone_from_o_is_quiet_as_on_standard_output(here, capsys):
    """``analyze -o FIFO`` whose reader left after 10 bytes said 'cannot write: Broken pipe', exit 2, where the same
    reader on standard output (``| head``) is quiet, exit 1: both are quiet, exit 1."""
    fifo = here / "fifo"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = _reader(fifo, 10, got)
    args = ["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--angles", "0:360:0.01", "--format", "csv"]
    code, out, err = run([*args, "-o", "fifo"], capsys)
    reader.join(30)
    assert (code, out, err) == (1, "", "")
    assert got == [b"input:cran"]


# ---------------------------------------------------------------- 3. driver names holding ',' or '='
ODD_NAMES = """\
format: linkagekit/1
name: five-bar with odd driver names
units: {length: m, angle: deg}
joints:
  A: [0, 0]
  E: [3, 0]
  B: [0, 1]
  D: [3, 1]
  C: [1.5, 2.5]
links:
  ground: [A, E]
  "arm,left": [A, B]
  "arm=right": [E, D]
  c1: [B, C]
  c2: [D, C]
drivers:
  - {link: "arm,left", pivot: A, toward: B}
  - {link: "arm=right", pivot: E, toward: D}
"""


def test_a_driver_name_with_a_comma_or_an_equals_sign_is_given_as_written(tmp_path, capsys):
    """A driver (a link) named 'arm=right' could not be given: ``--at arm=right=90`` said "no driver named 'arm'".
    NAME is everything before the last '=' (a value never holds one): every option takes the names as written."""
    path = write(tmp_path, ODD_NAMES)
    code, out, err = run(
        ["analyze", path, "--at", "arm,left=90,100", "--at", "arm=right=90", "--speed", "arm=right=2",
         "--speed", "arm,left = 1", "--format", "json"],
        capsys,
    )  # fmt: skip
    assert (code, err) == (0, "")
    res = json.loads(out)
    assert res["inputs"] == {"arm,left": [90.0, 100.0], "arm=right": [90.0, 90.0]}
    b = res["joints"]["B"]
    assert b["x"][0] == pytest.approx(0.0, abs=1e-12) and b["y"][0] == pytest.approx(1.0, abs=1e-12)
    assert b["vx"][0] == pytest.approx(-1.0, abs=1e-12)  # |AB| = 1 turning at 1 rad/s from 90 deg
    assert res["joints"]["D"]["vx"][0] == pytest.approx(-2.0, abs=1e-12)  # |ED| = 1 at 2 rad/s
    code, out, err = run(["modes", path, "--at", "arm,left=90", "--at", "arm=right=90", "--format", "json"], capsys)
    assert (code, err) == (0, "") and json.loads(out)["input"] == {"arm,left": 90.0, "arm=right": 90.0}


def test_an_unknown_driver_lists_the_names_quoted(tmp_path, capsys):
    """The list of drivers in the message read 'drivers: arm,left, arm=right': each name is quoted."""
    path = write(tmp_path, ODD_NAMES)
    code, out, err = run(["analyze", path, "--at", "arm=90"], capsys)
    assert (code, out) == (2, "")
    assert err == "linkagekit: error: --at: no driver named 'arm' (drivers: 'arm,left', 'arm=right')\n"


# ---------------------------------------------------------------- 4. plot --at has a cap
@pytest.mark.parametrize(
    ("values", "n"),
    [
        ([",".join(str(i % 360) for i in range(100_000))], 100_000),
        (["crank1=" + ",".join(str(i % 360) for i in range(1001)), "crank2=75"], 1001),
    ],
)
def test_plot_at_takes_at_most_as_many_poses_as_an_animation_has_frames(capsys, values, n):
    """``plot --at`` with 100,000 values (the command line's cap on a list) drew every pose: minutes, and memory.
    It takes at most MAX_POSES (1000, an animation's most frames), refused before anything is solved or drawn."""
    from linkagekit.cli import MAX_POSES
    from linkagekit.viz.animate import MAX_FRAMES

    assert MAX_POSES == MAX_FRAMES == 1000
    fourbar = str(EXAMPLES / "seed000_fourbar.yaml")
    path = fourbar if len(values) == 1 else str(EXAMPLES / "fivebar_two_drivers.yaml")
    args = [a for v in values for a in ("--at", v)]
    start = time.perf_counter()
    code, out, err = run(["plot", path, *args, "-o", "p.png"], capsys)
    assert time.perf_counter() - start < 20  # refused at once (it ran for minutes)
    assert (code, out) == (2, "")
    assert err == (
        f"linkagekit: error: --at: {n} values, more poses than plot draws (1000): give fewer, or --angles for the "
        "curves of a sweep\n"
    )
    assert not Path("p.png").exists()


@pytest.mark.long  # 4 s: the suite's five minutes
def test_plot_at_of_a_thousand_poses_is_drawn(capsys):
    """The cap is MAX_POSES itself: 1000 values are drawn."""
    fourbar = str(EXAMPLES / "seed000_fourbar.yaml")
    code, out, err = run(
        ["plot", fourbar, "--at", ",".join(f"{0.36 * i:g}" for i in range(1000)), "-o", "p.svg"], capsys
    )
    assert (code, out, err) == (0, "", "") and Path("p.svg").read_text().rstrip().endswith("</svg>")


# ---------------------------------------------------------------- 5. a large numerical group's conditioning
def test_a_large_groups_conditioning_is_the_svds_without_the_tridiagonal_form(monkeypatch):
    """``analyze --method numerical`` on a 97-joint chain spent 7.4 of its 10 s in the Python-level tridiagonal form
    of J^T J (about n^3 / 3 array operations for n = 194 columns), then took the SVD anyway. Above
    COND_TRIDIAGONAL_MOST columns every matrix goes to LAPACK's SVD at once: the same numbers (to rounding)."""
    import numpy as np

    from linkagekit import group

    rng = np.random.default_rng(5)
    # well conditioned (above COND_EXACT: the old path answered from the eigenvalues) and ill conditioned
    good = np.eye(40)[None] * 3 + 0.05 * rng.normal(size=(4, 40, 40))
    bad = rng.normal(size=(3, 40, 40)) @ np.diag(np.geomspace(1, 1e-6, 40))
    small = rng.normal(size=(5, 6, 6))  # a triad's 6 columns keep the tridiagonal way
    expect = {
        k: (lambda s: s[:, -1] / s[:, 0])(np.linalg.svd(m, compute_uv=False)) for k, m in (("g", good), ("b", bad))
    }
    tridiagonal = group._gram_tridiagonal
    calls: list[int] = []
    monkeypatch.setattr(group, "_gram_tridiagonal", lambda Js: calls.append(Js.shape[2]) or tridiagonal(Js))
    assert group.COND_TRIDIAGONAL_MOST == 18
    np.testing.assert_allclose(group._condition(good), expect["g"], rtol=1e-12, atol=0)
    np.testing.assert_allclose(group._condition(bad), expect["b"], rtol=1e-9, atol=0)
    assert calls == []
    s = np.linalg.svd(small, compute_uv=False)
    np.testing.assert_allclose(group._condition(small), s[:, -1] / s[:, 0], rtol=1e-12, atol=0)
    assert calls == [6]


def test_dyad_like_is_counted_once_per_group():
    """The walk asked ``Group.dyad_like`` at every restart and it recounted the links each time (0.6 s of the
    chain's sweep): it is a cached property of the (immutable) group, the same answer."""
    import linkagekit as lk
    from linkagekit.group import Group
    from linkagekit.plan import make_plan

    plan = make_plan(lk.load(EXAMPLES / "triad_six_modes.yaml"), numerical=True)
    (st,) = [s for s in plan.steps if isinstance(s, Group)]
    assert st.dyad_like is False and "dyad_like" in vars(st)
    assert isinstance(vars(Group)["dyad_like"], functools.cached_property)


def test_two_drivers_given_unequal_sweeps_are_named_both_and_told_how_they_combine(capsys):
    """Before: "inputs: driver 'crank2' has 4 values but another has 5", naming the API's argument and not the
    other driver, and not saying that the values pair up sample by sample (review 16c)."""
    path = EXAMPLES / "fivebar_two_drivers.yaml"
    code, out, err = run(["analyze", str(path), "--angles", "crank1=0:40:10", "--angles", "crank2=0:30:10"], capsys)
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert "driver 'crank2' is given 4 values and driver 'crank1' 5" in err and "sample by sample" in err, err


def test_a_force_plot_of_a_mechanism_without_forces_says_what_gives_forces(tmp_path, capsys):
    """``plot -q torques`` of a massless four-bar said only "this mechanism has no driver torques" (review 16c)."""
    out = tmp_path / "t.png"
    code, _, err = run(["plot", str(EXAMPLES / "seed000_fourbar.yaml"), "-q", "torques", "-o", str(out)], capsys)
    assert code == 2 and err.count("\n") == 1 and not out.exists(), err
    assert "no driver torques (forces are computed when the file gives masses, gravity, loads" in err, err
    code, _, err = run(["plot", str(EXAMPLES / "slider_crank.yaml"), "-q", "forces", "-o", str(out)], capsys)
    assert code == 2 and err.strip().endswith("this mechanism has no driver forces"), err  # it has forces: a crank


def test_a_file_name_that_is_not_utf8_makes_a_readable_page_and_file(tmp_path, capsys):
    """A file name with a byte that is not UTF-8 (``four\\xff.yaml``): ``report`` stopped with "internal error:
    UnicodeEncodeError", and a synthesis of ``tg\\xff.csv`` wrote its name into the mechanism's description as
    ``\\uDCFF``, a file linkagekit then refused to read (review 16a). Both write U+FFFD for the byte."""
    import dataclasses

    import linkagekit as lk

    src = tmp_path / os.fsdecode(b"four\xff.yaml")
    src.write_bytes((EXAMPLES / "seed000_fourbar.yaml").read_bytes())
    code, _, err = run(["report", str(src), "-o", str(tmp_path / "r.html")], capsys)
    assert code == 0, err
    assert "four\ufffd.yaml" in (tmp_path / "r.html").read_text(encoding="utf-8")
    mech = dataclasses.replace(lk.load(src), description="from " + os.fsdecode(b"tg\xff.csv"))
    lk.save(mech, tmp_path / "out.yaml")
    assert lk.load(tmp_path / "out.yaml").description == "from tg\ufffd.csv"


def test_a_number_on_the_command_line_is_written_as_in_a_file(capsys):
    """``--at 1_000`` and full-width digits (``１２``) were taken (Python's float), which the file reader refuses
    (review 16a)."""
    for text in ("1_000", "\uff11\uff12"):
        code, out, err = run(["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--at", text], capsys)
        assert (code, out) == (2, "") and f"{text!r} is not a number" in err, err


def test_a_table_written_with_o_that_fails_half_way_leaves_the_old_file(tmp_path: Path) -> None:
    """Review 18b: ``analyze -o prev.csv`` opened the file for writing (emptying it) and wrote; under a file-size
    limit it stopped at 10240 bytes mid-row and the old file was gone. It is written in one step, as pictures are:
    the old file stays, whole, and the line names ``-o``."""
    import resource

    (tmp_path / "prev.csv").write_text("OLD\n")

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (10240, 10240))  # Python ignores SIGXFSZ: writes fail, EFBIG

    args = ["analyze", str(EXAMPLES / "jansen_leg.yaml"), "--angles", "0:360:0.5", "--format", "csv", "-o", "prev.csv"]
    script = f"import sys; sys.argv = ['linkagekit', *{args!r}]; from linkagekit.cli import main; main()"
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=False,
        preexec_fn=small_files, cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 2 and done.stderr.startswith("linkagekit: error: -o prev.csv: cannot write: ")
    assert len(done.stderr.splitlines()) == 1
    assert (tmp_path / "prev.csv").read_text() == "OLD\n"
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize("command", ["plot", "analyze"])
def test_output_names_near_and_over_the_limit(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    """Review 18b: a valid 240-character name was refused by ``plot`` (its temporary file's name went over 255), and a
    300-character one was an internal error (``is_symlink`` raised ENAMETOOLONG). The first is written, the second
    is one line naming ``-o``, exit 2."""
    ext = ".png" if command == "plot" else ".csv"
    ok = "b" * (240 - len(ext)) + ext
    extra = ["--format", "csv"] if command == "analyze" else []
    assert main([command, str(EXAMPLES / "seed000_fourbar.yaml"), *extra, "-o", ok]) == 0
    assert Path(ok).stat().st_size > 0
    capsys.readouterr()
    long = "a" * (300 - len(ext)) + ext
    code, _, err = run([command, str(EXAMPLES / "seed000_fourbar.yaml"), *extra, "-o", long], capsys)
    assert code == 2 and "cannot write" in err and "internal error" not in err and len(err.splitlines()) == 1


def test_o_dev_stdout_and_a_directory(tmp_path: Path) -> None:
    """Review 18d: writing every ``-o`` in one step broke ``-o /dev/stdout`` into a pipe (the link's own target reads
    ``pipe:[...]``, no path: 'No such file or directory', exit 2), and ``-o .`` was an internal error. The first
    writes into the pipe, as before; the second is one line, exit 2."""
    args = ["analyze", str(EXAMPLES / "seed000_fourbar.yaml"), "--angles", "0:360:90", "--format", "csv"]
    piped = _script([*args, "-o", "/dev/stdout"], subprocess.PIPE)
    assert piped.returncode == 0 and piped.stdout.startswith("input:crank,") and len(piped.stdout.splitlines()) == 6
    here = _script([*args, "-o", "."], subprocess.PIPE)
    assert here.returncode == 2 and here.stderr == "linkagekit: error: -o .: cannot write: it is a directory\n"


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="no /proc on this machine")
def test_an_output_link_is_tried_where_it_points(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Review 18d: the directory tried before any work was the link's own, not its target's: a link here to
    ``/proc/x.png`` passed and failed only at the end. It is refused first, naming ``-o``."""
    (tmp_path / "out.png").symlink_to("/proc/x.png")
    code, _, err = run(["plot", str(EXAMPLES / "seed000_fourbar.yaml"), "-o", "out.png"], capsys)
    assert code == 2 and err.startswith("linkagekit: error: -o out.png: cannot write there: ")


def test_stray_temporaries_of_a_relative_path_are_listed_once(tmp_path: Path) -> None:
    """Review 18d: with a relative path each stray temporary was listed twice (once by the path, once by its real
    path); and the temporaries of two long names that start alike are told apart."""
    from linkagekit.files import _tmp_stem, stray_temporaries

    (tmp_path / ".m.yaml.0123456789ab.tmp").write_text("")
    assert [p.name for p in stray_temporaries("m.yaml")] == [".m.yaml.0123456789ab.tmp"]
    a, b = "a" * 230 + ".csv", "a" * 229 + "b.csv"
    (tmp_path / f".{_tmp_stem(b)}.0123456789ab.tmp").write_text("")
    assert stray_temporaries(a) == [] and len(stray_temporaries(b)) == 1


def test_a_file_we_may_not_write_is_refused_and_one_in_a_closed_directory_written_in_place(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Review 18d: in one step, a read-only table output (mode 444) was replaced where ``open`` refused it, and a
    writable one in a directory that takes no new file was refused where ``open`` wrote it: a table (``like_open``,
    as ``-o`` of analyze writes it) behaves as ``open`` again. Everything else is only ever written in one step
    (review 18e: the editor's save, written in place, skipped its check that nobody changed the file, and a Ctrl-C
    in a picture's render left it cut off): there the closed directory is refused and the old file stays. (As root
    every file is writable: what the system says is stood in for.)"""
    from linkagekit import files
    from linkagekit.errors import InputError

    out = tmp_path / "t.csv"
    out.write_text("OLD\n")
    real_access = os.access
    monkeypatch.setattr(files.os, "access", lambda p, m: False if Path(p) == out else real_access(p, m))
    with pytest.raises(InputError, match="cannot write: Permission denied"):
        files.write_atomic(out, b"NEW\n", like_open=True)
    assert out.read_text() == "OLD\n"
    monkeypatch.setattr(files.os, "access", real_access)

    def closed(tmp: Path, model: object) -> int:
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(files, "_create", closed)
    with pytest.raises(InputError, match="cannot write: Permission denied"):
        files.write_atomic(out, b"NEWER\n")  # in one step or not at all
    assert out.read_text() == "OLD\n"
    files.write_atomic(out, b"NEWER\n", like_open=True)
    assert out.read_text() == "NEWER\n" and sorted(p.name for p in tmp_path.iterdir()) == ["t.csv"]
    with pytest.raises(InputError, match="cannot write: Permission denied"):
        files.write_atomic(tmp_path / "new.csv", b"x", like_open=True)  # no file to write in place


def test_a_long_name_in_multibyte_characters_is_written(tmp_path: Path) -> None:
    """Review 18e: the temporary file's name was cut by characters, not bytes: a valid 248-byte name of 81 CJK
    characters could not be written ('File name too long')."""
    from linkagekit.files import _tmp_stem, write_atomic

    name = "\u6a5f" * 81 + ".yaml"
    assert len(name.encode()) == 248 and len(_tmp_stem(name).encode()) <= 200
    write_atomic(tmp_path / name, b"x")
    assert (tmp_path / name).read_bytes() == b"x" and len(list(tmp_path.iterdir())) == 1
