"""An actuator written as a barrel, a rod and a slider driver equals the same actuator written as a `cylinder:`.

The slider form (issue 29, item 3): the barrel is pinned to one body and carries the slide's
line, the rod is pinned to the other and slides in the barrel without turning in it, and a
slider driver pushes the rod (its input: the displacement from the pose, so the cylinder's
length is the pose's length plus it).  Every position, rate, reaction and driver force must
equal the `cylinder:` form's to 1e-12 of the size or force scale, over the whole stroke, and
beyond the stroke both must be flagged.  The driver force is also checked by virtual work
(power balance), which does not use the force solve.
"""

from __future__ import annotations

import numpy as np
import pytest

import linkagekit as lk
from linkagekit.checks import input_range
from linkagekit.errors import LinkageError
from linkagekit.plan import make_plan

TOL = 1e-12  # of the mechanism's size, of the force scale


def as_slider(
    mech: lk.Mechanism, head: float = 0.4, flip: bool = False
) -> tuple[lk.Mechanism, dict[str, tuple[str, float, str, str]]]:
    """The mechanism with every cylinder [A, B] written as a barrel [A, head point], a rod [B] and a slider driver.

    ``flip``: the barrel on B and the rod on A instead.

    Returns the slider form and, per cylinder name, (its slider driver's name, the pose's length, the barrel, the link
    pinned at the cylinder's second end).
    """
    d = mech.to_dict()
    sliders, drivers, names = list(d.get("sliders", [])), [], {}
    for entry, drv in zip(d["drivers"], mech.drivers, strict=True):
        if "cylinder" not in entry:
            drivers.append(entry)
            continue
        a, b = entry["cylinder"][::-1] if flip else entry["cylinder"]
        za, zb = mech.joints[a], mech.joints[b]
        s0 = abs(zb - za)
        hd = za + head * (zb - za)
        d["joints"][f"{drv.name}_head"] = [hd.real, hd.imag]
        d["links"][f"{drv.name}_barrel"] = [a, f"{drv.name}_head"]
        d["links"][f"{drv.name}_rod"] = [b]
        sliders.append({"link": f"{drv.name}_rod", "on": f"{drv.name}_barrel", "through": b,
                        "direction": [(zb - za).real, (zb - za).imag]})  # fmt: skip
        lo, hi = entry["stroke"]
        sw = entry["lengths"]
        new = {"slider": len(sliders) - 1, "stroke": [lo - s0, hi - s0], "speed": drv.speed}
        new["displacements"] = {"start": sw["start"] - s0, "stop": sw["stop"] - s0, "step": sw["step"]}
        drivers.append(new)
        names[drv.name] = (
            f"{drv.name}_rod",
            s0,
            f"{drv.name}_barrel",
            f"{drv.name}_barrel" if flip else f"{drv.name}_rod",
        )
    d["sliders"], d["drivers"] = sliders, drivers
    return lk.Mechanism.from_dict(d), names


def both(
    cyl: lk.Mechanism, sl: lk.Mechanism, names: dict[str, tuple[str, float, str, str]], lengths: dict[str, np.ndarray]
):
    """Both forms analysed at the same cylinder lengths, with speeds and accelerations."""
    rng = np.random.default_rng(29)
    n = len(next(iter(lengths.values())))
    speed = {k: rng.uniform(-0.2, 0.2, n) for k in lengths}
    accel = {k: rng.uniform(-0.1, 0.1, n) for k in lengths}
    rc = lk.analyze(cyl, lengths, speed=speed, acceleration=accel)
    inputs = {names[k][0]: v - names[k][1] for k, v in lengths.items()}
    rs = lk.analyze(
        sl,
        inputs,
        speed={names[k][0]: v for k, v in speed.items()},
        acceleration={names[k][0]: v for k, v in accel.items()},
    )
    return rc, rs


