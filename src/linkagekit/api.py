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

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, replace
from functools import lru_cache
from types import MappingProxyType
from typing import Any

import numpy as np

from .branch import along_sweep, limits
from .errors import InputError, LinkageError, shorten
from .forces import Forces, Kinematics, solve_forces
from .model import Mechanism
from .options import BranchMode
from .params import Body, LoadParams, Params, as_poses, compile
from .plan import Plan, make_plan
from .positions import Positions, reference_mode, solve
from .rates import REPORTED_TOL, Rates, link_motion, solve_rates
from .result import Result, frozen
from .threads import one_blas_thread

ArrayLike = Any

#: design-samples per chunk of a batch: bounds the solver's working memory (~100 MB with rates)
CHUNK_SAMPLES = 1 << 17
#: the largest result one call may hold (bytes); beyond it analyze refuses and points to analyze_chunks
MAX_RESULT_BYTES = 4 << 30
#: the largest magnitude of an input value, speed or acceleration
MAX_ABS = 1e12


def prepare(mech: Mechanism, poses: ArrayLike | None = None, numerical: bool = False) -> Params:
    """The plan and numbers of the mechanism (or of each of ``poses``), in their reference modes.

    ``numerical``: place joints by numerical groups wherever possible (``method="numerical"``).
    """
    if not isinstance(mech, Mechanism):
        raise InputError(f"expected a linkagekit Mechanism (lk.load(...)), got {type(mech).__name__}")
    if poses is None:
        return _prepared(mech, numerical)
    _real_poses(poses)
    return compile(mech, as_poses(mech, poses), make_plan(mech, numerical))


def pose_inputs(mech: Mechanism) -> dict[str, float]:
    """Each driver's input at the reference pose, in file units.

    >>> import linkagekit as lk
    >>> {k: round(v, 4) for k, v in pose_inputs(lk.load("examples/slider_crank.yaml")).items()}
    {'crank': 53.1301}
    """
    params = prepare(mech)
    return {d.name: float(params.pose_inputs[i, 0] / d.input_scale(mech)) for i, d in enumerate(mech.drivers)}


@lru_cache(maxsize=64)
def _prepared(mech: Mechanism, numerical: bool = False) -> Params:
    """One mechanism's parameters in its reference mode, cached (mechanisms are immutable; the arrays read-only)."""
    return reference_mode(mech, compile(mech, None, make_plan(mech, numerical))).read_only()


# ---------------------------------------------------------------------- argument checks
def _real_any(value: ArrayLike, what: str) -> np.ndarray:
    """``value`` as an array as given (an ndarray is not copied), refused when complex.

    Complex values would lose their imaginary part silently in a conversion to float.
    """
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{what}: expected numbers, got {shorten(repr(value))}") from None
    if arr.dtype.kind == "c":
        raise InputError(f"{what}: expected real numbers, got complex values")
    if arr.dtype.kind not in "biuf":  # text, dates, objects: not numbers, even when they read as one
        raise InputError(f"{what}: expected numbers, got {shorten(repr(value))}")
    return arr


def _real(value: ArrayLike, what: str) -> np.ndarray:
    """``value`` as a non-empty 1-D real array as given: nothing is converted or allocated yet."""
    arr = np.atleast_1d(_real_any(value, what))
    if arr.ndim != 1:
        raise InputError(f"{what}: expected a 1-D array of values")
    if arr.size == 0:
        raise InputError(f"{what}: no values given")
    return arr


