"""The vector-loop method (seeds 003 and 001) against the main natural-coordinate solver.

The two share no code: the main solver triangulates joint coordinates and differentiates
each step; the vector-loop method iterates on link angles (fixed point, Newton-Raphson)
and solves the seeds' velocity and acceleration systems.  Over full sweeps, in every
assembly mode, positions, velocities, accelerations and link rates must agree to 1e-9
relative to the largest value of each quantity over the sweep.
"""

import dataclasses
import itertools
import json

import numpy as np
import pytest

import linkagekit as lk
from helpers import accelerations, fourbar_dict, points, random_points, stephenson_dict, velocities, watt2_dict
from linkagekit.positions import all_sign_combinations
from linkagekit.vectorloop import FourBar, Stephenson, from_mechanism

RTOL = 1e-9
SWEEP = np.arange(0.0, 360.0, 0.5)


def relative_error(x, y, assembled):
    x, y = np.asarray(x)[..., assembled], np.asarray(y)[..., assembled]
    scale = max(np.nanmax(np.abs(x), initial=0.0), 1e-12)
    return np.nanmax(np.abs(x - y), initial=0.0) / scale


def compare(mech, signs, model, w, al):
    """Main solver in mode `signs` against the vector-loop `model`; returns the worst relative error."""
    res = lk.analyze(mech, SWEEP, speed=w, acceleration=al, signs=signs)
    _, offset = from_mechanism(mech)
    sol = model.solve(np.radians(SWEEP) + offset, w, al)
    ok = res.assembled
    if ok.sum() < 10:
        return None
    if not np.array_equal(res.assembled, sol.assembled):
        return np.inf  # another mode: where the second loop closes depends on the first's branch
    # NaN must sit at the same samples (singular ones), everything else must agree
    assert np.array_equal(res.singular, sol.singular)
    worst = 0.0
    for j in mech.joint_names:
        worst = max(
            worst,
            relative_error(res.point(j), sol.z[j], ok),
            relative_error(res.velocity(j), sol.v[j], ok),
            relative_error(res.acceleration(j), sol.a[j], ok),
        )
    for link in sol.omega:
        worst = max(
            worst,
            relative_error(res.link_omega[link], sol.omega[link], ok),
            relative_error(res.link_alpha[link], sol.alpha[link], ok),
        )
    return worst


def matched_branches(mech, model, branch_field, n_branches, w, al):
    """For every mode of the main solver, exactly one vector-loop branch choice must match it."""
    matched = 0
    for col in all_sign_combinations(len(lk.reference_signs(mech))).T:
        errors = []
        for br in itertools.product((1.0, -1.0), repeat=n_branches):
            value = br[0] if n_branches == 1 else br
            err = compare(mech, col, dataclasses.replace(model, **{branch_field: value}), w, al)
            errors.append(err)
        if all(e is None for e in errors):
            continue
        found = sorted(e for e in errors if e is not None)
        assert found[0] < RTOL and (len(found) == 1 or found[1] > 1e-3), errors  # one branch, and only one
        matched += 1
    return matched


def test_fourbars_agree_over_full_sweeps():
    rng = np.random.default_rng(3)
    done = 0
    while done < 15:
        mech = lk.Mechanism.from_dict(fourbar_dict(*random_points(rng, "ABCDP").values()))
        model, _ = from_mechanism(mech)
        assert isinstance(model, FourBar)
        if matched_branches(mech, model, "branch", 1, rng.uniform(-5, 5), rng.uniform(-5, 5)):
            done += 1


@pytest.mark.long  # 7.5 s: the suite's five minutes (the other six-bar and four-bar agreements stay in it)
def test_stephenson_sixbars_agree_over_full_sweeps():
    rng = np.random.default_rng(1)
    done = 0
    while done < 6:
        try:
            mech = lk.Mechanism.from_dict(stephenson_dict(random_points(rng, "ABCDEFGP")))
        except lk.LinkageError:
            continue
        model, _ = from_mechanism(mech)
        assert isinstance(model, Stephenson)
        if matched_branches(mech, model, "branches", 2, rng.uniform(-5, 5), rng.uniform(-5, 5)) >= 2:
            done += 1


@pytest.mark.parametrize("example", ["seed000_fourbar", "seed003_ex21", "seed004_stephenson1"])
def test_vector_loop_method_through_analyze(example):
    mech = lk.load(f"examples/{example}.yaml")
    a = lk.analyze(mech, speed=2.0, acceleration=-1.5)
    b = lk.analyze(mech, speed=2.0, acceleration=-1.5, method="vector-loop")
    assert np.array_equal(a.assembled, b.assembled)
    ok = a.assembled
    assert relative_error(points(a), points(b), ok) < RTOL
    assert relative_error(velocities(a), velocities(b), ok) < RTOL
    assert relative_error(accelerations(a), accelerations(b), ok) < RTOL
    for ln in mech.links:
        assert relative_error(a.link_angle[ln.name], b.link_angle[ln.name], ok) < RTOL


