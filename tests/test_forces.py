"""Kinetostatics against independent computations.

* Power balance: the driver power equals the rate of change of kinetic energy minus the
  power of gravity and of the external loads, to 1e-9 relative, for random mechanisms of
  every kind (four-bar, Watt II, Stephenson, slider-cranks, slider driver, five-bar with two
  drivers, a compound hinge of three links, a slider driver on a turning arm) with random masses, centres of gravity,
  inertias, gravity and loads.  The centre-of-gravity motion here is computed from the two
  first joints of each link by a fixed complex ratio, not by the library's rotation.
* Equilibrium residual: every link, loaded with the reported reactions (each one acting on
  both of its links, with opposite signs), satisfies Newton-Euler to 1e-9.
* Whole-system balance: the shaking force and moment equal what the inertia, gravity and
  loads of all moving links leave for the frame.
* Static case by virtual work: at zero speed the driver torque is the derivative of the
  potential of gravity and loads, by finite differences of positions alone.
* Hand-worked cases: a driven pendulum (two links) and a slider-crank at 90 degrees.
* Seed 001's Stephenson six-bar: our corrected 15x15 values and its energy balance.
"""

import json
import zlib
from pathlib import Path

import numpy as np
import pytest

import linkagekit as lk
from helpers import points, pose_inputs, random_points, xy
from test_rates import KINDS as KINEMATIC_KINDS

RTOL = 1e-9


def compound_hinge(rng):
    """A four-bar with a dyad hung on its coupler-rocker joint D: three links meet at D."""
    p = random_points(rng, "ABECDF")
    return {
        "joints": xy(p),
        "links": {
            "ground": ["A", "B", "E"],
            "crank": ["A", "C"],
            "coupler": ["C", "D"],
            "rocker": ["B", "D"],
            "link5": ["D", "F"],
            "link6": ["E", "F"],
        },
        "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
    }


def slider_on_arm(rng):
    """A turning arm with a block pushed along it: one crank driver and one slider driver on a moving guide."""
    p = random_points(rng, "OAB")
    return {
        "joints": xy(p),
        "links": {"ground": ["O"], "arm": ["O", "A"], "block": ["B"]},
        "sliders": [{"link": "block", "on": "arm", "through": "B", "direction": list(rng.normal(size=2))}],
        "drivers": [{"link": "arm", "pivot": "O", "toward": "A"}, {"slider": 0}],
    }


KINDS = dict(KINEMATIC_KINDS, compound_hinge=compound_hinge, slider_on_arm=slider_on_arm)


def with_dynamics(d, rng, massless_share=0.25):
    """Random masses, centres of gravity, inertias, gravity and loads on a mechanism dict."""
    d = dict(d)
    joints = {k: complex(*v) for k, v in d["joints"].items()}
    links = {}
    for name, spec in d["links"].items():
        js = spec if isinstance(spec, list) else spec["joints"]
        if name == "ground" or rng.random() < massless_share:
            links[name] = spec
            continue
        centre = np.mean([joints[j] for j in js]) + complex(*rng.normal(0, 1, 2))
        links[name] = {
            "joints": js,
            "mass": float(rng.uniform(0.1, 3)),
            "cg": [centre.real, centre.imag],
            "inertia": float(rng.uniform(0, 0.5)),
        }
    d["links"] = links
    d["gravity"] = list(rng.normal(0, 5, 2))
    moving = [n for n in links if n != "ground"]
    loads = []
    for _ in range(2):
        name = moving[rng.integers(len(moving))]
        js = links[name] if isinstance(links[name], list) else links[name]["joints"]
        at = js[rng.integers(len(js))] if rng.random() < 0.5 else list(rng.uniform(-10, 10, 2))
        loads.append({"link": name, "at": at, "force": list(rng.normal(0, 20, 2)), "torque": float(rng.normal(0, 5))})
    d["loads"] = loads
    return d


