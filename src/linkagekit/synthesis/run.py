"""``synthesize``: from target points to a mechanism, the library's entry point of synthesis.

Examples
--------
A four-bar whose coupler point passes through five points of a known coupler curve
(seconds on one core):

>>> import numpy as np, linkagekit as lk
>>> from linkagekit.synthesis.run import synthesize
>>> mech = lk.load("examples/seed000_fourbar.yaml")
>>> P = lk.analyze(mech, {"crank": [0, 60, 140, 220, 300]}).xy("P")
>>> out = synthesize(P, topology="fourbar", unit="cm", seed=1, restarts=2, generations=150)
>>> out.max_error < 1e-3 * out.diagonal, out.mechanism.drivers[0].name
(True, 'crank')
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError
from .objective import Problem, evaluate
from .optimize import Outcome, Progress, Settings, optimize
from .space import TOPOLOGIES, DesignSpace, builtin_space, template_space

if TYPE_CHECKING:
    from ..model import Mechanism

#: samples of the crank turn when the result is checked (every 0.1 degree)
CHECK_SAMPLES = 3600
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
    unit: str = "m",
    ordered: bool = False,
    min_transmission: float = 20.0,
    lengths: tuple[float, float] | None = None,
    pivots: tuple[tuple[float, float], tuple[float, float]] | None = None,
    free: Sequence[str] | Mapping[str, Any] | None = None,
    reach: float = 1.0,
    samples: int = 180,
) -> Problem:
    """The :class:`Problem` of ``targets`` ((m, 2) array or complex (m,)) in a topology or a template."""
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
    lo = np.array([z.real.min(), z.imag.min()])
    hi = np.array([z.real.max(), z.imag.max()])
    size = float(np.hypot(*(hi - lo)))
    if size <= 0:
        raise InputError("targets: the points span no distance")
    center = (float((lo[0] + hi[0]) / 2), float((lo[1] + hi[1]) / 2))
    space: DesignSpace
    if isinstance(topology, str):
        first = np.array([z[0].real, z[0].imag])
        box = (first - TRACER_BOX * size, first + TRACER_BOX * size)
        space = builtin_space(topology, center, size, unit, reach, box, pivots)
    else:
        space = template_space(topology, free or [j for j in topology.joint_names], center, size, reach)
    th = None
    if inputs is not None:
        th = np.radians(np.asarray(inputs, float).reshape(-1))
        if th.shape != z.shape or not np.all(np.isfinite(th)):
            raise InputError("targets: one finite input angle per target is needed")
    return Problem(space, z, th, ordered, float(min_transmission), lengths, samples)


def synthesize(
    targets: Any,
    topology: str | Mechanism = "fourbar",
    *,
    inputs: Sequence[float] | None = None,
    unit: str = "m",
    ordered: bool = False,
    min_transmission: float = 20.0,
    lengths: tuple[float, float] | None = None,
    pivots: tuple[tuple[float, float], tuple[float, float]] | None = None,
    free: Sequence[str] | Mapping[str, Any] | None = None,
    reach: float = 1.0,
    seed: int = 0,
    seconds: float = 60.0,
    restarts: int = 32,
    generations: int = 500,
    popsize: int = 15,
    goal: float = 1e-5,
    workers: int = 1,
    scheduler: str | None = None,
    checkpoint: str | None = None,
    progress: Callable[[Progress], None] | None = None,
) -> Synthesis:
    """Find a mechanism whose tracer point passes near every target.

    Parameters
    ----------
    targets : array_like, (m, 2) or complex (m,)
        The points, in ``unit``. An object with ``xy``, ``inputs`` and ``unit`` attributes
        (:class:`~linkagekit.synthesis.targets.Targets`) is taken as it is.
    topology : str or Mechanism
        One of ``TOPOLOGIES``, or a template mechanism (its joints ``free`` move within
        the targets' neighbourhood, all by default; its tracer is ``P``).
    inputs : sequence of float, optional
        The crank angle at each target (degrees): prescribed timing, up to one common offset.
    unit : str
        The targets' length unit (:data:`linkagekit.units.LENGTH_UNITS`), also the design's.
    ordered : bool
        Without timing, meet the targets in their order along the curve.
    min_transmission : float
        Degrees: transmission angles stay within ``[MIN, 180 - MIN]`` over the whole turn.
    lengths : (float, float), optional
        Bounds on every link length.
    pivots : ((xmin, xmax), (ymin, ymax)), optional
        The region of the ground pivots (built-in topologies).
    free : sequence of str or mapping, optional
        With a template: the joints that move (default all), or ``joint -> ((x0, x1), (y0, y1))``.
    reach : float
        Joints lie within ``reach`` target diagonals of the targets' centre.
    seed, seconds, restarts, generations, popsize, goal, workers, scheduler, checkpoint
        See :class:`~linkagekit.synthesis.optimize.Settings`.
    progress : callable, optional
        Called with a :class:`~linkagekit.synthesis.optimize.Progress` after every generation.
    """
    targets, inputs, unit = _unpack(targets, inputs, unit)
    problem = make_problem(targets, topology, inputs, unit, ordered, min_transmission, lengths, pivots, free, reach)
    settings = Settings(seed, seconds, restarts, generations, popsize, goal, workers, scheduler, checkpoint)
    return finish(problem, optimize(problem, settings, progress))


def _unpack(targets: Any, inputs: Sequence[float] | None, unit: str) -> tuple[Any, Sequence[float] | None, str]:
    """``(points, inputs, unit)``: a :class:`~linkagekit.synthesis.targets.Targets`'s own, else as given.

    Inputs given explicitly win over the targets' own.
    """
    if hasattr(targets, "xy") and hasattr(targets, "unit"):
        if inputs is None and getattr(targets, "inputs", None) is not None:
            inputs = list(targets.inputs)
        return targets.xy, inputs, targets.unit
    return targets, inputs, unit


def finish(problem: Problem, outcome: Outcome) -> Synthesis:
    """The :class:`Synthesis` of the best design: checked densely, as a mechanism."""
    x = outcome.x
    e = evaluate(problem, x[None], refine=4, samples=CHECK_SAMPLES, margin=0.0)
    err = e.errors[0]
    offset = float(np.degrees(problem.offset(x)[0])) if problem.timed else None
    max_err = float(np.max(err)) if np.all(np.isfinite(err)) else float("nan")
    name = f"synthesised {problem.space.topology}"
    if np.isfinite(max_err):
        name += f": max error {max_err:.4g} ({100 * max_err / problem.scale:.3g} % of the targets' diagonal)"
    mech = problem.space.mechanism(x, name)
    return Synthesis(
        mech,
        x,
        err,
        np.degrees(e.theta[0]),
        offset,
        problem.scale,
        bool(e.violation[0] == 0),
        float(e.transmission[0]),
        outcome,
    )


__all__ = ["TOPOLOGIES", "Synthesis", "make_problem", "synthesize"]