def test_vector_loop_method_from_the_command_line(capsys):
    from linkagekit.cli import main

    out = {}
    for method in ("natural", "vector-loop"):
        code = main(
            [
                "analyze",
                "examples/seed004_stephenson1.yaml",
                "--angles",
                "0:360:15",
                "--format",
                "json",
                "--method",
                method,
            ]
        )
        assert code == 0
        out[method] = json.loads(capsys.readouterr().out)
    for j, d in out["natural"]["joints"].items():
        for key in ("x", "y", "vx", "vy", "ax", "ay"):
            np.testing.assert_allclose(out["vector-loop"]["joints"][j][key], d[key], rtol=1e-9, atol=1e-9)


def test_other_topologies_are_refused_with_a_reason():
    rng = np.random.default_rng(0)
    mech = lk.Mechanism.from_dict(watt2_dict(random_points(rng, "ABECDFGP")))
    with pytest.raises(lk.NotSolvableError, match="vector-loop method handles only four-bars and Stephenson") as e:
        lk.analyze(mech, [0.0], method="vector-loop")
    # the reason first (after a long name, the line's 300 characters ended before it: review 19c)
    assert str(e.value).startswith("the ground must have exactly two pivots: ")
    with pytest.raises(lk.InputError, match="method: expected"):
        lk.analyze(mech, [0.0], method="loop")


# ----------------------------------------------------------------------------- seed 003, section 3-4
# Values to 6 decimals, derived again from the loop equations (docs/seed-errata.md); the
# printed tables round them to 2 (velocities) and 1 (accelerations) decimals.
EX31 = {  # theta2 = 120 deg, omega2 = 5 rad/s, alpha2 = 0; velocities in m/s, accelerations in m/s^2
    "omega": {"coupler": 10.097332, "rocker": 2.994888},
    "alpha": {"coupler": 5.312811, "rocker": 30.459449},
    "v": {"A": (-3.031089, -1.750000), "B": (-1.303000, 0.737923), "P": (-2.862684, 0.262432)},
    "a": {"A": (8.750000, -15.155445), "B": (-15.462131, 3.602688), "P": (-11.481591, -12.396142)},
}
PRINTED31 = {
    "omega": {"coupler": 10.10, "rocker": 2.99},
    "alpha": {"coupler": 5.31, "rocker": 30.46},
    "v": {"A": (-3.03, -1.75), "B": (-1.30, 0.74), "P": (-2.86, 0.26)},
    "a": {"A": (8.8, -15.2), "B": (-15.5, 3.6), "P": (-11.5, -12.4)},
}
EX32 = {  # theta2 = 60 deg on the parallelogram branch: the coupler translates
    "omega": {"coupler": 0.0, "rocker": 5.0},
    "alpha": {"coupler": 0.0, "rocker": 0.0},
    "v": {k: (-2.165064, 1.25) for k in "ABP"},
    "a": {k: (-6.25, -10.825318) for k in "ABP"},
}
PRINTED32 = {
    "omega": {"coupler": 0.00, "rocker": 5.00},
    "alpha": {"coupler": 0.00, "rocker": 0.00},
    "v": {k: (-2.17, 1.25) for k in "ABP"},
    "a": {k: (-6.3, -10.8) for k in "ABP"},
}


@pytest.mark.parametrize("method", ["natural", "vector-loop"])
@pytest.mark.parametrize(
    ("example", "theta2", "exact", "printed"),
    [
        ("seed003_ex21", 120.0, EX31, PRINTED31),
        ("seed003_ex22", 60.0, EX32, PRINTED32),
    ],
)
def test_seed003_examples_3_and_4(method, example, theta2, exact, printed):
    mech = lk.load(f"examples/{example}.yaml")  # lengths in mm
    res = lk.analyze(mech, [theta2], speed=5.0, acceleration=0.0, method=method)
    mm_to_m = mech.length_to_si
    assert mm_to_m == pytest.approx(1e-3)
    for link in ("coupler", "rocker"):
        for key, arr in (("omega", res.link_omega), ("alpha", res.link_alpha)):
            assert arr[link][0] == pytest.approx(exact[key][link], abs=1e-6)
            assert round(arr[link][0], 2) == pytest.approx(printed[key][link], abs=1e-12)
    for joint in "ABP":
        for key, get, digits in (("v", res.velocity, 2), ("a", res.acceleration, 1)):
            value = get(joint)[0] * mm_to_m
            assert value.real == pytest.approx(exact[key][joint][0], abs=1e-6)
            assert value.imag == pytest.approx(exact[key][joint][1], abs=1e-6)
            # the printed tables round half away from zero (-6.25 is printed -6.3)
            exact_9 = (round(value.real, 9), round(value.imag, 9))  # 8.7499999999996 is 8.75
            half_up = [float(np.sign(c) * np.floor(abs(c) * 10**digits + 0.5) / 10**digits) for c in exact_9]
            assert half_up == pytest.approx(list(printed[key][joint]), abs=1e-12)