def assert_same(cyl: lk.Mechanism, names: dict[str, tuple[str, float, str, str]], rc, rs, inside: np.ndarray) -> None:
    """Equal flags (assembled exactly inside the stroke) and equal numbers to TOL of the size and force scale."""
    assert inside.any() and (~inside).any()
    np.testing.assert_array_equal(rc.assembled, inside)
    np.testing.assert_array_equal(rs.assembled, inside)
    assert not rs.singular.any()
    size = cyl.length_scale
    for j in cyl.joint_names:
        for get in (rc.point, rc.velocity, rc.acceleration):
            a, b = get(j), getattr(rs, get.__name__)(j)
            assert np.isnan(b[~inside]).all()
            assert np.max(np.abs(a[inside] - b[inside])) <= TOL * size, (j, get.__name__)
    for ln in cyl.links:
        for what in ("angle", "omega", "alpha"):
            a, b = getattr(rc, what)(ln.name)[inside], getattr(rs, what)(ln.name)[inside]
            scale = 360.0 if what == "angle" else max(1.0, np.max(np.abs(a)))
            assert np.max(np.abs(a - b)) <= TOL * scale, (ln.name, what)
    fc, fs = rc.forces, rs.forces
    scale = max(np.max(np.abs(f[inside])) for f in fc.driver_force.values())
    for cname, (rod, *_) in names.items():
        a, b = fc.driver_force[cname], fs.driver_force[rod]
        assert np.isnan(b[~inside]).all()
        assert np.max(np.abs(a[inside] - b[inside])) <= TOL * scale, cname
    for r in fc.reactions:  # the reactions both forms have
        b = fs.reaction(r.joint, r.on, r.by)
        assert np.max(np.abs(r.force[inside] - b[inside])) <= TOL * scale, r.joint
    np.testing.assert_allclose(fs.input_power[inside], fc.input_power[inside], rtol=0, atol=TOL * scale)
    # what the frame feels: the cylinder's end on the frame is the barrel's (or rod's) pin reaction there
    assert np.max(np.abs(fs.shaking_force[inside] - fc.shaking_force[inside])) <= TOL * scale
    assert np.max(np.abs(fs.shaking_moment[inside] - fc.shaking_moment[inside])) <= TOL * scale * size
    for cname, (rod, _, barrel, at_b) in names.items():  # the actuator pushes as the cylinder: F along A -> B at B
        a, b = next(d.type.ends for d in cyl.drivers if d.name == cname)
        body = next(ln.name for ln in cyl.links if b in ln.joints)
        line = (rc.point(b) - rc.point(a))[inside]
        push = fs.reaction(b, body, at_b)[inside]
        assert np.max(np.abs(push - fc.driver_force[cname][inside] * line / np.abs(line))) <= TOL * scale
        # the barrel and the rod turn as the line between the cylinder's ends (links of the slider form only)
        dv, da = (rc.velocity(b) - rc.velocity(a))[inside], (rc.acceleration(b) - rc.acceleration(a))[inside]
        w_line = np.imag(dv / line)  # d/dt arg(line)
        al_line = np.imag(da / line - (dv / line) ** 2)
        for part in (barrel, rod):
            th = np.deg2rad(rs.angle(part)[inside])
            assert np.max(np.abs(np.imag(np.exp(1j * th) * np.conj(line)) / np.abs(line))) <= TOL  # along the line
            assert np.max(np.abs(rs.omega(part)[inside] - w_line)) <= TOL * max(1.0, np.max(np.abs(w_line)))
            assert np.max(np.abs(rs.alpha(part)[inside] - al_line)) <= TOL * max(1.0, np.max(np.abs(al_line)))