# ----------------------------------------------------------------- independent kinematics
def point_of(res, link, local):
    """Position, velocity, acceleration (SI) of a shape-frame point of a link.

    Links with two or more joints: the point is the complex-ratio combination of two
    joints, so its velocity and acceleration are the same combination.  Single-joint
    blocks: the joint plus a rotating arm, with the link's reported omega and alpha.
    """
    mech = res.mechanism
    si = mech.length_to_si
    ln = mech.link(link)
    j0 = ln.joints[0]
    if len(ln.joints) >= 2:
        j1 = ln.joints[1]
        rho = (local - ln.shape[j0]) / (ln.shape[j1] - ln.shape[j0])
        return tuple((f(j0) + rho * (f(j1) - f(j0))) * si for f in (res.point, res.velocity, res.acceleration))
    sl = next(s for s in mech.sliders if s.link == link)
    rot = np.exp(1j * (res.link_angle[link] * mech.angle_to_rad - np.angle(sl.direction)))
    r = rot * (local - ln.shape[j0]) * si
    w, al = res.link_omega[link], res.link_alpha[link]
    return (
        res.point(j0) * si + r,
        res.velocity(j0) * si + 1j * w * r,
        res.acceleration(j0) * si + (1j * al - w * w) * r,
    )


def dot(a, b):
    return a.real * b.real + a.imag * b.imag


def cross(a, b):
    return a.real * b.imag - a.imag * b.real


def power_terms(res):
    """Every power term of the balance (W), as a list of arrays that must sum to zero."""
    mech = res.mechanism
    g = mech.gravity or 0j
    terms = []
    for ln in mech.links:
        if ln.name == "ground":
            continue
        w, al = res.link_omega[ln.name], res.link_alpha[ln.name]
        if ln.mass > 0:
            _, vg, ag = point_of(res, ln.name, ln.cg)
            terms += [-ln.mass * dot(ag, vg), ln.mass * dot(g + 0j, vg)]
        terms.append(-ln.inertia * al * w)
    for ld in mech.loads:
        if ld.link == "ground":
            continue
        if ld.force != 0:
            terms.append(dot(ld.force, point_of(res, ld.link, ld.at)[1]))
        terms.append(ld.torque * res.link_omega[ld.link])
    f = res.forces
    for d in mech.drivers:
        if d.kind == "angle":
            terms.append(f.driver_torque[d.name] * res.speeds[d.name])
        else:
            terms.append(f.driver_force[d.name] * res.speeds[d.name] * mech.length_to_si)
    return terms


def sweep_inputs(mech, rng, n=40):
    out = {}
    for d in mech.drivers:
        if d.kind == "angle":
            out[d.name] = rng.uniform(0, 360, n)
        else:
            out[d.name] = rng.uniform(-3, 3, n)
    return out


def random_case(kind, rng):
    for _ in range(100):  # a draw refused, or with too few samples that assemble, is drawn again (bounded)
        try:
            mech = lk.Mechanism.from_dict(with_dynamics(KINDS[kind](rng), rng))
        except lk.LinkageError:
            continue
        speed = {d.name: rng.uniform(-4, 4) for d in mech.drivers}
        acc = {d.name: rng.uniform(-4, 4) for d in mech.drivers}
        res = lk.analyze(mech, sweep_inputs(mech, rng), speed=speed, acceleration=acc)
        ok = res.assembled & ~res.singular
        if ok.sum() >= 5:
            return mech, res, ok
    pytest.fail(f"no {kind} was drawn valid in 100 tries")


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_driver_power_equals_energy_balance(kind):
    rng = np.random.default_rng(zlib.crc32(kind.encode()) + 7)
    for _ in range(6):
        mech, res, ok = random_case(kind, rng)
        terms = np.array(power_terms(res))[:, ok]
        total = terms.sum(axis=0)
        scale = np.abs(terms).sum(axis=0)
        assert np.all(np.abs(total) <= RTOL * scale), (kind, np.max(np.abs(total) / scale))
        np.testing.assert_allclose(res.forces.input_power[ok], terms[-len(mech.drivers) :].sum(axis=0), rtol=1e-12)


