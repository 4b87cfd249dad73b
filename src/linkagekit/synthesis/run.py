"""``synthesize``: from target points to a mechanism, the library's entry point of synthesis.

Examples
--------
A four-bar whose coupler point passes through five points of a known coupler curve
(seconds on one core):

>>> import numpy as np, linkagekit as lk
>>> from linkagekit.synthesis.run import synthesize
>>> mech = lk.load("examples/seed000_fourbar.yaml")
>>> P = lk.analyze(mech, {"crank": [0, 60, 140, 220, 300]}).xy("P")
>>> out = synthesize(P, topology="fourbar", units="cm", seed=1, restarts=2, generations=150)
>>> out.max_error < 1e-3 * out.diagonal, out.mechanism.drivers[0].name
(True, 'crank')
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..checks import MIN_TRANSMISSION
from ..errors import InputError, LinkageError
from ..threads import one_blas_thread_with_scipy
from ..units import LENGTH_UNITS
from .base import Objective
from .distribute import usable
from .function_run import FunctionSynthesis, synthesize_function
from .objective import Problem, check
from .optimize import LIMITS, Optimum, Outcome, Progress, Settings, default_workers, optimize, search
from .space import TOPOLOGIES, DesignSpace, builtin_space, fixed, template_space
from .targets import check_scale, plural

if TYPE_CHECKING:
    from ..model import Mechanism

#: the tracer's box at the pose: this fraction of the targets' diagonal around the first target
TRACER_BOX = 0.05


@dataclass(frozen=True)
class Synthesis:
    """The outcome of :func:`synthesize`.

    Attributes
    ----------
    mechanism : Mechanism
        The design (tracer ``P``, driver ``crank`` for the built-in topologies), lengths
        read off its pose, in the targets' unit.
    x : ndarray (dim,)
        The design vector found: ``[x_0, y_0, x_1, y_1, ...]`` over the free joints of the
        pose, in the targets' unit (:mod:`linkagekit.synthesis.space`).
    errors : ndarray (m,)
        Distance from each target to the tracer's curve (or to its point at the target's
        input, with timing), in the targets' unit, checked on ``CHECK_SAMPLES`` samples
        with the nearest points refined.
    inputs : ndarray (m,)
        The crank angle (degrees) where each target is met.
    offset : float or None
        With timing, the common input offset found (degrees): the crank is at
        ``input + offset`` at each target.
    diagonal : float
        The targets' bounding-box diagonal.
    feasible : bool
        The crank turns fully and every constraint holds (checked on ``CHECK_SAMPLES``).
    min_transmission : float
        The smallest transmission angle over the turn (degrees).
    outcome : Outcome
        How the search went (restarts, generations, evaluations, seconds, what stopped it).
    sweep : (float, float) or None
        With ``partial``: the crank's range ``(start, stop)`` in degrees (the written driver's sweep).
    placement : (complex, complex) or None
        With ``shape_only``: the similarity ``z -> a z + b`` that moved, turned and scaled the
        design ``x`` onto the targets (the mechanism is the placed one).
    topology : str
        The topology's name (``fourbar``, ``sixbar-3``, ...; a template's source).
    tried : tuple
        ``--topology auto``: the topologies searched (:class:`~.auto.Tried`), else empty.
    bound : float
        The transmission bound the design was searched under (degrees; ``--min-transmission``).
    pareto : tuple of Synthesis
        With ``pareto=True``: a short list of designs from the most accurate (this one) to the
        best-transmitting, none beaten by another in both the max error and the smallest
        transmission angle (:mod:`linkagekit.synthesis.front`); otherwise empty.
    """

    mechanism: Mechanism
    x: np.ndarray
    errors: np.ndarray
    inputs: np.ndarray
    offset: float | None
    diagonal: float
    feasible: bool
    min_transmission: float
    outcome: Outcome
    sweep: tuple[float, float] | None = None
    placement: tuple[complex, complex] | None = None
    topology: str = ""
    tried: tuple[Any, ...] = ()
    bound: float = MIN_TRANSMISSION
    pareto: tuple[Synthesis, ...] = ()

    @property
    def margin(self) -> float:
        """How far the smallest transmission angle is above the bound (degrees; negative: below it)."""
        return self.min_transmission - self.bound

    @property
    def max_error(self) -> float:
        """The largest distance from a target to the tracer (``max(errors)``), in the targets' unit."""
        return float(np.max(self.errors))

    @property
    def rms_error(self) -> float:
        """The root mean square of the distances ``errors``, in the targets' unit."""
        return float(np.sqrt(np.mean(self.errors**2)))