def test_excavator_boom_cylinders_as_sliders():
    """examples/excavator_boom.yaml: both cylinders (boom and stick) as sliders, over and beyond their strokes."""
    cyl = lk.load("examples/excavator_boom.yaml")
    sl, names = as_slider(cyl)
    n = 121
    boom = np.linspace(1.75, 2.95, n)  # stroke [1.8, 2.9]
    stick = np.linspace(3.45, 2.45, n)  # stroke [2.5, 3.4], the other way
    boom[10], stick[60] = 1.8, 3.4  # the ends of the strokes are inside
    e = 1e-12  # the stroke's ends are inclusive to 1e-12 relative
    inside = (boom >= 1.8 * (1 - e)) & (boom <= 2.9 * (1 + e)) & (stick >= 2.5 * (1 - e)) & (stick <= 3.4 * (1 + e))
    rc, rs = both(cyl, sl, names, {"boom_cylinder": boom, "stick_cylinder": stick})
    assert_same(cyl, names, rc, rs, inside)


def test_bucket_linkage_example_files():
    """examples/excavator_bucket.yaml and its slider form excavator_bucket_slider.yaml, whole stroke and beyond."""
    cyl = lk.load("examples/excavator_bucket.yaml")
    sl = lk.load("examples/excavator_bucket_slider.yaml")
    names = {"bucket_cylinder": ("bucket_rod", 2.5, "bucket_barrel", "bucket_rod")}
    s0 = abs(cyl.joints["G"] - cyl.joints["K"])
    assert abs(s0 - 2.5) <= 1e-15  # the file's stroke [-0.35, 0.4] is the cylinder's [2.15, 2.9]
    assert sl.drivers[0].stroke == (-0.35, 0.4) and cyl.drivers[0].stroke == (2.15, 2.9)
    lengths = np.concatenate([np.linspace(2.1, 2.95, 86), [2.15, 2.9]])
    inside = (lengths >= 2.15 - 1e-12) & (lengths <= 2.9 + 1e-12)
    rc, rs = both(cyl, sl, names, {"bucket_cylinder": lengths})
    assert_same(cyl, names, rc, rs, inside)
    # the barrel on the moving joint G and the rod on the frame's K: the rod's pin is the known one
    sl2, names2 = as_slider(cyl, head=0.7, flip=True)
    assert "2. G = circle(F) x circle(K, actuator length of slider 0" in make_plan(sl2).describe()
    rc, rs2 = both(cyl, sl2, names2, {"bucket_cylinder": lengths})
    assert_same(cyl, names2, rc, rs2, inside)
    # the assembly range: the stroke, both ways (each end exact to 1e-9)
    (lo, hi), (ulo, uhi) = input_range(cyl)[0], input_range(sl)[0]
    assert len(input_range(sl)) == 1 and abs(lo - 2.15) <= 1e-9 and abs(hi - 2.9) <= 1e-9
    assert abs(ulo + 0.35) <= 1e-9 and abs(uhi - 0.4) <= 1e-9

    # a batch of poses (the file's and one moved by (1, 2) m): each design as the cylinder form's
    def poses(mech):
        pose = np.array([[mech.joints[j].real, mech.joints[j].imag] for j in mech.joint_names])
        return np.stack([pose, pose + [1.0, 2.0]])

    ba = lk.analyze(sl, {"bucket_rod": lengths - 2.5}, poses=poses(sl))
    bc = lk.analyze(cyl, {"bucket_cylinder": lengths}, poses=poses(cyl))
    np.testing.assert_array_equal(ba.assembled, np.stack([inside, inside]))
    np.testing.assert_array_equal(bc.assembled, ba.assembled)
    assert np.nanmax(np.abs(ba.point("P") - bc.point("P"))) <= TOL * cyl.length_scale
    dfa, dfc = ba.forces.driver_force["bucket_rod"], bc.forces.driver_force["bucket_cylinder"]
    assert np.nanmax(np.abs(dfa - dfc)) <= TOL * np.nanmax(np.abs(dfc))
    # the file's default sweeps: the whole stroke, the same samples
    da, db = lk.analyze(cyl), lk.analyze(sl)
    assert da.assembled.all() and db.assembled.all() and da.n == db.n == 101
    assert np.max(np.abs(da.forces.driver_force["bucket_cylinder"] - db.forces.driver_force["bucket_rod"])) <= 1e-6