def guide_rotation(res, link):
    """e^{i theta}: how far a link has turned from the reference pose."""
    if link == "ground":
        return 1.0
    mech = res.mechanism
    ln = mech.link(link)
    return np.exp(
        1j * (res.link_angle[link] * mech.angle_to_rad - np.angle(ln.shape[ln.joints[1]] - ln.shape[ln.joints[0]]))
    )


def link_loads(res):
    """For each moving link: list of (force N complex, application point m, pure moment N*m)."""
    mech, f = res.mechanism, res.forces
    si = mech.length_to_si
    loads = {ln.name: [] for ln in mech.links if ln.name != "ground"}

    def add(link, force, at, moment=0.0):
        if link != "ground":
            loads[link].append((force, at, moment))

    for r in f.reactions:
        at = res.point(r.joint) * si
        m = r.moment if r.moment is not None else 0.0
        add(r.on, r.force, at, m)
        add(r.by, -r.force, at, -m if r.moment is not None else 0.0)
    for d in mech.drivers:
        if d.kind == "angle":
            add(d.link, 0j, 0j, f.driver_torque[d.name])
        else:
            sl = mech.sliders[d.slider]
            E = guide_rotation(res, sl.on) * sl.direction
            at = res.point(sl.through) * si
            add(sl.link, f.driver_force[d.name] * E, at)
            add(sl.on, -f.driver_force[d.name] * E, at)
    g = mech.gravity or 0j
    for ln in mech.links:
        if ln.name != "ground" and ln.mass > 0:
            add(ln.name, ln.mass * g, point_of(res, ln.name, ln.cg)[0])
    for ld in mech.loads:
        if ld.link != "ground":
            at = point_of(res, ld.link, ld.at)[0] if ld.at is not None else 0j
            add(ld.link, ld.force + 0j, at, ld.torque)
    return loads


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_link_is_in_equilibrium_under_the_reported_reactions(kind):
    rng = np.random.default_rng(zlib.crc32(kind.encode()) + 11)
    for _ in range(4):
        mech, res, ok = random_case(kind, rng)
        # floors: a massless unloaded chain carries ~0 N, computed to the rounding of the others
        floor_f = np.max([r.magnitude for r in res.forces.reactions], axis=0)
        floor_m = floor_f * np.max(np.abs(np.nan_to_num(points(res))), axis=0) * mech.length_to_si
        for link, items in link_loads(res).items():
            ln = mech.link(link)
            j0 = ln.joints[0]
            ref = point_of(res, link, ln.cg)[0] if ln.cg is not None else res.point(j0) * mech.length_to_si
            force = sum(fz for fz, _, _ in items)
            moment = sum(cross(at - ref, fz) + mm for fz, at, mm in items)
            scale_f = sum(np.abs(fz) for fz, _, _ in items) + 1e-12
            scale_m = sum(np.abs(at - ref) * np.abs(fz) + np.abs(mm) for fz, at, mm in items) + 1e-12
            m_a = ln.mass * point_of(res, link, ln.cg)[2] if ln.mass > 0 else 0j
            i_al = ln.inertia * res.link_alpha[link]
            scale_f = scale_f + np.abs(m_a) + floor_f
            scale_m = scale_m + np.abs(i_al) + floor_m
            assert np.all(np.abs(force - m_a)[ok] <= RTOL * scale_f[ok]), (kind, link)
            assert np.all(np.abs(moment - i_al)[ok] <= RTOL * scale_m[ok]), (kind, link)
        assert np.nanmax(res.forces.residual[ok]) < 1e-12


@pytest.mark.parametrize("kind", ["fourbar", "slider_crank", "compound_hinge", "fivebar", "inverted_slider_crank"])
def test_shaking_force_and_moment_balance_the_whole_mechanism(kind):
    rng = np.random.default_rng(zlib.crc32(kind.encode()) + 3)
    mech, res, ok = random_case(kind, rng)
    g = mech.gravity or 0j
    force = np.zeros(res.n, complex)
    moment = np.zeros(res.n)
    for ln in mech.links:
        if ln.name == "ground":
            continue
        if ln.mass > 0:
            zg, _, ag = point_of(res, ln.name, ln.cg)
            force += ln.mass * (g - ag)
            moment += cross(zg, ln.mass * (g - ag))
        moment -= ln.inertia * res.link_alpha[ln.name]
    for ld in mech.loads:
        if ld.link != "ground":
            force += ld.force
            moment += cross(point_of(res, ld.link, ld.at)[0], ld.force + 0j) + ld.torque
    f = res.forces
    scale = np.max(np.abs(force[ok])) + np.max(np.abs(f.shaking_force[ok]))
    assert np.max(np.abs(f.shaking_force - force)[ok]) <= RTOL * scale
    mscale = np.max(np.abs(moment[ok])) + np.max(np.abs(f.shaking_moment[ok]))
    assert np.max(np.abs(f.shaking_moment - moment)[ok]) <= RTOL * mscale


