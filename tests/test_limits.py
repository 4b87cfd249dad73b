"""Limits that keep hostile or extreme input from hanging or exhausting the machine (issue 23, items 1-3).

* the numerical walk of a group goes at most ``group.WALK_TURNS`` turns of an angle driver
  from the pose's input: a sample farther away is not reached (NaN, not assembled), in a
  bounded CPU time, and a sample inside the reach is solved as before;
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
from linkagekit.group import WALK_REACH, WALK_TURNS

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
def test_walk_reach_is_ten_turns():
    assert WALK_TURNS == 10
    assert abs(WALK_REACH - 2 * math.pi * 10) <= 1e-12


@pytest.mark.parametrize("at", [1e11, -1e11, 1e5, 1e12])
def test_far_input_of_a_class3_group_is_not_reached_in_bounded_time(at):
    """Before: 1e11 deg was a MemoryError (745 GiB of walk samples) and 1e5 deg took minutes."""
    mech = lk.load(TRIAD)
    res, spent = cpu(lambda: lk.analyze(mech, np.array([at, -30.0])))
    assert res.assembled.tolist() == [False, True]
    assert np.all(np.isnan(res.x("J1")[:1])) and np.all(np.isfinite(res.x("J1")[1:]))
    assert spent < CPU_BUDGET


def test_far_input_through_the_command_line_is_flagged(capsys):
    from linkagekit.cli import main

    assert main(["analyze", str(TRIAD), "--at", "1e11", "--format", "json"]) == 0
    import json

    doc = json.loads(capsys.readouterr().out)
    assert doc["assembled"] == [False]


def test_walk_reach_boundary_numerical_fourbar():
    """A crank-rocker forced onto the numerical group: inside the reach it agrees with the closed form
    (1e-9 of its size) however many turns away; just outside, the sample is not reached."""
    mech = lk.load(FOURBAR)
    x0 = float(np.degrees(prepare(mech).pose_inputs[0, 0]))
    reach = math.degrees(WALK_REACH)
    inside = x0 + np.array([reach - 0.5, -reach + 0.5, 17.0, reach - 200.3])
    outside = x0 + np.array([reach + 0.5, -reach - 0.5, 1e11])
    x = np.concatenate([inside, outside])
    num, spent = cpu(lambda: lk.analyze(mech, x, method="numerical", rates=False))
    closed = lk.analyze(mech, x, rates=False)
    assert closed.assembled.all()
    assert num.assembled.tolist() == [True] * len(inside) + [False] * len(outside)
    size = max(abs(p) for p in mech.joints.values())
    for j in mech.joints:
        got = num.x(j)[: len(inside)] + 1j * num.y(j)[: len(inside)]
        want = closed.x(j)[: len(inside)] + 1j * closed.y(j)[: len(inside)]
        assert np.max(np.abs(got - want)) <= 1e-9 * size, j
    assert spent < CPU_BUDGET