def make_problem(
    targets: Any,
    topology: str | Mechanism = "fourbar",
    inputs: Sequence[float] | None = None,
    units: str = "m",
    ordered: bool = False,
    min_transmission: float = MIN_TRANSMISSION,
    lengths: tuple[float, float] | None = None,
    pivots: tuple[tuple[float, float], tuple[float, float]] | None = None,
    free: Sequence[str] | Mapping[str, Any] | None = None,
    reach: float = 3.0,
    samples: int = 180,
    shape_only: bool = False,
    partial: bool = False,
    **old: Any,
) -> Problem:
    """The :class:`Problem` of ``targets`` ((m, 2) array or complex (m,)) in a topology or a template.

    ``units`` is the targets' length unit (``unit=``, its former name, still works with a
    :class:`DeprecationWarning`). ``shape_only``: a built-in topology's ground pivots are fixed
    half a diagonal apart below the targets' centre (:func:`~.space.fixed`; the placement does
    the rest), ``pivots`` cannot be given, and the tracer is not held near the first target.
    """
    units = _units(units, old)
    t = np.asarray(targets)
    if np.iscomplexobj(t):
        z = t.reshape(-1)
    else:
        t = np.asarray(t, float)
        if t.ndim < 2 or t.shape[-1] != 2:
            raise InputError(f"targets: expected (m, 2) points, got shape {t.shape}")
        t = t.reshape(-1, 2)
        z = t[:, 0] + 1j * t[:, 1]
    if len(z) < 3:
        raise InputError(f"targets: {len(z)} points; at least 3 are needed")
    if not np.all(np.isfinite(z)):
        raise InputError("targets: every coordinate must be a finite number")
    lo, hi = (np.array([f(z.real), f(z.imag)]) for f in (np.min, np.max))
    size = float(np.hypot(*(hi - lo)))
    if size <= 0:
        raise InputError("targets: the points span no distance")
    check_scale(np.c_[z.real, z.imag], "targets", units)
    center = (float((lo[0] + hi[0]) / 2), float((lo[1] + hi[1]) / 2))
    space: DesignSpace
    if shape_only and pivots is not None:
        raise InputError("--pivots: the ground pivots have no place of their own with --shape-only")
    if isinstance(topology, str) and shape_only:
        space = fixed(builtin_space(topology, center, size / 2, units, 2 * reach), ("A", "B"))  # ground: L / 2
    elif isinstance(topology, str):
        first = np.array([z[0].real, z[0].imag])
        box = (first - TRACER_BOX * size, first + TRACER_BOX * size)
        space = builtin_space(topology, center, size, units, reach, box, pivots)
    else:
        space = template_space(topology, free or [j for j in topology.joint_names], center, size, reach)
    th = None
    if inputs is not None:
        th = np.radians(np.asarray(inputs, float).reshape(-1))
        if th.shape != z.shape or not np.all(np.isfinite(th)):
            raise InputError("targets: one finite input angle per target is needed")
    return Problem(space, z, th, ordered, float(min_transmission), lengths, samples, shape_only, partial)


@one_blas_thread_with_scipy
def synthesize(
    targets: Any,
    topology: str | Mechanism = "fourbar",
    *,
    task: str = "path",
    objective: Objective | None = None,
    **options: Any,
) -> Synthesis | MotionSynthesis | FunctionSynthesis | Optimum:
    """Design a mechanism: for a path, a motion or a function (docs/commands.md), or for any ``objective``.

    Parameters
    ----------
    targets : array_like or Targets or None
        ``task="path"``: the points (m, 2) or complex (m,) (:func:`synthesize_path`);
        ``"motion"``: the poses (m, 3) ``x, y, angle`` (degrees) (:func:`synthesize_motion`);
        ``"function"``: the pairs (m, 2) ``input, output`` (degrees from the ground line)
        (:func:`~linkagekit.synthesis.function_run.synthesize_function`).  ``None`` with ``objective``.
    topology : str or Mechanism
        Path generation's topology or template.
    task : str
        ``"path"`` (the default), ``"motion"`` or ``"function"``.
    objective : Objective, optional
        A user's own :class:`~linkagekit.synthesis.base.Objective`: searched by the same engine
        instead (:func:`~linkagekit.synthesis.optimize.search`); returns an :class:`Optimum`.
    **options
        The keywords of the function that runs the task (for ``objective``, the engine's:
        ``seed``, ``seconds``, ``restarts``, ``generations``, ``popsize``, ``goal``, ``workers``,
        ``scheduler``, ``checkpoint``, ``progress``).  ``angle_weight`` is motion's ``weight``.

    Returns
    -------
    Synthesis, MotionSynthesis, FunctionSynthesis or Optimum
    """
    if objective is not None:
        return search(objective, **options)
    from ..model import Mechanism

    if not isinstance(topology, (str, Mechanism)):
        raise InputError(f"topology: expected a name such as 'fourbar' or a Mechanism, got {type(topology).__name__}")
    targets = _targets_given(targets, task, options)
    if task == "path":
        return synthesize_path(targets, topology, **options)
    if task == "motion":
        if "angle_weight" in options:
            options["weight"] = options.pop("angle_weight")
        if options.get("min_transmission") is None:
            options.pop("min_transmission", None)
        return synthesize_motion(targets, **options)
    if task == "function":
        return _function_task(targets, **options)
    raise InputError(f"task: expected 'path', 'motion' or 'function', got {task!r}")