@pytest.mark.parametrize("variant", ["file", "heavy", "heavy offset"])
def test_driver_force_by_virtual_work(variant):
    """Slider form: F du/dt = d(kinetic energy)/dt - power of gravity and loads, from the kinematics alone.

    Also with a barrel and a rod of their own mass and inertia, and with the slide's line off the pins.
    """
    d = lk.load("examples/excavator_bucket_slider.yaml").to_dict()
    if "heavy" in variant:
        d["links"]["bucket_barrel"] = {"joints": ["K", "KH"], "mass": 60.0, "cg": [1.2, 0.95], "inertia": 20.0}
        d["links"]["bucket_rod"] = {"joints": ["G", "GR"], "mass": 30.0, "cg": [2.1, 0.72], "inertia": 3.0}
    if "offset" in variant:
        d["sliders"][0]["direction"] = [np.cos(np.radians(-12.0)), np.sin(np.radians(-12.0))]
    mech = lk.Mechanism.from_dict(d)
    u = np.linspace(-0.35, 0.4, 31)
    rng = np.random.default_rng(3)
    du, ddu = rng.uniform(0.05, 0.3, u.size), rng.uniform(-0.5, 0.5, u.size)
    res = lk.analyze(mech, {"bucket_rod": u}, speed={"bucket_rod": du}, acceleration={"bucket_rod": ddu})
    g = complex(*d["gravity"])
    power = np.zeros(u.size)
    for ln in mech.links:
        if ln.mass == 0:
            continue
        pin, w, al = _body_rates(mech, res, ln.name, u, du, ddu)
        a, b = ln.joints[:2]
        rho = (ln.cg_pose - mech.joints[a]) / (mech.joints[b] - mech.joints[a])  # cg on the line a -> b
        r = res.point(a) + rho * (res.point(b) - res.point(a)) - res.point(pin)
        vg = res.velocity(pin) + 1j * w * r
        ag = res.acceleration(pin) + (1j * al - w * w) * r
        power += ln.mass * np.real(np.conj(vg) * (ag - g)) + ln.inertia * w * al
    for ld in mech.loads:
        power -= np.real(np.conj(ld.force) * res.velocity(ld.at_joint))
    force = res.forces.driver_force["bucket_rod"]
    assert np.max(np.abs(force * du - power)) <= 1e-9 * np.max(np.abs(force * du))


def _body_rates(mech, res, link, u, du, ddu):
    """(a joint, w, alpha) of a link, from joint rates that no rotation of a step carried.

    The four-bar's links from their first two joints (placed by circles); the barrel and the rod
    (whose other joints are carried with the barrel's rates) from their pins K, G: they turn as the
    line K -> G less the turn of rel(u) = rel0 + u d in the barrel's frame,
    d arg(rel)/du = Im(d / rel), d^2 arg(rel)/du^2 = -Im((d / rel)^2).
    """
    if link not in ("bucket_barrel", "bucket_rod"):
        a, b = mech.link(link).joints[:2]
        c = (res.velocity(b) - res.velocity(a)) / (res.point(b) - res.point(a))
        return (
            a,
            np.imag(c),
            np.imag((res.acceleration(b) - res.acceleration(a)) / (res.point(b) - res.point(a)) - c * c),
        )
    dd = res.point("G") - res.point("K")
    c = res.velocity("G") / dd
    w_line, al_line = np.imag(c), np.imag(res.acceleration("G") / dd - c * c)
    e = mech.sliders[0].direction
    q = e / (mech.joints["G"] - mech.joints["K"] + u * e)
    w_rel, al_rel = np.imag(q) * du, np.imag(q) * ddu - np.imag(q * q) * du * du
    return ("K" if link == "bucket_barrel" else "G"), w_line - w_rel, al_line - al_rel