@pytest.mark.parametrize("kind", ["fourbar", "watt2", "stephenson", "slider_crank", "compound_hinge"])
def test_static_torque_is_the_derivative_of_the_potential(kind):
    """Virtual work: T = dU/dtheta with U = -sum m g.z_G - sum F.z_P - sum tau phi (positions only)."""
    rng = np.random.default_rng(zlib.crc32(kind.encode()) + 5)
    mech, _, _ = random_case(kind, rng)
    g = mech.gravity or 0j
    name = mech.drivers[0].name

    theta = np.degrees(pose_inputs(mech)[0, 0]) + rng.uniform(-20, 20, 30)  # near the pose: it assembles
    res = lk.analyze(mech, theta, speed=0.0, acceleration=0.0)
    h = 1e-3  # deg

    base = lk.analyze(mech, theta, speed=0.0, dynamics=False)

    def potential(offset):
        """U(theta + offset) - U(theta); link turns measured from theta (no unwrapping across samples)."""
        r = lk.analyze(mech, theta + offset, speed=0.0, dynamics=False)
        u = np.zeros(len(theta))
        for ln in mech.links:
            if ln.name != "ground" and ln.mass > 0:
                u -= ln.mass * dot(g + 0j, point_of(r, ln.name, ln.cg)[0] - point_of(base, ln.name, ln.cg)[0])
        for ld in mech.loads:
            if ld.link != "ground":
                u -= dot(ld.force + 0j, point_of(r, ld.link, ld.at)[0] - point_of(base, ld.link, ld.at)[0])
                turn = np.angle(np.exp(1j * (r.link_angle[ld.link] - base.link_angle[ld.link]) * mech.angle_to_rad))
                u -= ld.torque * turn
        return u

    u = {k: potential(k * h) for k in (-2, -1, 1, 2)}
    du = (-u[2] + 8 * u[1] - 8 * u[-1] + u[-2]) / (12 * np.radians(h))
    ok = res.assembled & ~res.singular & np.isfinite(du) & (np.abs(res.condition) > 0.05)
    assert ok.sum() >= 5
    t = res.forces.driver_torque[name]
    np.testing.assert_allclose(t[ok], du[ok], rtol=1e-6, atol=1e-6 * np.max(np.abs(du[ok])))


def test_two_link_pendulum_by_hand():
    """Crank OA of length L, mass m at L/2, inertia I_G, gravity -9.81 y: T = I_O alpha + m g (L/2) cos(theta)."""
    L, m, ig, g = 0.8, 2.5, 0.07, 9.81
    mech = lk.Mechanism.from_dict(
        {
            "units": {"length": "m", "angle": "deg"},
            "joints": {"O": [0, 0], "A": [L, 0]},
            "links": {"ground": ["O"], "arm": {"joints": ["O", "A"], "mass": m, "cg": [L / 2, 0], "inertia": ig}},
            "drivers": [{"link": "arm", "pivot": "O", "toward": "A"}],
            "gravity": [0, -g],
        }
    )
    th = np.linspace(0, 350, 36)
    w, al = 3.0, -1.5
    res = lk.analyze(mech, th, speed=w, acceleration=al)
    t = np.radians(th)
    torque = (ig + m * (L / 2) ** 2) * al + m * g * (L / 2) * np.cos(t)
    np.testing.assert_allclose(res.forces.driver_torque["arm"], torque, rtol=1e-12, atol=1e-12)
    a_g = (L / 2) * (1j * al - w * w) * np.exp(1j * t)
    bearing = m * a_g - m * (-1j * g)  # F = m a_G - m g: the ground holds the arm
    np.testing.assert_allclose(res.forces.reaction("O", "arm", "ground"), bearing, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.forces.reactions[0].magnitude, np.abs(bearing), rtol=1e-12)