def _targets_given(targets: Any, task: str, options: dict[str, Any]) -> Any:
    """The targets as the task takes them: a file name (str or path) read by :func:`~.targets.read_targets` (path
    generation, in ``options``' ``units``); a :class:`~.targets.Targets` whose unit another ``units=`` contradicts,
    or anything that is not numbers, refused in one line (they were a ValueError, a TypeError or ignored)."""
    from .targets import read_targets

    key = "units" if "units" in options or "unit" not in options else "unit"  # unit=: its former name
    if isinstance(targets, (str, os.PathLike)):
        if task != "path":
            reader = "synthesis.motion.read_poses" if task == "motion" else "synthesis.function.read_pairs"
            raise InputError(f"targets: a file name; read it first (linkagekit.{reader}) and pass its numbers")
        return read_targets(targets, units=options.get(key, "m"))
    if hasattr(targets, "xy") and hasattr(targets, "unit"):
        if options.get(key, targets.unit) != targets.unit:
            raise InputError(
                f"{key}={options[key]!r}: the targets were read in {targets.unit!r} "
                "(give the unit to read_targets, which keeps it)"
            )
        return targets
    try:
        np.asarray(targets, complex)
    except (TypeError, ValueError):
        raise InputError(f"targets: expected an array of numbers, got {type(targets).__name__}") from None
    return targets


def _function_task(
    targets: Any, units: str = "m", min_transmission: float | None = None, **options: Any
) -> FunctionSynthesis:
    """``synthesize(task="function")``: the pairs' two columns to :func:`synthesize_function`."""
    pairs = np.asarray(targets, float)
    if pairs.ndim != 2 or pairs.shape[1] != 2:
        raise InputError("targets: function generation takes pairs (m, 2) of input, output angles (degrees)")
    mt = 0.0 if min_transmission is None else float(min_transmission)
    return synthesize_function(pairs[:, 0], pairs[:, 1], units=units, min_transmission=mt, **options)


def synthesize_path(
    targets: Any,
    topology: str | Mechanism = "fourbar",
    *,
    inputs: Sequence[float] | None = None,
    units: str = "m",
    ordered: bool = False,
    min_transmission: float | None = None,
    lengths: tuple[float, float] | None = None,
    pivots: tuple[tuple[float, float], tuple[float, float]] | None = None,
    free: Sequence[str] | Mapping[str, Any] | None = None,
    reach: float = 3.0,
    shape_only: bool = False,
    partial: bool = False,
    seed: int = 0,
    seconds: float = 60.0,
    restarts: int = 1000,
    generations: int = 500,
    popsize: int = 15,
    goal: float = 1e-5,
    workers: int | None = None,
    scheduler: str | None = None,
    checkpoint: str | None = None,
    progress: Callable[[Progress], None] | None = None,
    pareto: bool = False,
    **old: Any,
) -> Synthesis:
    """Path generation: a mechanism whose tracer point passes near every target (``synthesize``'s ``task="path"``).

    Parameters
    ----------
    targets : array_like, (m, 2) or complex (m,), or Targets
        The points, in ``units`` (a :class:`~linkagekit.synthesis.targets.Targets` as it is).
    topology, units : str or Mechanism, str
        One of ``TOPOLOGIES`` or a template mechanism (its joints ``free`` move; its tracer is ``P``); the
        targets' length unit (:data:`~linkagekit.units.LENGTH_UNITS`; ``unit=``, its former name, warns).
    inputs : sequence of float, optional
        The crank angle at each target (degrees): prescribed timing, up to one common offset.
    ordered, shape_only, partial : bool
        The targets met in order; matched up to a similarity (placed on them); on a part swept by >= 90 deg.
    min_transmission, lengths, pivots, free, reach : optional
        Transmission angles within ``[MIN, 180 - MIN]`` degrees (default 20); bounds on every link length; the
        region ``((xmin, xmax), (ymin, ymax))`` of the ground pivots (built-in topologies); with a template, the
        joints that move (default all), or ``joint -> ((x0, x1), (y0, y1))``; joints within ``reach`` diagonals.
    seed, seconds, restarts, generations, popsize, goal, workers, scheduler, checkpoint, progress, pareto
        See :class:`~.optimize.Settings` (``workers``: every core by default); ``progress`` gets a ``Progress``
        per generation (first, :mod:`~.atlas`); ``pareto``: also search at transmission bounds 10, 20 and 30
        degrees higher, and return in ``pareto`` designs from the most accurate to the best-transmitting.

    Returns
    -------
    Synthesis
    """
    targets, inputs, units, source = _unpack(targets, inputs, _units(units, old))
    mt = MIN_TRANSMISSION if min_transmission is None else min_transmission
    args = (targets, topology, inputs, units, ordered, mt, lengths, pivots, free, reach, 180, shape_only, partial)
    problem = make_problem(*args)
    workers = default_workers() if workers is None else usable(workers)
    settings = Settings(seed, seconds, restarts, generations, popsize, goal, workers, scheduler, checkpoint, pareto)
    return finish(problem, _from_atlas(problem, settings, progress), source)