def test_actuator_inside_a_triad_is_placed_by_the_numerical_group(tmp_path):
    """An actuator whose rod's pin is on a link no closed-form step places (inside a triad): refused with
    "slides on a link that nothing fixes" before groups took slider drivers (issue 29); now the group holds
    it: the pins are sqrt(17) + u apart (the slide is the line through both pins), every link keeps its lengths, the
    pose comes back at 0 and a sample beyond the stroke is flagged (tests/test_group_cylinders.py checks the
    numbers against the cylinder form and an independent solve)."""
    text = """
joints: {A: [0, 0], B: [4, 0], C: [1, -1], X: [0.5, 2], Y: [3.5, 2], G: [2, 3], CH: [1.25, 0]}
links:
  ground: [A, B, C]
  l1: [A, X]
  l2: [B, Y]
  plate: [X, Y, G]
  barrel: [C, CH]
  rod: [G]
sliders: [{link: rod, on: barrel, through: G, direction: [1, 4]}]
drivers: [{slider: 0, stroke: [-0.5, 0.5]}]
"""
    path = tmp_path / "triad_actuator.yaml"
    path.write_text(text)
    mech = lk.load(path)  # (with C at [2, -1] under G the pose is a dead point: G moves square to the slide)
    u = np.array([-0.55, -0.45, -0.2, 0.0, 0.04, 0.2])  # it assembles for u in [-0.5 (stroke), 0.0501 (dead point)]
    res = lk.analyze(mech, {"rod": u})
    assert res.assembled.tolist() == [False, True, True, True, True, False]
    z = {j: res.xy(j)[1:5] @ [1, 1j] for j in mech.joint_names}
    np.testing.assert_allclose(np.abs(z["G"] - z["C"]), np.sqrt(17) + u[1:5], rtol=0, atol=1e-10)
    for a, b in (("A", "X"), ("B", "Y"), ("X", "Y"), ("X", "G"), ("Y", "G"), ("C", "CH")):
        np.testing.assert_allclose(np.abs(z[a] - z[b]), abs(mech.joints[a] - mech.joints[b]), rtol=0, atol=1e-10)
    assert all(abs(z[j][2] - mech.joints[j]) <= 1e-12 for j in mech.joint_names)


@pytest.mark.parametrize(
    ("driver", "key"),
    [
        ("{slider: 0, stroke: [0.2, 0.5]}", "drivers[0].stroke"),  # leaves out the pose
        ("{slider: 0, stroke: [0.5, -0.5]}", "drivers[0].stroke"),
        (
            "{slider: 0, stroke: [-0.1, 0.1], displacements: {start: -0.2, stop: 0.1, step: 0.1}}",
            "drivers[0].displacements",
        ),
        ("{link: crank, pivot: A, toward: C, stroke: [0, 1]}", "drivers[0].stroke"),
    ],
)
def test_bad_slider_strokes(tmp_path, driver, key):
    """A slider driver's stroke: increasing, holding the pose (0), holding the file's sweep; a crank has none."""
    links = "{ground: [A], crank: [A, C], rod: [C, B], block: [B]}"
    text = f"""
joints: {{A: [0, 0], C: [0.03, 0.04], B: [0.115, 0]}}
links: {links}
sliders: [{{link: block, on: ground, through: B, direction: [1, 0]}}]
drivers: [{driver}]
"""
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(LinkageError, match=r"drivers\[0\]"):
        lk.load(path)
    try:
        lk.load(path)
    except LinkageError as e:
        assert key in str(e)


def test_check_names_the_stroke_ends_by_length_when_the_slide_points_back():
    """The slide from the rod's pin to the barrel's: u = -0.4 is the longest actuator (2.9 m), 0.35 the shortest."""
    d = lk.load("examples/excavator_bucket_slider.yaml").to_dict()
    d["sliders"][0]["direction"] = [-0.96, 0.28]  # along G -> K: the length is 2.5 - u
    d["drivers"][0]["stroke"] = [-0.4, 0.35]
    d["drivers"][0].pop("displacements", None)  # the sweep: the stroke's
    dead = lk.check(lk.Mechanism.from_dict(d))["dead_points"]["bucket_rod"]
    got = {round(dp["input"], 6): dp["detail"] for dp in dead}
    assert got == {
        -0.4: "cylinder 'bucket_rod' at the end of its stroke (longest)",
        0.35: "cylinder 'bucket_rod' at the end of its stroke (shortest)",
    }
    cyl = lk.check(lk.load("examples/excavator_bucket.yaml"))["dead_points"]["bucket_cylinder"]
    assert [dp["detail"].rsplit(" ", 1)[1] for dp in cyl] == ["(shortest)", "(longest)"]


