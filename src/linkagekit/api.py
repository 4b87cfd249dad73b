"""``analyze``: inputs normalised once, then the kernels over (designs, samples), then one Result.

One design (a mechanism as its file describes it) or a batch (``poses=``: many reference
poses of the mechanism's topology, each a design with its own dimensions and assembly
mode) go through the same vectorized kernels.  A batch is cut into chunks of designs so
that the working memory stays bounded whatever the number of designs; the result holds
only what was asked for (``rates=False``: positions only).  For batches too large to hold
at all, :func:`analyze_chunks` yields one Result per chunk.

Examples
--------
>>> import numpy as np, linkagekit as lk
>>> mech = lk.load("examples/seed000_fourbar.yaml")
>>> pose = np.array([mech.joints[j] for j in mech.joint_names])
>>> poses = np.stack([np.c_[pose.real, pose.imag] * s for s in (1.0, 2.0, 3.0)])  # three sizes
>>> res = lk.analyze(mech, {"crank": np.arange(0.0, 360.0, 1.0)}, poses=poses)
>>> res.xy("P").shape, res.assembled.shape
((3, 360, 2), (3, 360))
>>> bool(np.allclose(res.xy("P")[2], 3 * res.xy("P")[0]))
True
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

from .errors import InputError, LinkageError
from .forces import Kinematics, solve_forces
from .model import Mechanism
from .params import Params, as_poses, compile
from .plan import make_plan
from .positions import Positions, reference_mode, solve
from .rates import Rates, link_motion, solve_rates
from .result import Result, frozen

ArrayLike = Any

#: design-samples per chunk of a batch: bounds the solver's working memory (~100 MB with rates)
CHUNK_SAMPLES = 1 << 17


def prepare(mech: Mechanism, poses: ArrayLike | None = None) -> Params:
    """The plan and numbers of the mechanism (or of each of ``poses``), in their reference modes."""
    if not isinstance(mech, Mechanism):
        raise InputError(f"expected a linkagekit Mechanism (lk.load(...)), got {type(mech).__name__}")
    plan = make_plan(mech)
    if poses is None:
        return reference_mode(mech, compile(mech, None, plan))
    return compile(mech, as_poses(mech, poses), plan)


# ---------------------------------------------------------------------- argument checks
def _as_array(value: ArrayLike, what: str) -> np.ndarray:
    try:
        arr = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError):
        raise InputError(f"{what}: expected numbers, got {value!r}") from None
    if arr.ndim != 1:
        raise InputError(f"{what}: expected a 1-D array of values")
    if arr.size == 0:
        raise InputError(f"{what}: no values given")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{what}: values must be finite numbers")
    return arr


def _per_driver(mech: Mechanism, given: Mapping[str, ArrayLike] | ArrayLike | None, what: str) -> dict[str, Any]:
    names = [d.name for d in mech.drivers]
    if given is None:
        return {}
    if not isinstance(given, Mapping):
        if len(names) != 1:
            raise InputError(
                f"{what}: this mechanism has drivers {', '.join(names)}: give one value per driver by name"
            )
        return {names[0]: given}
    for k in given:
        if k not in names:
            raise InputError(f"{what}: no driver named '{k}' (drivers: {', '.join(names)})")
    return dict(given)


def _rate(value: ArrayLike, n: int, what: str) -> np.ndarray:
    arr = _as_array(value, what)
    if len(arr) not in (1, n):
        raise InputError(f"{what}: {len(arr)} values for {n} samples")
    return np.broadcast_to(arr, (n,)).astype(float)


def _choice(value: ArrayLike, names: tuple[str, ...], n: int, what: str, kind: str) -> np.ndarray:
    """Signs (+1/-1) or mirror flags per slot, as (k, 1, 1 or n), from an array or a mapping."""
    k = len(names)
    if isinstance(value, Mapping):
        unknown = [key for key in value if key not in names]
        if unknown:
            raise InputError(f"{what}: no {kind} '{unknown[0]}' (there are: {', '.join(names) or 'none'})")
        arr = np.array([value.get(nm, np.nan) for nm in names], float)
    else:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{what}: expected +1/-1 values, got {value!r}") from None
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != k or arr.shape[1] not in (1, n):
        raise InputError(f"{what}: expected {k} values ({', '.join(names)}), or {k} rows of {n}, got shape {arr.shape}")
    return arr[:, None, :]


# ---------------------------------------------------------------------- analyze
def analyze(
    mech: Mechanism,
    inputs: Mapping[str, ArrayLike] | ArrayLike | None = None,
    *,
    speed: Mapping[str, ArrayLike] | ArrayLike | None = None,
    acceleration: Mapping[str, ArrayLike] | ArrayLike | None = None,
    signs: ArrayLike | Mapping[str, int] | None = None,
    mirrors: ArrayLike | Mapping[str, bool] | None = None,
    poses: ArrayLike | None = None,
    rates: bool = True,
    dynamics: bool = True,
    method: str = "natural",
    static: bool = False,
) -> Result:
    """Positions, velocities and accelerations (and forces, when the file has masses or loads).

    Parameters
    ----------
    mech : Mechanism
    inputs : mapping of driver name to array, optional
        Input values in the file's units (angle unit, or length unit for a slider
        driver), the same for every design.  With one driver a bare array is accepted.
        Drivers left out follow their default sweep from the file when it has as many
        samples as the others, and otherwise stay at their reference-pose value.
    speed, acceleration : mapping of driver name to scalar or array, optional
        Input speed (rad/s, or length/s for a slider) and acceleration; default: the file's.
    signs : array_like or mapping of joint name to +1/-1, optional
        Assembly mode, one sign per sign step (``Result.signs`` names them); an array may
        have one column per sample.  Default: each design's reference pose's.
    mirrors : array_like or mapping of link name to bool, optional
        Flip links of three or more joints (default: as in the pose).
    poses : array_like, shape (n_designs, n_joints, 2), optional
        Many designs of this topology in one call: each design's reference pose, joints in
        ``mech.joint_names`` order, file units.  Each design reads its dimensions and its
        assembly mode off its own pose, exactly as a file without ``lengths`` would; masses,
        inertias, loads and slider directions are the mechanism's (centres of gravity and
        load points keep their place relative to each link's first two joints).
    rates : bool
        False: positions only (faster, smaller).
    dynamics : bool
        False: no forces even when the mechanism has masses or loads.
    method : {"natural", "vector-loop"}
        ``"natural"`` (default): successive triangulation in natural coordinates.
        ``"vector-loop"``: the independent link-angle formulation of seeds 003/001
        (:mod:`linkagekit.vectorloop`), four-bars and Stephenson six-bars, one design.
    static : bool
        Zero speed and acceleration for every driver: the forces are then the static ones
        that balance gravity and the loads (not to be combined with ``speed``/``acceleration``).

    Returns
    -------
    Result
    """
    params = prepare(mech, poses)
    plan = params.plan
    D = params.n_designs
    given = {k: _as_array(v, f"inputs[{k}]") for k, v in _per_driver(mech, inputs, "inputs").items()}
    n = max((len(v) for v in given.values()), default=0)
    for k, v in given.items():
        if len(v) not in (1, n):
            raise InputError(f"inputs: driver '{k}' has {len(v)} values but another has {n}; give equal lengths")
    if n == 0:
        n = len(mech.drivers[0].sweep.values())
    factors = np.array([mech.angle_to_rad if d.kind == "angle" else 1.0 for d in mech.drivers])
    values: dict[str, np.ndarray] = {}
    q = np.empty((len(mech.drivers), D, n))
    for i, d in enumerate(mech.drivers):
        if d.name in given:
            values[d.name] = np.broadcast_to(given[d.name], (n,)).astype(float)
        else:
            sw = d.sweep.values()
            values[d.name] = sw if len(sw) == n else np.repeat(params.pose_inputs[i][:, None] / factors[i], n, axis=1)
        q[i] = values[d.name] * factors[i]
        if poses is None:
            values[d.name] = np.reshape(values[d.name], (-1, n))[0]

    if static:
        if speed is not None or acceleration is not None:
            raise InputError("static: the input speed and acceleration are zero; do not give them too")
        speed = {d.name: 0.0 for d in mech.drivers}
        acceleration = {d.name: 0.0 for d in mech.drivers}
    sp = _per_driver(mech, speed, "speed")
    ac = _per_driver(mech, acceleration, "acceleration")
    speeds = {d.name: _rate(sp.get(d.name, d.speed), n, f"speed[{d.name}]") for d in mech.drivers}
    accels = {d.name: _rate(ac.get(d.name, d.acceleration), n, f"acceleration[{d.name}]") for d in mech.drivers}
    w_in = np.array([speeds[d.name] for d in mech.drivers])[:, None, :]
    a_in = np.array([accels[d.name] for d in mech.drivers])[:, None, :]

    sg = None if signs is None else _choice(signs, plan.sign_joints, n, "signs", "sign joint")
    if sg is not None and not np.all(np.abs(sg) == 1):
        raise InputError("signs: every sign must be +1 or -1")
    mr = None
    if mirrors is not None:
        m = _choice(mirrors, plan.mirror_links, n, "mirrors", "mirror link")
        if not np.all((m == 0) | (m == 1)):
            raise InputError("mirrors: expected true/false (or 1/0) per link: true flips it")
        mr = m == 1

    if method == "vector-loop":
        if poses is not None or signs is not None or mirrors is not None:
            raise InputError("method 'vector-loop' solves one design in the pose's mode: no poses, signs or mirrors")
        pos, rt = _vector_loop(mech, params, q, w_in, a_in)
        return _build(mech, params, None, values, speeds, accels, [(slice(0, 1), pos, rt)], rates, dynamics, sg)
    if method != "natural":
        raise InputError(f"method: expected 'natural' or 'vector-loop', got {method!r}")

    chunk = max(1, CHUNK_SAMPLES // max(n, 1))
    z_out = np.empty((len(plan.joint_names), D, n), complex)
    parts: list[tuple[slice, Positions, Rates | None]] = []
    for start in range(0, D, chunk):
        sl = slice(start, min(start + chunk, D))
        p = params.take(sl)
        qq = q[:, sl]
        pos = solve(p, qq, None if sg is None else sg, mr, out=z_out[:, sl])
        parts.append((sl, pos, solve_rates(p, pos, w_in, a_in) if rates else None))
    return _build(mech, params, poses, values, speeds, accels, parts, rates, dynamics, sg, z_out)


def analyze_chunks(
    mech: Mechanism,
    inputs: Mapping[str, ArrayLike] | ArrayLike | None = None,
    *,
    poses: ArrayLike,
    designs: int | None = None,
    **options: Any,
) -> Iterator[tuple[slice, Result]]:
    """:func:`analyze` over a large batch of poses, one chunk of designs at a time.

    Yields ``(slice, result)`` pairs: ``result`` covers ``poses[slice]``.  Memory stays
    bounded by the chunk (``designs`` designs per chunk; default: about 2^17 design-samples
    with rates, 2^20 positions only) whatever the number of designs.
    """
    arr = as_poses(mech, poses)
    if designs is None:
        n = len(mech.drivers[0].sweep.values())
        first: Any = next(iter(inputs.values())) if isinstance(inputs, Mapping) and inputs else inputs
        if first is not None:
            n = int(np.size(first))
        budget = CHUNK_SAMPLES * (8 if options.get("rates") is False else 1)
        designs = max(1, budget // max(n, 1))
    if designs < 1:
        raise InputError("designs: at least one design per chunk")
    for start in range(0, arr.shape[0], designs):
        sl = slice(start, min(start + designs, arr.shape[0]))
        yield sl, analyze(mech, inputs, poses=arr[sl], **options)


# ---------------------------------------------------------------------- assembling the Result
def _cat(parts: list[Any], axis: int) -> np.ndarray:
    return parts[0] if len(parts) == 1 else np.concatenate(parts, axis=axis)


def _build(
    mech: Mechanism,
    params: Params,
    poses: ArrayLike | None,
    values: dict[str, np.ndarray],
    speeds: dict[str, np.ndarray],
    accels: dict[str, np.ndarray],
    parts: list[tuple[slice, Positions, Rates | None]],
    rates: bool,
    dynamics: bool,
    sg: np.ndarray | None,
    z_out: np.ndarray | None = None,
) -> Result:
    plan = params.plan
    batch = poses is not None

    def squeeze(a: np.ndarray) -> np.ndarray:
        """Drop the design axis (axis -2) of a single mechanism's arrays."""
        return frozen(a if batch else a[..., 0, :])

    z = z_out if z_out is not None else _cat([p.z for _, p, _ in parts], 1)
    assembled = _cat([p.assembled for _, p, _ in parts], 0)
    blocks = [ln for ln in mech.links if len(ln.joints) < 2 and ln.name != "ground"]
    motion_parts = []
    for sl, pos, rt in parts:
        links = mech.links if rates else blocks
        motion_parts.append(link_motion(params.take(sl), pos, rt, links))
    block_rot = {ln.name: squeeze(_cat([m[ln.name][0] for m in motion_parts], 0)) for ln in blocks}
    omega = alpha = None
    v = a = None
    if rates:
        v = _cat([rt.v for _, _, rt in parts], 1)  # type: ignore[union-attr]
        a = _cat([rt.a for _, _, rt in parts], 1)  # type: ignore[union-attr]
        singular = _cat([rt.singular for _, _, rt in parts], 0)  # type: ignore[union-attr]
        cond_parts = []
        for _, pos, rt in parts:
            c = np.min(np.abs(rt.condition), axis=0) if plan.n_signs else np.ones(pos.assembled.shape)  # type: ignore[union-attr]
            cond_parts.append(np.where(pos.assembled, c, np.nan))
        condition = _cat(cond_parts, 0)
        omega, alpha = (
            {ln.name: squeeze(_stitch(motion_parts, parts, ln.name, k)) for ln in mech.links} for k in (1, 2)
        )
    else:
        singular = np.zeros(assembled.shape, bool)
        condition = np.full(assembled.shape, np.nan)

    forces = None
    if rates and dynamics and mech.has_dynamics:
        forces = _forces(mech, parts, motion_parts, speeds, assembled.shape, batch)

    ground = next(ln for ln in mech.links if ln.name == "ground")
    if len(ground.joints) >= 2:
        sa, sb = params.bases["ground"]
        ground_angle = np.angle(sb - sa)[:, 0] / mech.angle_to_rad  # per design
        ground_angle = ground_angle[:, None] if batch else float(ground_angle[0])
    else:
        ground_angle = 0.0

    signs_used = params.signs[:, :, None] if sg is None else sg
    sign_map = {}
    for i, j in enumerate(plan.sign_joints):
        s = np.asarray(signs_used[i])
        if s.shape[-1] == 1:
            s = s[..., 0]
        sign_map[j] = (s.astype(int) if batch else int(s[0])) if s.ndim == 1 else s.astype(int)

    def ro(d: dict[str, np.ndarray]) -> MappingProxyType[str, np.ndarray]:
        return MappingProxyType({k: frozen(val) for k, val in d.items()})

    return Result(
        mech,
        ro(values),
        ro(speeds),
        ro(accels),
        squeeze(assembled),
        squeeze(singular),
        squeeze(condition),
        MappingProxyType(sign_map),
        forces,
        None if poses is None else frozen(np.asarray(as_poses(mech, poses))),
        squeeze(z),
        None if v is None else squeeze(v),
        None if a is None else squeeze(a),
        None if omega is None else MappingProxyType(omega),
        None if alpha is None else MappingProxyType(alpha),
        MappingProxyType(block_rot),
        ground_angle,
    )