def _finite(arr: np.ndarray, what: str) -> np.ndarray:
    """``arr`` (from :func:`_real`, its size checked) as finite floats of at most ``MAX_ABS`` in magnitude."""
    try:
        out = np.asarray(arr, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{what}: expected numbers, got {shorten(repr(arr))}") from None
    if not np.all(np.isfinite(out)) or np.any(np.abs(out) > MAX_ABS):
        raise InputError(f"{what}: values must be finite numbers of at most {MAX_ABS:g} in magnitude")
    return out


def _as_array(value: ArrayLike, what: str) -> np.ndarray:
    return _finite(_real(value, what), what)


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
    arr = _real(value, what)
    if len(arr) not in (1, n):
        raise InputError(f"{what}: {len(arr)} values for {n} samples")
    return np.broadcast_to(_finite(arr, what), (n,)).astype(float)


def _choice(value: ArrayLike, names: tuple[str, ...], n: int, what: str, default: np.ndarray) -> np.ndarray:
    """Signs (+1/-1) or mirror flags (1/0) per slot from an array or a mapping, as (k, D or 1, 1 or n).

    An array gives every slot (one value, or one per sample); a mapping gives some slots by
    name and the others keep ``default`` (k, D): each design's reference mode, or no mirror.
    """
    k = len(names)
    if isinstance(value, Mapping):
        unknown = [key for key in value if key not in names]
        if unknown:
            raise InputError(f"{what}: no entry named '{unknown[0]}' (there are: {', '.join(names) or 'none'})")
        arr = np.array(default, float)[:, :, None]
        for key, v in value.items():
            try:
                arr[names.index(key)] = float(v)
            except (TypeError, ValueError, OverflowError):
                raise InputError(f"{what}: '{key}' needs a number, got {shorten(repr(v))}") from None
        return arr
    raw = _real_any(value, what)
    try:
        arr = np.asarray(raw, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{what}: expected numbers, got {shorten(repr(value))}") from None
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != k or arr.shape[1] not in (1, n):
        raise InputError(f"{what}: expected {k} values ({', '.join(names)}), or {k} rows of {n}, got shape {arr.shape}")
    return arr[:, None, :]


# ---------------------------------------------------------------------- the request
METHODS = ("natural", "vector-loop", "numerical")


@dataclass(frozen=True)
class Options:
    """The keyword arguments of :func:`analyze`, as given (see there)."""

    speed: Mapping[str, ArrayLike] | ArrayLike | None = None
    acceleration: Mapping[str, ArrayLike] | ArrayLike | None = None
    signs: ArrayLike | Mapping[str, int] | None = None
    mirrors: ArrayLike | Mapping[str, bool] | None = None
    poses: ArrayLike | None = None
    rates: bool = True
    dynamics: bool = True
    method: str = "natural"
    static: bool = False
    branch: str | BranchMode = BranchMode.POSE


@dataclass(frozen=True)
class Request:
    """An analysis as asked for, checked and normalised by :func:`request`: what :func:`solve_request` solves.

    ``q`` (drivers, D or 1, n) are the inputs in solver units (no design axis when every
    design shares them); ``values``, ``speeds``, ``accels`` are per driver in file units
    (speeds in rad/s or length/s), as the Result shows them; ``w_in``, ``a_in`` are
    (drivers, 1, n).  ``signs`` (sign steps, D or 1, n or 1) and ``mirrors`` (mirror links,
    ...) are None when the pose's own are used.  ``branch``: the pose's signs, or followed
    through change points (:class:`~linkagekit.options.BranchMode`).
    """

    mech: Mechanism
    params: Params
    poses: np.ndarray | None
    n_designs: int
    n: int
    values: dict[str, np.ndarray]
    q: np.ndarray
    speeds: dict[str, np.ndarray]
    accels: dict[str, np.ndarray]
    w_in: np.ndarray
    a_in: np.ndarray
    signs: np.ndarray | None
    mirrors: np.ndarray | None
    method: str
    rates: bool
    forces: bool
    branch: BranchMode = BranchMode.POSE


def _check_kinds(mech: Mechanism, o: Options) -> None:
    """The argument types checked before anything is computed."""
    if not isinstance(mech, Mechanism):
        raise InputError(f"expected a linkagekit Mechanism (lk.load(...)), got {type(mech).__name__}")
    for flag, value in (("rates", o.rates), ("dynamics", o.dynamics), ("static", o.static)):
        if not isinstance(value, bool | np.bool_):
            raise InputError(f"{flag}: expected True or False, got {type(value).__name__}")
    if not isinstance(o.method, str):
        raise InputError(f"method: expected 'natural', 'vector-loop' or 'numerical', got {type(o.method).__name__}")


def _given_inputs(mech: Mechanism, inputs: Mapping[str, ArrayLike] | ArrayLike | None) -> tuple[dict[str, Any], int]:
    """The inputs given per driver (1-D arrays, as given), and the number of samples (default: the file's sweep's).

    Nothing is converted here: :func:`request` checks the result's size first, then the values.
    """
    given = {k: _real(v, f"inputs[{k}]") for k, v in _per_driver(mech, inputs, "inputs").items()}
    n = max((len(v) for v in given.values()), default=0)
    longest = next((k for k, v in given.items() if len(v) == n), "")
    for k, v in given.items():
        if len(v) not in (1, n):
            raise InputError(
                f"driver '{k}' is given {len(v)} values and driver '{longest}' {n}: the drivers' values go together "
                "sample by sample (not as a grid), so give each driver as many values, or one"
            )
    return given, n if n else mech.drivers[0].sweep.count()


def _real_poses(poses: ArrayLike | None) -> None:
    """Refuse complex poses (their imaginary part would be dropped); the rest is checked by ``as_poses``."""
    if poses is None:
        return
    try:
        kind = np.asarray(poses).dtype.kind
    except (TypeError, ValueError, OverflowError):  # not an array of numbers: as_poses says so
        return
    if kind == "c":
        raise InputError("poses: expected real coordinates (n_designs, n_joints, 2), got complex values")


def _n_designs(mech: Mechanism, poses: ArrayLike | None, n: int, rates: bool) -> int:
    """The number of designs, once the result's size is known to stay within :data:`MAX_RESULT_BYTES`."""
    try:
        shape = np.shape(poses) if poses is not None else ()
    except (TypeError, ValueError, OverflowError):
        shape = ()
    D = int(shape[0]) if len(shape) == 3 else 1  # the size is checked before anything is built for it
    J, L = len(mech.joints), len(mech.links)
    nbytes = D * n * (16 * J * (3 if rates else 1) + (2 * 8 * L if rates else 0) + 32)
    if nbytes > MAX_RESULT_BYTES:
        raise InputError(
            f"this call would hold about {nbytes / 2**30:.1f} GB of results ({D} design(s) x {n} samples), "
            f"more than linkagekit.api.MAX_RESULT_BYTES ({MAX_RESULT_BYTES / 2**30:.0f} GB): use fewer samples, "
            "rates=False, or lk.analyze_chunks for many designs (or raise the limit)"
        )
    return D


def _input_values(
    mech: Mechanism, params: Params, given: dict[str, Any], n: int, D: int, batch: bool
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Every driver's input values (file units) and ``q`` (drivers, D or 1, n) in solver units.

    A driver not given follows its file's sweep when that has ``n`` samples, and otherwise
    stays at each design's reference-pose value.
    """
    factors = np.array([d.input_scale(mech) for d in mech.drivers])
    values: dict[str, np.ndarray] = {}
    per_design = [d.name not in given and d.sweep.count() != n for d in mech.drivers]
    q = np.empty((len(mech.drivers), D if any(per_design) else 1, n))  # shared inputs: no design axis
    for i, d in enumerate(mech.drivers):
        if d.name in given:
            values[d.name] = np.broadcast_to(given[d.name], (n,)).astype(float)
        elif d.sweep.count() == n:
            values[d.name] = d.sweep.values()
        else:
            values[d.name] = np.repeat(params.pose_inputs[i][:, None] / factors[i], n, axis=1)
        q[i] = values[d.name] * factors[i]
        if not batch:
            values[d.name] = np.reshape(values[d.name], (-1, n))[0]
    return values, q


def sweep_inputs(mech: Mechanism, params: Params) -> np.ndarray:
    """``q`` (drivers, D or 1, n) in solver units of the file's own sweep, exactly as :func:`analyze` runs it.

    ``n`` is the first driver's sweep count; a driver whose sweep has another count stays at
    each design's pose value (:func:`_input_values`).
    """
    n = mech.drivers[0].sweep.count()
    D = params.pose_inputs.shape[1]
    return _input_values(mech, params, {}, n, D, D > 1)[1]


def _input_rates(mech: Mechanism, o: Options, n: int) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Every driver's input speed and acceleration over the samples (``static``: zero)."""
    speed, acceleration = o.speed, o.acceleration
    if o.static:
        if speed is not None or acceleration is not None:
            raise InputError("static: the input speed and acceleration are zero; do not give them too")
        speed = {d.name: 0.0 for d in mech.drivers}
        acceleration = {d.name: 0.0 for d in mech.drivers}
    sp = _per_driver(mech, speed, "speed")
    ac = _per_driver(mech, acceleration, "acceleration")
    speeds = {d.name: _rate(sp.get(d.name, d.speed), n, f"speed[{d.name}]") for d in mech.drivers}
    accels = {d.name: _rate(ac.get(d.name, d.acceleration), n, f"acceleration[{d.name}]") for d in mech.drivers}
    return speeds, accels


def _modes(params: Params, o: Options, n: int) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The assembly signs and mirror flags asked for (None: the pose's own)."""
    plan = params.plan
    sg = None if o.signs is None else _choice(o.signs, plan.sign_joints, n, "signs", params.signs)
    if sg is not None and not np.all(np.abs(sg) == 1):
        raise InputError("signs: every sign must be +1 or -1")
    mr = None
    if o.mirrors is not None:
        m = _choice(o.mirrors, plan.mirror_links, n, "mirrors", np.zeros((plan.n_mirrors, 1)))
        if not np.all((m == 0) | (m == 1)):
            raise InputError("mirrors: expected true/false (or 1/0) per link: true flips it")
        mr = m == 1
    if o.method not in METHODS:
        raise InputError(f"method: expected 'natural', 'vector-loop' or 'numerical', got {o.method!r}")
    if o.method == "vector-loop" and (o.poses is not None or sg is not None or mr is not None):
        raise InputError("method 'vector-loop' solves one design in the pose's mode: no poses, signs or mirrors")
    return sg, mr


def _branch_mode(o: Options, sg: np.ndarray | None) -> BranchMode:
    """The ``branch`` option parsed (:class:`BranchMode`), and not continuous with given signs or the vector loop."""
    mode = BranchMode.parse(o.branch)
    if mode is BranchMode.CONTINUOUS and (sg is not None or o.method == "vector-loop"):
        raise InputError("branch 'continuous' chooses the signs itself: not with signs= or method='vector-loop'")
    return mode


def request(mech: Mechanism, inputs: Mapping[str, ArrayLike] | ArrayLike | None, o: Options) -> Request:
    """Check and normalise the arguments of :func:`analyze` (each error names its argument)."""
    _check_kinds(mech, o)
    _real_poses(o.poses)
    given, n = _given_inputs(mech, inputs)
    D = _n_designs(mech, o.poses, n, o.rates)  # the size first: nothing of that size is built before
    given = {k: _finite(v, f"inputs[{k}]") for k, v in given.items()}
    poses = None if o.poses is None else as_poses(mech, o.poses)
    params = prepare(mech, poses, numerical=o.method == "numerical")
    values, q = _input_values(mech, params, given, n, D, poses is not None)
    speeds, accels = _input_rates(mech, o, n)
    w_in = np.array([speeds[d.name] for d in mech.drivers])[:, None, :]
    a_in = np.array([accels[d.name] for d in mech.drivers])[:, None, :]
    sg, mr = _modes(params, o, n)
    mode = _branch_mode(o, sg)
    forces = bool(o.rates and o.dynamics and mech.has_dynamics)
    return Request(
        mech, params, poses, D, n, values, q, speeds, accels, w_in, a_in, sg, mr, o.method, o.rates, forces, mode
    )


def solve_request(req: Request) -> Result:
    """Solve a request chunk of designs by chunk of designs (bounded working memory) into one Result."""
    continuous = req.branch is BranchMode.CONTINUOUS
    out = _Outputs(req.mech, req.params.plan, req.n_designs, req.n, req.rates, continuous)
    chunk = max(1, CHUNK_SAMPLES // max(req.n, 1))
    for start in range(0, req.n_designs, chunk):  # every chunk writes its slice
        sl = slice(start, min(start + chunk, req.n_designs))
        p = req.params.take(sl)

        def cut(a: np.ndarray | None, sl: slice = sl) -> np.ndarray | None:
            """A chunk's designs of an array with a design axis (axis 1), or the array itself when it has none."""
            return a[:, sl] if a is not None and a.shape[1] > 1 else a

        rt: Rates | None = None
        if req.method == "vector-loop":
            pos, rt = _vector_loop(req.mech, req.params, req.q, req.w_in, req.a_in)
        else:
            pos, rt = _solve_chunk(req, p, cut, out, sl, continuous)
        out.write(sl, p, pos, rt)
        if req.forces:
            out.write_forces(sl, _forces(req.mech, p, out, sl, req.speeds))
    return _result(req, out)


def _solve_chunk(
    req: Request,
    p: Params,
    cut: Callable[[np.ndarray | None], np.ndarray | None],
    out: _Outputs,
    sl: slice,
    continuous: bool,
) -> tuple[Positions, Rates | None]:
    """Positions and rates of one chunk of designs (``p``), written into ``out``: the pose's signs, or the
    continuous branch's (signs followed along the path, and the branch's limit at samples on a change point)."""
    sg, q = cut(req.signs), cut(req.q)
    assert q is not None
    angular = tuple(d.type.cyclic for d in req.mech.drivers)
    br = along_sweep(p, q, angular) if continuous else None
    if br is not None:
        sg = br.signs
        assert out.signs is not None
        out.signs[:, sl] = sg
    pos = solve(p, q, sg, cut(req.mirrors), out=out.z[:, sl], continuous=continuous)
    rt = None
    if out.v is not None and out.a is not None:
        rt = solve_rates(p, pos, req.w_in, req.a_in, tol=REPORTED_TOL, out=(out.v[:, sl], out.a[:, sl]))
    if br is not None:
        pos, rt = limits(p, q, (req.w_in, req.a_in), cut(req.mirrors), br, angular, pos, rt)
    return pos, rt


# ---------------------------------------------------------------------- analyze
@one_blas_thread
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
    branch: str | BranchMode = "pose",
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
    rates, dynamics : bool
        False: positions only (faster, smaller); no forces even when the mechanism has masses or loads.
    method : {"natural", "vector-loop", "numerical"}
        ``"natural"`` (default): successive triangulation in natural coordinates, with
        numerical groups only where no closed-form step applies.
        ``"vector-loop"``: the independent link-angle formulation of seeds 003/001
        (:mod:`linkagekit.vectorloop`), four-bars and Stephenson six-bars, one design.
        ``"numerical"``: numerical groups (Newton, continued from the pose) wherever they
        apply, even where circle-circle steps could: a cross-check.
    static : bool
        Zero speed and acceleration for every driver: the forces are then the static ones
        that balance gravity and the loads (not to be combined with ``speed``/``acceleration``).
    branch : {"pose", "continuous"} or BranchMode
        ``"pose"`` (default): the pose's signs; ``"continuous"``: followed through change points
        (:mod:`linkagekit.branch`; ``Result.signs`` per sample; on a change point, the branch's limit).

    Returns
    -------
    Result
    """
    options = Options(speed, acceleration, signs, mirrors, poses, rates, dynamics, method, static, branch)
    return solve_request(request(mech, inputs, options))


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
    _real_poses(poses)
    arr = as_poses(mech, poses)
    if designs is None:
        n = mech.drivers[0].sweep.count()
        first: Any = next(iter(inputs.values())) if isinstance(inputs, Mapping) and inputs else inputs
        if first is not None:
            n = int(np.size(first))
        budget = CHUNK_SAMPLES * (8 if options.get("rates") is False else 1)
        designs = max(1, budget // max(n, 1))
    if isinstance(designs, bool) or not isinstance(designs, int | np.integer) or designs < 1:
        raise InputError(f"designs: a whole number of designs per chunk, at least 1, got {shorten(repr(designs))}")
    for start in range(0, arr.shape[0], designs):
        sl = slice(start, min(start + designs, arr.shape[0]))
        yield sl, analyze(mech, inputs, poses=arr[sl], **options)


# ---------------------------------------------------------------------- assembling the Result
class _Outputs:
    """The arrays of a Result over (designs, samples), allocated once and filled chunk by chunk."""

    def __init__(
        self, mech: Mechanism, plan: Plan, D: int, n: int, rates: bool, per_sample_signs: bool = False
    ) -> None:
        J = len(plan.joint_names)
        self.signs = np.empty((plan.n_signs, D, n)) if per_sample_signs else None  # the continuous branch's
        self.mech = mech
        self.z = np.empty((J, D, n), complex)
        self.v = np.empty((J, D, n), complex) if rates else None
        self.a = np.empty((J, D, n), complex) if rates else None
        self.assembled = np.empty((D, n), bool)
        self.singular = np.zeros((D, n), bool)
        self.condition = np.full((D, n), np.nan)
        self.blocks = [ln.name for ln in mech.links if len(ln.joints) < 2 and ln.name != "ground"]
        self.block_rot = {b: np.empty((D, n), complex) for b in self.blocks}
        self.omega = {ln.name: np.empty((D, n)) for ln in mech.links} if rates else None
        self.alpha = {ln.name: np.empty((D, n)) for ln in mech.links} if rates else None
        self.rot = {ln.name: np.empty((D, n), complex) for ln in mech.links} if rates and mech.has_dynamics else None
        self.forces: Forces | None = None

    def write_forces(self, sl: slice, f: Forces) -> None:
        """Store the forces of one chunk (the arrays are made on the first chunk)."""
        if self.forces is None:
            shape = self.assembled.shape
            self.forces = f.map(lambda a: np.empty(shape, a.dtype))
        for dst, src in zip(self.forces.arrays(), f.arrays(), strict=True):
            dst[sl] = src

    def write(self, sl: slice, params: Params, pos: Positions, rt: Rates | None) -> None:
        """Store one chunk of designs (positions are already in place when solved with ``out=``)."""
        if not np.shares_memory(pos.z, self.z[:, sl]):  # solved elsewhere (the vector-loop method)
            self.z[:, sl] = pos.z
        self.assembled[sl] = pos.assembled
        links = self.mech.links if rt is not None else [ln for ln in self.mech.links if ln.name in self.block_rot]
        motion = link_motion(params, pos, rt, links)
        for b in self.blocks:
            self.block_rot[b][sl] = motion[b][0]
        if rt is None or self.v is None or self.a is None or self.omega is None or self.alpha is None:
            return
        if not np.shares_memory(rt.v, self.v):
            self.v[:, sl], self.a[:, sl] = rt.v, rt.a
        self.singular[sl] = rt.singular
        if len(rt.condition):
            self.condition[sl] = np.where(pos.assembled, np.min(np.abs(rt.condition), axis=0), np.nan)
        else:
            self.condition[sl] = np.where(pos.assembled, 1.0, np.nan)
        for name, (rot, w, al) in motion.items():
            self.omega[name][sl], self.alpha[name][sl] = w, al
            if self.rot is not None:
                self.rot[name][sl] = rot


def _result(req: Request, out: _Outputs) -> Result:
    """The read-only Result of a solved request (the design axis dropped for one mechanism)."""
    mech, params, batch = req.mech, req.params, req.poses is not None

    def squeeze(a: np.ndarray) -> np.ndarray:
        """Drop the design axis (axis -2) of a single mechanism's arrays."""
        return frozen(a if batch else a[..., 0, :])

    def ro(d: Mapping[str, np.ndarray] | None) -> MappingProxyType[str, np.ndarray] | None:
        return None if d is None else MappingProxyType({k: squeeze(val) for k, val in d.items()})

    def proxy(d: dict[str, np.ndarray]) -> MappingProxyType[str, np.ndarray]:
        return MappingProxyType({k: frozen(v) for k, v in d.items()})

    block_rot = ro(out.block_rot)
    assert block_rot is not None
    res = Result(
        mech,
        proxy(req.values),
        proxy(req.speeds),
        proxy(req.accels),
        squeeze(out.assembled),
        squeeze(out.singular),
        squeeze(out.condition),
        MappingProxyType(_signs_used(req, out.signs)),
        None if out.forces is None else _frozen_forces(out.forces, squeeze),
        None if req.poses is None else frozen(req.poses),
        squeeze(out.z),
        None if out.v is None else squeeze(out.v),
        None if out.a is None else squeeze(out.a),
        ro(out.omega),
        ro(out.alpha),
        block_rot,
        _ground_angle(mech, params, batch),
    )
    res.catalogue  # noqa: B018 - built once here: two quantities with one column name are refused now
    return res


def _ground_angle(mech: Mechanism, params: Params, batch: bool) -> Any:
    """The frame's angle (rad): 0 for a one-joint ground, else per design (a column for a batch)."""
    if len(mech.link("ground").joints) < 2:
        return 0.0
    sa, sb = params.bases["ground"]
    per_design = np.angle(sb - sa)[:, 0]  # radians: link_angle converts to the file unit once
    return per_design[:, None] if batch else float(per_design[0])


def _signs_used(req: Request, chosen: np.ndarray | None = None) -> dict[str, Any]:
    """The mode used, per sign joint: an int (one design), or an array (per design and/or per sample).

    ``chosen``: the signs the continuous branch chose, (n_signs, D, n).
    """
    params, batch = req.params, req.poses is not None
    sg = req.signs if chosen is None else chosen
    signs_used = params.signs[:, :, None] if sg is None else np.broadcast_to(sg, (params.plan.n_signs, *sg.shape[1:]))
    sign_map: dict[str, Any] = {}
    for i, j in enumerate(params.plan.sign_joints):
        s = np.asarray(signs_used[i]).astype(int)  # (D or 1, n or 1)
        if not batch:
            s = s[0]
        elif s.shape[0] == 1 and params.n_designs > 1:
            s = np.broadcast_to(s, (params.n_designs, s.shape[1]))
        if s.shape[-1] == 1:
            s = s[..., 0]
        sign_map[j] = int(s) if s.ndim == 0 else frozen(s)
    return sign_map


def _forces(mech: Mechanism, params: Params, out: _Outputs, sl: slice, speeds: dict[str, np.ndarray]) -> Forces:
    """The kinetostatics of one chunk of designs (flattened: one linear system per design-sample), (C, n) arrays."""
    assert out.v is not None and out.a is not None and out.omega is not None and out.alpha is not None
    assert out.rot is not None
    shape = out.assembled[sl].shape
    N = int(np.prod(shape))

    def flat(a: np.ndarray) -> np.ndarray:
        return a[sl].reshape(N)

    def joints(a: np.ndarray) -> np.ndarray:
        return a[:, sl].reshape(a.shape[0], N)

    def spread(a: np.ndarray) -> np.ndarray:
        """A chunk's per-design column (C, 1) spread over its samples, flat (N,)."""
        return np.broadcast_to(a, shape).reshape(N)

    def per_sample(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else spread(a)

    km = Kinematics(
        joints(out.z),
        joints(out.v),
        joints(out.a),
        {k: (flat(out.rot[k]), flat(out.omega[k]), flat(out.alpha[k])) for k in out.omega},
        flat(out.assembled & ~out.singular),
        np.array([np.broadcast_to(speeds[d.name], out.assembled.shape)[sl].reshape(N) for d in mech.drivers]),
        tuple(Body(b.link, spread(b.mass), spread(b.inertia), per_sample(b.cg)) for b in params.bodies),
        tuple(LoadParams(ld.link, spread(ld.force), spread(ld.torque), per_sample(ld.at)) for ld in params.loads),
    )
    f = solve_forces(mech, km)
    return f.reshape(shape)


def _frozen_forces(f: Forces, squeeze: Any) -> Forces:
    """Read-only forces, the design axis dropped for a single mechanism."""
    g = f.map(squeeze)
    return replace(
        g,
        driver_torque=MappingProxyType(g.driver_torque),  # type: ignore[arg-type]
        driver_force=MappingProxyType(g.driver_force),  # type: ignore[arg-type]
        spring_force=MappingProxyType(g.spring_force),  # type: ignore[arg-type]
        spring_length=MappingProxyType(g.spring_length),  # type: ignore[arg-type]
        damper_force=MappingProxyType(g.damper_force),  # type: ignore[arg-type]
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
    """The assembly mode of the mechanism's reference pose: joint -> +1/-1 (the ``signs`` that ``modes`` lists)."""
    p = prepare(mech)
    return {j: int(p.signs[i, 0]) for i, j in enumerate(p.plan.sign_joints)}


__all__ = ["LinkageError", "analyze", "analyze_chunks", "prepare", "reference_signs"]