def test_stroke_of_a_slider_driver_on_the_frame():
    """A block pushed along a fixed guide is flagged beyond its stroke too (the ends inclusive), with a round trip."""
    d = lk.load("examples/slider_crank.yaml").to_dict()
    k = next(i for i, s in enumerate(d["sliders"]) if s["on"] == "ground")
    d["drivers"] = [
        {"slider": k, "stroke": [-0.02, 0.01], "displacements": {"start": -0.02, "stop": 0.01, "step": 0.01}}
    ]
    mech = lk.Mechanism.from_dict(d)
    assert lk.Mechanism.from_dict(mech.to_dict()) == mech
    name = mech.drivers[0].name
    u = np.array([-0.03, -0.02, -0.01, 0.0, 0.01, 0.011])
    res = lk.analyze(mech, {name: u})
    np.testing.assert_array_equal(res.assembled, [False, True, True, True, True, False])
    rep = lk.check(mech).to_dict()
    assert np.allclose(rep["input_range"], [[-0.02, 0.01]], rtol=0, atol=1e-9)
    ends = [(p["kind"], p["detail"]) for p in rep["dead_points"][name]]
    assert ends == [("end of range", f"slider driver '{name}' at the end of its stroke ({e})") for e in ("min", "max")]
    free = lk.Mechanism.from_dict({**d, "drivers": [{"slider": k}]})
    ref = lk.analyze(free, {name: u})
    inside = res.assembled
    np.testing.assert_array_equal(
        res.point(mech.sliders[k].through)[inside], ref.point(mech.sliders[k].through)[inside]
    )


def test_offset_actuator_against_law_of_cosines_and_finite_differences():
    """A slide line not through the pins: the pins are |rel0 + u d| apart; positions by the law of cosines,
    rates by central differences of the positions (independent of the step's rate formulas)."""
    from helpers import by_cosines

    d = lk.load("examples/excavator_bucket_slider.yaml").to_dict()
    d["sliders"][0]["direction"] = [np.cos(np.radians(-12.0)), np.sin(np.radians(-12.0))]  # about 4 deg off K -> G
    d["drivers"][0].pop("stroke")
    d["drivers"][0]["displacements"] = {"start": -0.3, "stop": 0.3, "step": 0.1}
    mech = lk.Mechanism.from_dict(d)
    J = mech.joints
    e = complex(*d["sliders"][0]["direction"])
    u = np.linspace(-0.3, 0.3, 13)
    res = lk.analyze(mech, {"bucket_rod": u}, speed={"bucket_rod": 1.0}, acceleration={"bucket_rod": 0.0})

    def pin(x):  # G at 0.55 from F (the file's length) and |rel0 + u d| from K, right of F -> K (the pose's side)
        return by_cosines(J["F"], J["K"], 0.55, np.abs(J["G"] - J["K"] + x * e), -1)

    assert np.max(np.abs(res.point("G") - pin(u))) <= 1e-12 * mech.length_scale
    h = 1e-4
    v_fd = (pin(u + h) - pin(u - h)) / (2 * h)
    a_fd = (pin(u + h) - 2 * pin(u) + pin(u - h)) / h**2
    assert np.max(np.abs(res.velocity("G") - v_fd)) <= 1e-7
    assert np.max(np.abs(res.acceleration("G") - a_fd)) <= 1e-5

    def turn(x):  # the barrel's angle: the line K -> G turned back by rel(u)'s own angle
        return np.unwrap(np.angle((pin(x) - J["K"]) / (J["G"] - J["K"] + x * e)))

    th = np.deg2rad(res.angle("bucket_barrel")) - np.angle(J["KH"] - J["K"])
    assert np.max(np.abs(np.angle(np.exp(1j * (th - turn(u)))))) <= 1e-12
    assert np.max(np.abs(res.omega("bucket_barrel") - (turn(u + h) - turn(u - h)) / (2 * h))) <= 1e-7
    al_fd = (turn(u + h) - 2 * turn(u) + turn(u - h)) / h**2
    assert np.max(np.abs(res.alpha("bucket_barrel") - al_fd)) <= 1e-5
    assert np.max(np.abs(res.omega("bucket_rod") - res.omega("bucket_barrel"))) == 0.0