def _stitch(motion_parts: list[dict[str, Any]], parts: list[Any], link: str, k: int) -> np.ndarray:
    """Item ``k`` (1: omega, 2: alpha) of a link's motion over all chunks, shape (D, n)."""
    return _cat(
        [np.broadcast_to(m[link][k], p.assembled.shape) for m, (_, p, _) in zip(motion_parts, parts, strict=True)], 0
    )


def _forces(
    mech: Mechanism,
    parts: list[tuple[slice, Positions, Rates | None]],
    motion_parts: list[dict[str, Any]],
    speeds: dict[str, np.ndarray],
    shape: tuple[int, ...],
    batch: bool,
) -> Any:
    """The kinetostatics of every chunk, flattened to samples, stitched back to ``shape``."""
    from .forces import Forces, Reaction

    chunks = []
    for (_, pos, rt), motion in zip(parts, motion_parts, strict=True):
        assert rt is not None
        cshape = pos.assembled.shape
        N = int(np.prod(cshape))
        flat: dict[str, Any] = {k: tuple(np.broadcast_to(x, cshape).reshape(N) for x in m) for k, m in motion.items()}
        sp = np.array([np.broadcast_to(speeds[d.name], cshape).reshape(N) for d in mech.drivers])
        km = Kinematics(
            pos.z.reshape(pos.z.shape[0], N),
            rt.v.reshape(rt.v.shape[0], N),
            rt.a.reshape(rt.a.shape[0], N),
            flat,
            (pos.assembled & ~rt.singular).reshape(N),
            sp,
        )
        chunks.append((cshape, solve_forces(mech, km)))

    def stitch(get: Any) -> np.ndarray:
        arr = _cat([get(f).reshape(cs) for cs, f in chunks], 0)
        return frozen(arr if batch else arr[0])

    first = chunks[0][1]
    reactions = tuple(
        Reaction(
            r.joint,
            r.on,
            r.by,
            stitch(lambda f, i=i: f.reactions[i].force),
            None if r.moment is None else stitch(lambda f, i=i: f.reactions[i].moment),
        )
        for i, r in enumerate(first.reactions)
    )
    return Forces(
        reactions,
        MappingProxyType({k: stitch(lambda f, k=k: f.driver_torque[k]) for k in first.driver_torque}),  # type: ignore[arg-type]
        MappingProxyType({k: stitch(lambda f, k=k: f.driver_force[k]) for k in first.driver_force}),  # type: ignore[arg-type]
        stitch(lambda f: f.input_power),
        stitch(lambda f: f.shaking_force),
        stitch(lambda f: f.shaking_moment),
        stitch(lambda f: f.residual),
    )