#: the share of the time the atlas's answer may take, unless a checkpoint asks for a reproducible one (then it is
#: bounded by its evaluations only)
ATLAS_SHARE = 0.25


def _from_atlas(problem: Problem, settings: Settings, progress: Callable[[Progress], None] | None) -> Outcome:
    """The search started from the atlas's answer (:func:`~.atlas.first_answer`), when the atlas has the topology.

    The answer, within :data:`ATLAS_SHARE` of the time (without a checkpoint), is reported at once
    (``Progress.source == "atlas"``); one that meets the goal ends the run.
    ``LINKAGEKIT_ATLAS_SIZE=0`` turns the atlas off.
    """
    from . import atlas

    if not atlas.applies(problem):
        return optimize(problem, settings, progress)

    def start() -> np.ndarray:
        t0 = time.monotonic()
        clocked = not settings.checkpoint  # a checkpoint's answer is reproducible: bounded by its evaluations only
        until, whole = (t0 + ATLAS_SHARE * settings.seconds, t0 + settings.seconds) if clocked else (None, None)
        workers = None if settings.scheduler else settings.workers
        ans = atlas.first_answer(problem, workers=workers, until=until, first_until=whole)
        if progress is not None and len(ans.designs):
            progress(Progress(0, 0, ans.cost, ans.error, len(ans.designs), time.monotonic() - t0, source="atlas"))
        return ans.designs

    return optimize(problem, settings, progress, start)


def _units(units: str, old: dict[str, Any]) -> str:
    """``units``, or the deprecated ``unit=`` among the other keywords ``old`` (anything else: TypeError)."""
    unknown = set(old) - {"unit"}
    if unknown:
        raise TypeError(f"unexpected keyword argument {sorted(unknown)[0]!r}")
    if "unit" in old:
        import warnings

        warnings.warn("synthesize(unit=...) is now units=... (as in read_targets)", DeprecationWarning, stacklevel=3)
        units = str(old["unit"])
    if not isinstance(units, str) or units not in LENGTH_UNITS:  # it was "fourbar: units.length: ..."
        raise InputError(f"units: expected one of {', '.join(map(repr, LENGTH_UNITS))}, got {units!r}")
    return units


def _unpack(
    targets: Any, inputs: Sequence[float] | None, unit: str
) -> tuple[Any, Sequence[float] | None, str, str | None]:
    """``(points, inputs, unit, source)``: a :class:`~linkagekit.synthesis.targets.Targets`'s own, else as given.

    Inputs given explicitly win over the targets' own.
    """
    if hasattr(targets, "xy") and hasattr(targets, "unit"):
        if inputs is None and getattr(targets, "inputs", None) is not None:
            inputs = list(targets.inputs)
        return targets.xy, inputs, targets.unit, getattr(targets, "source", None)
    return targets, inputs, unit, None


def finish(problem: Problem, outcome: Outcome, source: str | None = None) -> Synthesis:
    """The :class:`Synthesis` of the best design: checked densely, as a mechanism (with --pareto, its short list).

    The mechanism's ``name`` gives its max error with its unit; its ``description`` records the
    targets (``source``: where they came from), the errors and the search.
    """
    best = _finish(problem, outcome, outcome.x, source)
    if not outcome.front:
        return best
    from .front import short_list

    xs = [best.x] + [f[0] for f in outcome.front]
    err = np.array([best.max_error / best.diagonal] + [f[1] for f in outcome.front])
    mu = np.array([best.min_transmission] + [f[2] for f in outcome.front])
    more = [i for i in short_list(err, mu) if i != 0 and err[i] >= err[0] and mu[i] > mu[0]]
    listed = [best] + [_finish(problem, outcome, xs[i], source) for i in more]
    return replace(best, pareto=tuple(listed))