def test_forced_through_newton_far_past_the_stroke_is_flagged_not_an_index_error():
    """Review 12b: the slider form of the bucket forced through Newton and swept from -180 to 540 (the stroke is
    -0.35..0.4; the walk's grid of a length went up to ``GRID_MOST`` steps either way, 98 s for two inputs). A leg
    that reached the grid's last column covers the cell past it, whose far end is off the grid: the samples' start
    indexed the grid's slopes there (IndexError, an internal error). Now the grid ends a cell past the walk driver's
    stroke (every sample beyond it is flagged anyway; 0.1 s), a sample off the grid is NaN, and the flags and
    positions are the closed form's (1e-12 of the size)."""
    mech = lk.load("examples/excavator_bucket_slider.yaml")
    u = {mech.drivers[0].name: np.linspace(-180.0, 540.0, 1441)}
    ref = lk.analyze(mech, u, rates=False)
    res = lk.analyze(mech, u, method="numerical", rates=False)
    assert np.array_equal(res.assembled, ref.assembled) and ref.assembled.sum() >= 1
    size = max(abs(complex(*p)) for p in mech.pose_array())
    for j in mech.joint_names:
        assert np.nanmax(np.abs(res.xy(j) - ref.xy(j))) <= 1e-12 * size


def test_a_sample_past_the_walks_grid_is_flagged_not_an_index_error(monkeypatch):
    """The same bucket without a stroke, its walk's grid cut to 8 steps either way (``GRID_MOST``, 4096 in use): a
    sample in the cell past the grid's last column, whose far end is off the grid, raised IndexError (the samples'
    start indexed the grid's slopes there). Now every sample's flag and position are the closed form's (1e-12 of
    the size): those in the cells past either end are reached by sub-steps from the last column, and the one 20
    steps out assembles in neither."""
    from linkagekit import positions

    monkeypatch.setattr(positions, "GRID_MOST", 8)
    doc = lk.load("examples/excavator_bucket_slider.yaml").to_dict()
    del doc["drivers"][0]["stroke"]
    mech = lk.Mechanism.from_dict(doc)
    name = mech.drivers[0].name
    step = positions.GRID_STEP_LENGTH * np.mean(_group_lengths(mech))
    u = np.array([0.0, 3.5 * step, 8.5 * step, 20 * step, -8.5 * step])
    res = lk.analyze(mech, {name: u}, method="numerical", rates=False)
    ref = lk.analyze(mech, {name: u}, rates=False)
    on = res.assembled
    assert np.array_equal(on, ref.assembled) and on.tolist() == [True, True, True, False, True]
    size = max(abs(complex(*p)) for p in mech.pose_array())
    for j in mech.joint_names:
        assert np.max(np.abs(res.xy(j)[on] - ref.xy(j)[on])) <= 1e-12 * size


def _group_lengths(mech: lk.Mechanism) -> list[float]:
    """The link lengths of the bucket's numerical group forced through Newton (the grid step: 1/32 of their mean)."""
    from linkagekit.group import Group
    from linkagekit.params import compile  # noqa: A004
    from linkagekit.plan import make_plan

    params = compile(mech, None, make_plan(mech, True))
    gi, st = next((i, s) for i, s in enumerate(params.plan.steps) if isinstance(s, Group))
    lengths = st._design_nums(params.steps[gi], np.zeros(1, int))[0]
    return [float(np.ravel(x)[0]) for x in lengths]