def _vector_loop(
    mech: Mechanism, params: Params, q: np.ndarray, w_in: np.ndarray, a_in: np.ndarray
) -> tuple[Positions, Rates]:
    """Positions and rates by :mod:`linkagekit.vectorloop`, packed like the main solver's (one design)."""
    from .vectorloop import from_mechanism

    model, offset = from_mechanism(mech)
    sol = model.solve(q[0, 0] + offset, w_in[0, 0], a_in[0, 0])
    names = mech.joint_names
    z = np.array([sol.z[j] for j in names])[:, None, :]
    v = np.array([sol.v[j] for j in names])[:, None, :]
    a = np.array([sol.a[j] for j in names])[:, None, :]
    assembled = sol.assembled[None, :]
    margin = np.where(assembled, 1.0, -1.0)[None]
    pos = Positions(z, {}, margin, assembled, params.signs[:, :, None], np.zeros((params.plan.n_mirrors, 1, 1), bool))
    omega = {k: val[None, :] for k, val in sol.omega.items()}
    alpha = {k: val[None, :] for k, val in sol.alpha.items()}
    return pos, Rates(v, a, omega, alpha, sol.condition[None, None, :], sol.singular[None, :])


def reference_signs(mech: Mechanism) -> dict[str, int]:
    """The assembly mode of the mechanism's reference pose: joint -> +1/-1 (spec section 2's ``signs``)."""
    p = prepare(mech)
    return {j: int(p.signs[i, 0]) for i, j in enumerate(p.plan.sign_joints)}


__all__ = ["LinkageError", "analyze", "analyze_chunks", "prepare", "reference_signs"]