def named(name: str, errors: np.ndarray, unit: str, diagonal: float) -> str:
    """A synthesised mechanism's ``name``: ``name`` and its max error with its unit (where every error is known).

    >>> named("synthesised fourbar", np.array([0.1, 0.25]), "mm", 10.0)
    "synthesised fourbar: max error 0.25 mm (2.5 % of the targets' diagonal)"
    """
    if not np.all(np.isfinite(errors)):
        return name
    worst = float(np.max(errors))
    return f"{name}: max error {worst:.4g} {unit} ({100 * worst / diagonal:.3g} % of the targets' diagonal)"


def _finish(problem: Problem, outcome: Outcome, x: np.ndarray, source: str | None) -> Synthesis:
    """The :class:`Synthesis` of design ``x``."""
    e = check(problem, x[None])
    err = e.errors[0]
    turn = float(np.angle(e.a[0]))  # the placement turns the crank's angles too
    offset = float(np.degrees(problem.offset(x)[0])) if problem.timed else None
    unit = problem.space.template.length_unit
    name = named(f"synthesised {problem.space.topology}", err, unit, problem.scale)
    if e.violation[0] != 0:  # the best found breaks a constraint: the file says so where a reader looks first
        name = f"INFEASIBLE {name} (it breaks a constraint)"
    try:
        mech = problem.mechanism(x, name)
    except InputError as exc:  # pushed against its bounds, the best found put two joints at one spot
        raise LinkageError(
            f"no design found meets the constraints, and the best one is no mechanism ({exc.args[0].split(': ')[-1]}):"
            " widen --pivots or --lengths"
        ) from None
    start, span = np.degrees(e.sweep[0, 0] + turn), np.degrees(e.sweep[0, 1])
    out = Synthesis(
        mech,
        x,
        err,
        np.degrees(e.theta[0] + turn),
        offset,
        problem.scale,
        bool(e.violation[0] == 0),
        float(e.transmission[0]),
        outcome,
        (float(start), float(start + span)) if problem.partial else None,
        (complex(e.a[0]), complex(e.b[0])) if problem.shape_only else None,
        problem.space.topology,
        bound=problem.min_transmission,
    )
    return replace(out, mechanism=replace(mech, description=describe(out, problem, source)))


def transmission_line(out: Synthesis) -> str:
    """The smallest transmission angle, and how far it is above the bound (the margin)."""
    where = "above" if out.margin >= 0 else "below"
    return (
        f"smallest transmission angle {out.min_transmission:.4g} deg, {abs(out.margin):.3g} deg {where} "
        f"the bound {out.bound:g} deg"
    )


#: targets listed one by one in a description, at most
DESCRIBED_TARGETS = 100


def describe(out: Synthesis, problem: Problem, source: str | None = None) -> str:
    """The ``description`` of a synthesised mechanism: its targets, its errors (with units), the search."""
    unit = problem.space.template.length_unit
    m, o = len(out.errors), out.outcome
    lines = [f"Synthesised by linkagekit from {m} target points" + (f" ({source})" if source else "") + "."]
    lines.append(
        f"max error {out.max_error:.6g} {unit} ({100 * out.max_error / out.diagonal:.4g} % of the targets' "
        f"diagonal {out.diagonal:.6g} {unit}), rms {out.rms_error:.6g} {unit}"
    )
    if out.offset is not None:  # to full precision: the file's errors are recomputed from it
        lines.append(f"input offset {out.offset:.17g} deg (crank angle = input + offset)")
    if out.placement is not None:
        a, b = out.placement
        lines.append(f"shape only: the design placed by z -> a z + b, a = {a:.9g}, b = {b:.9g} {unit}")
    if out.sweep is not None:
        lines.append(f"partial: the crank rocks from {out.sweep[0]:.6g} to {out.sweep[1]:.6g} deg")
    lines.append(transmission_line(out) + ("" if out.feasible else ", INFEASIBLE"))
    lines.append(
        f"{plural(o.restarts, 'search', 'searches')}, {plural(o.generations, 'generation')}, "
        f"{plural(o.evaluations, 'design')}; stopped by {o.stopped_by}"
    )
    if m <= DESCRIBED_TARGETS:
        lines.append(
            f"targets: x [{unit}], y [{unit}]" + (", input [deg]" if problem.timed else "") + f", error [{unit}]"
        )
        z, th = problem.targets, problem.inputs
        for i in range(m):
            row = [z[i].real, z[i].imag] + ([np.degrees(th[i])] if th is not None else []) + [out.errors[i]]
            lines.append("  " + ", ".join(f"{float(v):.9g}" for v in row))
    return "\n".join(lines)


__all__ = [
    "TOPOLOGIES",
    "MotionFourBar",
    "MotionSynthesis",
    "Optimum",
    "Synthesis",
    "describe",
    "make_problem",
    "search",
    "synthesize",
    "synthesize_motion",
]


