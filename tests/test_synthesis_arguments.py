"""The Python API's search arguments are checked once, at the boundary, against the limits the command line uses.

A NaN time budget used to remove the limit, a negative one or a negative goal was taken,
``lengths=(5, 1)`` gave an infeasible run and ``restarts=0`` raised a bare IndexError (found by
a new-user review).  Each is now an :class:`~linkagekit.errors.InputError` naming the argument,
raised before any search; the runs that would otherwise start are kept tiny.
"""

from __future__ import annotations

import numpy as np
import pytest

import linkagekit as lk
from linkagekit.errors import InputError, LinkageError
from linkagekit.synthesis.auto import synthesize_auto
from linkagekit.synthesis.optimize import LIMITS

ARC = np.array([[0, 0], [1, 0.5], [2, 0.8], [3, 0.9], [4, 0.8], [5, 0.5], [6, 0]], float)
TINY = {"restarts": 1, "generations": 2, "workers": 1}
NAN = float("nan")


@pytest.fixture(autouse=True)
def no_atlas(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LINKAGEKIT_ATLAS_SIZE", "0")  # the path runs that should not start stay short


@pytest.mark.parametrize(
    "bad",
    [
        {"seconds": NAN},
        {"seconds": -1.0},
        {"seconds": 0.0},
        {"goal": -1.0},
        {"goal": NAN},
        {"restarts": 0},
        {"generations": 2.5},
        {"workers": 0},
        {"lengths": (5.0, 1.0)},
        {"lengths": (1.0, NAN)},
    ],
)
def test_path_arguments_out_of_range_are_input_errors_naming_them(bad):
    name = next(iter(bad))
    with pytest.raises(InputError, match=rf"^{name}: expected "):
        lk.synthesize(ARC, "fourbar", **{**TINY, **bad})


@pytest.mark.parametrize("bad", [{"seconds": NAN}, {"restarts": 0}, {"workers": 0}])
def test_function_arguments_are_checked_even_when_three_pairs_need_no_search(bad):
    name = next(iter(bad))
    with pytest.raises(InputError, match=rf"^{name}: expected "):
        lk.synthesize([[30, 75], [75, 90], [135, 135]], task="function", **bad)


def test_motion_time_is_checked_even_on_the_exact_route():
    poses = [[0, 0, 0], [1, 0.2, 10], [2, 0.1, 25], [3, -0.3, 35]]  # four poses: Burmester, no engine
    with pytest.raises(InputError, match=r"^seconds: expected a positive time"):
        lk.synthesize(poses, task="motion", seconds=NAN)


@pytest.mark.parametrize("bad", [{"seconds": NAN}, {"restarts": 0}, {"goal": -1.0}])
def test_auto_arguments_are_checked_before_the_screening(bad):
    name = next(iter(bad))
    with pytest.raises(InputError, match=rf"^{name}: expected "):
        synthesize_auto(ARC, max_joints=5, **bad)


def test_the_command_line_refuses_by_the_same_limits(tmp_path, capsys):
    from linkagekit.cli import main

    csv = tmp_path / "arc.csv"
    csv.write_text("x,y\n" + "".join(f"{x},{y}\n" for x, y in ARC))
    over = int(LIMITS["restarts"].high) + 1
    assert main(["synthesize", str(csv), "-o", str(tmp_path / "o.yaml"), "--restarts", str(over)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--restarts: expected 1 to {over - 1}, got {over}" in err
    assert issubclass(InputError, LinkageError)


def test_a_file_name_is_read_as_targets_in_the_units_given(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """``lk.synthesize("targets.csv")``, what the command line takes, raised a ValueError from NumPy: a file name
    (str or path) is now read by ``read_targets`` in ``units`` (the search itself is not run here)."""
    import pathlib

    from linkagekit.synthesis import run

    csv = tmp_path / "arc.csv"
    csv.write_text("x,y\n" + "\n".join(f"{x},{y}" for x, y in ARC))
    seen: list = []
    monkeypatch.setattr(run, "synthesize_path", lambda targets, topology, **kw: seen.append((targets, kw)))
    lk.synthesize(str(csv), "fourbar", units="mm")
    lk.synthesize(pathlib.Path(csv), "fourbar")
    (a, kw_a), (b, kw_b) = seen
    assert a.unit == "mm" and kw_a["units"] == "mm" and b.unit == "m" and a.source == str(csv)
    assert np.array_equal(a.xy, ARC) and np.array_equal(b.xy, ARC)


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda: lk.synthesize({"x": [0, 1]}, "fourbar"), "targets: expected an array of numbers, got dict"),
        (lambda: lk.synthesize(ARC, 4), "topology: expected a name"),
        (lambda: lk.synthesize(ARC, "fourbar", units="km"), "units: expected one of 'mm', 'cm', 'm', 'in', got 'km'"),
        (lambda: lk.synthesize("poses.csv", task="motion"), "read it first"),
    ],
)
def test_targets_topology_and_units_that_are_no_such_thing_are_one_line(call, words) -> None:  # type: ignore[no-untyped-def]
    """They were a TypeError, an AttributeError ('int' object has no attribute 'joint_names') and 'fourbar:
    units.length: ...' (naming no argument)."""
    with pytest.raises(InputError, match=words.replace("(", r"\(").replace(")", r"\)")):
        call()


def test_a_unit_that_contradicts_the_targets_own_is_refused(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Targets read in metres (the default) and ``units="mm"`` given to synthesize: the design was written in metres
    without a word."""
    csv = tmp_path / "arc.csv"
    csv.write_text("x,y\n" + "\n".join(f"{x},{y}" for x, y in ARC))
    T = lk.read_targets(csv)
    with pytest.raises(InputError, match=r"units='mm': the targets were read in 'm'"):
        lk.synthesize(T, "fourbar", units="mm", **TINY)
    from linkagekit.synthesis.run import _targets_given

    assert _targets_given(T, "path", {"units": "m"}) is T and _targets_given(T, "path", {}) is T


@pytest.mark.parametrize("topology", ["hexbar", "no/such/template.yaml"])
def test_an_unknown_topology_in_python_names_the_argument(topology):
    """``lk.synthesize(T, "hexbar")`` (or a template's file name) said '--topology: unknown topology ...': a Python
    caller gave the argument ``topology``, and a template is passed as a Mechanism, which the message says."""
    with pytest.raises(InputError) as info:
        lk.synthesize(ARC, topology, seconds=1, **TINY)
    message = str(info.value)
    assert message.startswith(f"topology: unknown topology '{topology}'"), message
    assert "fourbar" in message and "lk.load(FILE)" in message and "\n" not in message


def test_the_former_unit_keyword_is_checked_as_units_is(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """A review: ``unit="cm"`` (the deprecated name) skipped the contradiction check and read a file in metres."""
    from linkagekit.synthesis.run import _targets_given

    csv = tmp_path / "arc.csv"
    csv.write_text("x,y\n" + "\n".join(f"{x},{y}" for x, y in ARC))
    assert _targets_given(str(csv), "path", {"unit": "cm"}).unit == "cm"
    with pytest.raises(InputError, match=r"unit='cm': the targets were read in 'm'"):
        _targets_given(lk.read_targets(csv), "path", {"unit": "cm"})
    with pytest.raises(InputError, match=r"'auto' is a search of its own: linkagekit.synthesis.auto.synthesize_auto"):
        lk.synthesize(ARC, "auto")