def test_slider_crank_static_by_hand():
    """In-line slider-crank at 90 deg: dx_B/dtheta = -r, so holding a load F_x on the block takes T = F_x r."""
    mech = lk.load("examples/slider_crank.yaml")
    res = lk.analyze(mech, [90.0], speed=0.0, acceleration=0.0)
    # gravity does no virtual work here: A moves horizontally, B and the cg of the block too,
    # and the crank's cg moves horizontally as well at 90 deg
    assert res.forces.driver_torque["crank"][0] == pytest.approx(-50 * 0.05, rel=1e-12)


def test_seed001_stephenson_example():
    mech = lk.load("examples/seed001_stephenson.yaml")
    res = lk.analyze(mech, [50.0], speed=3.0, acceleration=-2.0)
    f = res.forces
    # our corrected 15x15 system (docs/seed-errata.md), F_ij = force by link i on link j
    expected = {
        ("OA", "input", "ground"): -100.226883 - 270.432258j,  # F12
        ("Q", "input", "link3"): -4.324012 + 153.462519j,  # F32
        ("S", "input", "link4"): 90.364256 + 102.530657j,  # F42
        ("X", "link3", "link6"): -34.426893 + 107.233839j,  # F63
        ("W", "link4", "output"): 57.507551 + 93.526780j,  # F54
        ("OB", "output", "ground"): -65.699995 + 124.332518j,  # F15
        ("Y", "link6", "output"): -85.432063 + 54.314349j,
    }  # F56
    for (joint, on, by), value in expected.items():
        assert f.reaction(joint, on, by)[0] == pytest.approx(value, abs=2e-6)
    assert f.driver_torque["input"][0] == pytest.approx(-336.755041, abs=1e-6)
    # its own energy balance over the whole default sweep (no gravity, no loads)
    res = lk.analyze(mech)
    assert res.assembled.all() and not res.singular.any()
    terms = np.array(power_terms(res))
    assert np.all(np.abs(terms.sum(axis=0)) <= RTOL * np.abs(terms).sum(axis=0))


def test_singular_position_gives_flagged_nan_forces():
    d = {
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"O1": [0, 0], "O2": [1000, 0], "A": [433.012701892219, 250], "B": [1433.01270189222, 250]},
        "links": {
            "ground": ["O1", "O2"],
            "crank": ["O1", "A"],
            "coupler": {"joints": ["A", "B"], "mass": 3.0, "cg": [933.0127, 250], "inertia": 0.2},
            "rocker": ["O2", "B"],
        },
        "drivers": [{"link": "crank", "pivot": "O1", "toward": "A"}],
        "gravity": [0, -9.81],
    }
    mech = lk.Mechanism.from_dict(d)
    res = lk.analyze(mech, [0.0, 30.0, 180.0], speed=5.0)
    assert res.singular.tolist() == [True, False, True]
    f = res.forces
    for r in f.reactions:
        assert np.isnan(r.force[[0, 2]]).all() and np.isfinite(r.force[1])
    assert np.isnan(f.driver_torque["crank"][[0, 2]]).all()
    out = res.to_dict()
    assert out["driver_torque"]["crank"][0] is None and out["reactions"][0]["fx"][2] is None


def test_no_mass_no_gravity_no_load_means_no_forces():
    mech = lk.load("examples/seed000_fourbar.yaml")
    res = lk.analyze(mech, [0.0, 10.0])
    assert res.forces is None
    out = res.to_dict()
    assert "reactions" not in out and "driver_torque" not in out