# ---------------------------------------------------------------------- motion generation
@dataclass(frozen=True)
class MotionFourBar:
    """One four-bar found for the poses.

    Attributes
    ----------
    mechanism : Mechanism
        Joints ``A0, A1, B1, B0, P, Q``; the coupler carries ``P`` (the pose point) and ``Q``
        (along the pose's line); driver ``crank`` sweeping from the first pose to the last.
    position_errors : ndarray (m,)
        ``|P - (x, y)|`` at each pose, in the poses' unit.
    angle_errors : ndarray (m,)
        The orientation error at each pose, degrees (signed: achieved minus wanted).
    inputs : ndarray (m,)
        The crank angle at each pose (degrees), in the order the crank turns.
    one_branch : bool
        The poses are met in order on one assembly branch, assembling all the way.
    grashof : str
        Its Grashof type (:func:`linkagekit.checks.grashof`).
    min_transmission : float
        The smallest transmission angle over the sweep (degrees).
    method : str
        ``"exact"`` (Burmester) or ``"approximate"``.
    """

    mechanism: Mechanism
    position_errors: np.ndarray
    angle_errors: np.ndarray
    inputs: np.ndarray
    one_branch: bool
    grashof: str
    min_transmission: float
    method: str

    @property
    def max_position_error(self) -> float:
        return float(np.max(self.position_errors))

    @property
    def max_angle_error(self) -> float:
        """Degrees."""
        return float(np.max(np.abs(self.angle_errors)))


@dataclass(frozen=True)
class MotionSynthesis:
    """The outcome of :func:`synthesize_motion`.

    Attributes
    ----------
    fourbars : list of MotionFourBar
        Every four-bar found, the best first.
    diagonal : float
        The poses' bounding-box diagonal.
    weight : float
        The angle weight of the error measure (:mod:`linkagekit.synthesis.motion`).
    best : MotionFourBar
        ``fourbars[0]``.
    mechanism : Mechanism
        The best four-bar's mechanism.
    """

    fourbars: list[MotionFourBar]
    diagonal: float
    weight: float

    @property
    def best(self) -> MotionFourBar:
        """The best four-bar found."""
        return self.fourbars[0]

    @property
    def mechanism(self) -> Mechanism:
        """The best four-bar's mechanism."""
        return self.best.mechanism


def synthesize_motion(
    poses: Any,
    *,
    inputs: Sequence[float] | None = None,
    closed: bool = False,
    approximate: bool = False,
    weight: float | None = None,
    min_transmission: float = 0.0,
    units: str = "m",
    seed: int = 0,
    seconds: float = 20.0,
    full_turn: bool = False,
    engine: Mapping[str, Any] | None = None,
    source: str = "motion",
) -> MotionSynthesis:
    """Four-bars whose coupler passes through (or near) the poses, best first.

    Parameters
    ----------
    poses : array_like (m, 3)
        ``x, y, angle`` per pose (``angle`` in degrees, counter-clockwise from +x).
    inputs : sequence of float, optional
        The crank angle at each pose (degrees): timing, up to one common offset.
    closed, approximate : bool
        The motion is a cycle (the crank turns fully, back to the first pose); for 3 to 5
        poses, the approximate route instead of the exact one (Burmester).
    weight : float, optional
        The angle weight ``w`` (diagonals per radian, default ``motion.ANGLE_WEIGHT``).
    min_transmission, units : float, str
        Degrees: the smallest transmission angle allowed over the sweep; the poses' length unit.
    full_turn : bool
        The crank turns fully in one assembly mode, meeting the poses on the way (as a closed motion's).
    seed, seconds, engine : int, float, mapping
        The engine's search that adds seeds: by default short (``ENGINE_SEEDS``, at most 5 s);
        ``engine`` may set its ``restarts``, ``generations``, ``workers``, ``scheduler``, ``checkpoint``.
    source : str
        Names the poses in the LinkageError raised when no four-bar found meets them in order on one branch.

    Examples
    --------
    >>> import linkagekit as lk
    >>> from linkagekit.synthesis import motion
    >>> t = np.radians([0, 15, 30, 45, 60, 75])
    >>> F = np.array([[0.0, 0, 0.3, 0.1, 0.4, 0.9, 0, 0.6, -0.2, 0.7]])  # a four-bar: pose of the body at t
    >>> O, u, _, _ = motion.frames(F, t[None], np.array([1.0]))
    >>> poses = np.stack([O[0].real, O[0].imag, np.degrees(np.angle(u[0]))], axis=1)
    >>> out = synthesize_motion(poses)
    >>> bool(out.best.max_position_error < 1e-9 and out.best.max_angle_error < 1e-7 and out.best.one_branch)
    True
    """
    deadline = time.monotonic() + LIMITS["seconds"].check(seconds, "seconds")  # checked: the exact route runs no engine
    P, p, w = _motion_problem(poses, inputs, closed or full_turn, weight)  # the approximate route: as a cycle
    exact = 3 <= p.m <= 5 and not approximate and inputs is None and not closed
    found = _exact_route(P, units, full_turn) if exact else []
    if not any(_admissible(f, min_transmission) for f in found):
        found += _approximate_route(p, w, min_transmission, units, seed, seconds, engine or {}, deadline)
    if not any(_admissible(f, min_transmission) for f in found):
        raise _none_found(source, min_transmission, seconds if time.monotonic() > deadline else 0.0, exact)
    return MotionSynthesis(_best_first(found, p.scale, w, min_transmission), p.scale, w)


def _exact_route(P: np.ndarray, units: str, full_turn: bool) -> list[MotionFourBar]:
    """The exact four-bars (Burmester) of 3 to 5 poses ``P``, judged over a whole turn with ``full_turn``."""
    found = _exact_motion(P, units)
    return [_turning_fully(f) for f in found] if full_turn else found


def _approximate_route(
    p: Any, w: float, min_transmission: float, units: str, seed: int, seconds: float, engine: Any, deadline: float
) -> list[MotionFourBar]:
    """The approximate route's four-bars (:func:`~.motion.approximate`), the engine's best design among its seeds."""
    from . import motion as mo

    seeds = _engine_seeds(mo.MotionObjective(p, w, min_transmission), seed, seconds, engine)
    found = []
    for d in mo.approximate(p, w, min_transmission, seeds, deadline):
        try:
            found.append(_motion_fourbar(p, d, units))
        except LinkageError:  # no mechanism (its ground pivots at one spot): 1000 poses on an arc ended the run
            continue
    return found


def _none_found(source: str, min_transmission: float, late: float, exact: bool) -> LinkageError:
    """The error of a motion synthesis that found no admissible four-bar: what was searched, not that none exists.

    ``late``: the time budget (seconds) when it ran out before the polish was done (0: it did not);
    ``exact``: the exact route (Burmester) was searched first.

    >>> str(_none_found("p.csv", 0.0, 0.0, False)).split(" (searched")[0]
    'p.csv: no four-bar found that meets the poses in order on one branch'
    """
    bound = f" with a transmission angle within [{min_transmission:g}, {180 - min_transmission:g}] deg"
    wanted = f"meets the poses in order on one branch{bound * (min_transmission > 0)}"
    if late:
        budget = f"in the time budget ({late:g} s; more may find one)"
        return LinkageError(f"{source}: no four-bar found {budget} that {wanted}")
    routes = "the exact four-bars (Burmester), " * exact
    routes += "pairs of circle-fit dyads and the engine's best, the best polished to the minimax"
    return LinkageError(f"{source}: no four-bar found that {wanted} (searched: {routes})")


def _best_first(found: list[MotionFourBar], scale: float, w: float, min_transmission: float) -> list[MotionFourBar]:
    """The four-bars found, the admissible first, each group by ``E`` (:mod:`~.motion`)."""
    return sorted(
        found,
        key=lambda f: (
            not _admissible(f, min_transmission),
            max(f.max_position_error / scale, w * np.radians(f.max_angle_error)),
        ),
    )


def _admissible(f: MotionFourBar, min_transmission: float) -> bool:
    """Meets the poses in order on one branch, its transmission angle never below ``min_transmission`` (degrees).

    The exact route (Burmester) knows no bound: its four-bars are judged here, the approximate
    route's search and polish impose it.
    """
    return f.one_branch and not f.min_transmission < min_transmission - 1e-6


def _motion_problem(poses: Any, inputs: Sequence[float] | None, closed: bool, weight: float | None) -> Any:
    """The checked poses (m, 3), the :class:`~.motion.MotionPoses` and the angle weight of :func:`synthesize_motion`."""
    from . import motion as mo

    P = np.asarray(poses, float)
    if P.ndim != 2 or P.shape[1] != 3:
        raise InputError(f"poses: expected (m, 3) rows of x, y, angle, got shape {P.shape}")
    if np.any(np.abs(P[:, 2]) > 360):
        raise InputError("poses: an angle is out of range (degrees within [-360, 360] expected)")
    ins = None if inputs is None else np.radians(np.asarray(inputs, float))
    p = mo.motion_poses(P[:, 0], P[:, 1], np.radians(P[:, 2]), ins, closed)
    w = mo.ANGLE_WEIGHT if weight is None else float(weight)
    if not w > 0:
        raise InputError(f"--angle-weight: expected a positive number, got {weight}")
    return P, p, w