def test_force_output_in_json_csv_and_table(capsys):
    from linkagekit.cli import main

    assert main(["analyze", "examples/slider_crank.yaml", "--at", "0,90", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    pairs = {(r["joint"], r["on"], r["by"]) for r in out["reactions"]}
    assert pairs == {("O", "crank", "ground"), ("A", "rod", "crank"), ("B", "block", "rod"), ("B", "block", "ground")}
    assert set(out["driver_torque"]) == {"crank"} and len(out["driver_torque"]["crank"]) == 2
    assert set(out["shaking_force"]) == {"fx", "fy"} and len(out["input_power"]) == 2
    slider = next(r for r in out["reactions"] if r["by"] == "ground" and r["on"] == "block")
    assert slider["kind"] == "slider" and slider["fx"] == pytest.approx([0.0, 0.0], abs=1e-12)  # frictionless
    assert main(["analyze", "examples/slider_crank.yaml", "--at", "0,90", "--format", "csv"]) == 0
    header = capsys.readouterr().out.splitlines()[0].split(",")
    assert "T[crank]" in header and "F[O:ground>crank].fx" in header and "F[B:ground>block].moment" in header
    assert main(["analyze", "examples/slider_crank.yaml", "--at", "0,90"]) == 0
    table = capsys.readouterr().out
    assert "T[crank]" in table and "N" in table


def test_static_option(capsys):
    from linkagekit.cli import main

    assert main(["analyze", "examples/slider_crank.yaml", "--at", "90", "--static", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["driver_torque"]["crank"][0] == pytest.approx(-2.5, rel=1e-12)
    assert out["speeds"]["crank"] == [0.0]
    mech = lk.load("examples/slider_crank.yaml")
    assert lk.analyze(mech, [90.0], static=True).forces.driver_torque["crank"][0] == pytest.approx(-2.5, rel=1e-12)
    with pytest.raises(lk.InputError, match="static"):
        lk.analyze(mech, [90.0], static=True, speed=3.0)


def test_two_drivers_and_a_slider_driver_report_their_efforts():
    rng = np.random.default_rng(5)
    mech, res, ok = random_case("fivebar", rng)
    assert set(res.forces.driver_torque) == {d.name for d in mech.drivers}
    mech, res, ok = random_case("slider_driven", rng)
    assert set(res.forces.driver_force) == {mech.drivers[0].name} and res.forces.driver_torque == {}
    assert "driver_force" in res.to_dict()


def test_forces_do_not_depend_on_the_length_unit():
    """The same slider-crank written in m and in mm: forces in N and torques in N*m agree."""
    import yaml

    from linkagekit.files import _Loader  # YAML 1.2 booleans: `on:` is a key, not True

    text = Path("examples/slider_crank.yaml").read_text()
    d = yaml.load(text, Loader=_Loader)
    mm = yaml.load(text, Loader=_Loader)
    mm["units"]["length"] = "mm"
    mm["joints"] = {k: [1000 * c for c in v] for k, v in d["joints"].items()}
    for ln in mm["links"].values():
        if isinstance(ln, dict):
            ln["lengths"] = {k: 1000 * v for k, v in ln.get("lengths", {}).items()}
            if "cg" in ln:
                ln["cg"] = [1000 * c for c in ln["cg"]]
    th = np.linspace(0, 350, 36)
    a = lk.analyze(lk.Mechanism.from_dict(d), th, speed=7.0, acceleration=-3.0).forces
    b = lk.analyze(lk.Mechanism.from_dict(mm), th, speed=7.0, acceleration=-3.0).forces
    np.testing.assert_allclose(b.driver_torque["crank"], a.driver_torque["crank"], rtol=1e-9, atol=1e-12)
    for ra, rb in zip(a.reactions, b.reactions, strict=True):
        np.testing.assert_allclose(rb.force, ra.force, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(b.shaking_moment, a.shaking_moment, rtol=1e-9, atol=1e-9)


def test_reaction_lookup_names_the_ambiguity():
    res = lk.analyze(lk.load("examples/slider_crank.yaml"), [30.0])
    f = res.forces
    np.testing.assert_allclose(f.reaction("B", "rod"), -f.reaction("B", "block", "rod"))
    with pytest.raises(KeyError, match="several reactions at 'B' on 'block'"):
        f.reaction("B", "block")