#: motion's search of seeds by default: a short one (the circle fits do most of the work)
ENGINE_SEEDS: dict[str, Any] = {"restarts": 2, "generations": 60, "popsize": 15, "goal": 0.0}


def _engine_seeds(objective: Any, seed: int, seconds: float, engine: Mapping[str, Any]) -> np.ndarray:
    """The engine's best design of the circle-fit objective, as a four-bar vector (1, 10).

    A short search (:data:`ENGINE_SEEDS`, at most 5 s) unless ``engine`` says otherwise: its
    restarts, generations, workers, scheduler and checkpoint are the engine's, as for every task.
    """
    given = {k: v for k, v in engine.items() if v is not None}
    budget = seconds if given else min(seconds, 5.0)
    settings = Settings(seed, budget, **{**ENGINE_SEEDS, **given})
    x = optimize(objective, settings).x
    return np.asarray(objective.fourbars(x[None]), float)


def _motion_fourbar(p: Any, d: Any, units: str) -> MotionFourBar:
    """A :class:`~linkagekit.synthesis.motion.MotionDesign` as a :class:`MotionFourBar`."""
    from ..checks import FourBar, grashof
    from . import motion as mo

    v = d.vector
    ga, a, gb, b = complex(v[0], v[1]), complex(v[2], v[3]), complex(v[5], v[6]), complex(v[7], v[8])
    kind, _ = grashof(FourBar(0, 1, 2, 3, ground=abs(gb - ga), crank=v[4], coupler=abs(b - a), rocker=v[9]))
    name = f"motion four-bar: max errors {np.max(d.position_errors):.4g} {units}, "
    name += f"{np.degrees(np.max(np.abs(d.angle_errors))):.4g} deg"
    mech = mo.mechanism(p, d, units, name)
    return MotionFourBar(
        mech,
        d.position_errors,
        np.degrees(d.angle_errors),
        np.degrees(d.inputs),
        d.one_branch,
        kind,
        d.min_transmission,
        "approximate",
    )


def _whole_sweep(mech: Mechanism, start: float, stop: float) -> tuple[bool, float]:
    """Does a written four-bar (joints ``A0, A1, B1, B0`` of its reference pose) assemble at every crank angle from
    ``start`` to ``stop`` (degrees), and its smallest transmission angle there (degrees, folded to [0, 90]; NaN
    where not): exactly, by :func:`~linkagekit.geometry.fourbar_sweep` (samples every 1/4 degree step over a gap)."""
    from ..geometry import fourbar_sweep

    A0, A1, B1, B0 = (mech.joints[j] for j in ("A0", "A1", "B1", "B0"))
    ok, mu = fourbar_sweep(A0, abs(A1 - A0), B0, abs(B1 - A1), abs(B1 - B0), np.radians(start), np.radians(stop))
    return bool(ok), float(mu)


def _turning_fully(f: MotionFourBar) -> MotionFourBar:
    """An exact four-bar judged over a whole turn of its crank from the first pose (the pose's mode throughout).

    Its driver then sweeps that turn; ``one_branch`` says whether it assembles all the way (exactly:
    :func:`_whole_sweep`).
    """
    from ..model import Mechanism

    if not f.one_branch:
        return f
    start = float(f.inputs[0])
    way = 1.0 if f.inputs[-1] >= f.inputs[0] else -1.0
    data = f.mechanism.to_dict()
    data["drivers"][0]["angles"] = {"start": start, "stop": start + way * 360.0, "step": way}
    mech = Mechanism.from_dict(data, "<Burmester four-bar>")
    turns, smallest = _whole_sweep(mech, start, start + way * 360.0)
    return replace(f, mechanism=mech, one_branch=turns, min_transmission=smallest)


def _exact_motion(P: np.ndarray, units: str) -> list[MotionFourBar]:
    """Every four-bar of Burmester theory for 3 to 5 poses (:mod:`linkagekit.synthesis.burmester`), if available."""
    import importlib

    try:
        burmester = importlib.import_module("linkagekit.synthesis.burmester")
    except ImportError:
        return []
    out = []
    for fb in burmester.exact_motion((P[:, 0], P[:, 1], np.radians(P[:, 2]))):
        name = f"Burmester four-bar: max error {fb.position_error:.3g} {units}"
        out.append(
            MotionFourBar(
                fb.mechanism(units, name),
                np.asarray(fb.position_errors, float),
                np.degrees(np.asarray(fb.angle_errors, float)),
                np.degrees(np.asarray(fb.inputs, float)),
                bool(fb.in_order),
                str(fb.grashof),
                _whole_sweep(fb.mechanism(units, name), *np.degrees(fb.inputs[[0, -1]]))[1] if fb.in_order else np.nan,
                "exact",
            )
        )
    return out
