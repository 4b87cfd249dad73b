"""``synthesize --task function``: the engine's global search, then the minimax polish of :mod:`.function`.

The engine (:func:`linkagekit.synthesis.run.search`) searches :class:`~.function.FunctionObjective`
(branch, link ratios and, when free, the offsets) by differential evolution and CMA-ES; its
best design joins the Freudenstein starts (least squares of all pairs, exact fits of triples,
or an offset grid) that :func:`~.function.solve` polishes by least squares and minimax.  The
best design that meets every pair on one branch is returned.  Three pairs with fixed angle
scales, or pairs that Freudenstein's least squares meets exactly, are met without a search.

Examples
--------
>>> from linkagekit.synthesis.function_run import synthesize_function
>>> pairs = [40, 45, 50, 55, 60], [70, 76, 83, 91, 100]
>>> out = synthesize_function(*pairs, ground_length=180, restarts=1, generations=40)
>>> round(out.fit.max_error, 4), out.fit.valid, out.mechanism.drivers[0].name
(0.1076, True, 'crank')
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..geometry import FloatArray
from .function import POLISH_STARTS, FunctionFit, FunctionObjective, check_pairs, solve
from .optimize import Optimum, check_settings, search

if TYPE_CHECKING:
    from ..model import Mechanism

#: a fit this close (degrees) meets the pairs exactly, and the engine is not run
EXACT = 1e-9
#: the engine's goal: the largest output-angle error in radians (1e-9 deg)
GOAL = 1.7e-11


@dataclass(frozen=True)
class FunctionSynthesis:
    """What :func:`synthesize_function` found.

    Attributes
    ----------
    fit : FunctionFit
        The four-bar, its errors, branch, Grashof type and transmission angles.
    mechanism : Mechanism
        The four-bar as a mechanism (links ground, crank, coupler, output; driver ``crank``).
    engine : Optimum or None
        The engine's search (None when three pairs were met exactly without one).
    """

    fit: FunctionFit
    mechanism: Mechanism
    engine: Optimum | None


def synthesize_function(
    inputs: ArrayLike,
    outputs: ArrayLike,
    *,
    free_offsets: bool = False,
    ground_length: float = 1.0,
    units: str = "m",
    seed: int = 0,
    seconds: float = 10.0,
    restarts: int = 4,
    generations: int = 200,
    workers: int | None = None,
    source: str = "pairs",
    min_transmission: float = 0.0,
    scheduler: str | None = None,
    checkpoint: str | None = None,
) -> FunctionSynthesis:
    """A four-bar whose output angle follows ``outputs`` at ``inputs`` (degrees from the ground line), minimax.

    The engine's options (``seed``, ``seconds``, ``restarts``, ``generations``, ``workers``) are
    :func:`~linkagekit.synthesis.optimize.search`'s (and ``scheduler``, ``checkpoint``); the module's
    description says the method.
    ``min_transmission`` (degrees, default 0): the transmission angle stays within
    ``[min, 180 - min]`` from the first pair to the last.
    """
    x, y = check_pairs(inputs, outputs, source)
    check_settings(seconds=seconds, restarts=restarts, generations=generations, workers=workers)  # met at once too
    fit_from = partial(
        solve, inputs, outputs, free_offsets=free_offsets, ground_length=ground_length, source=source,
        min_transmission=min_transmission,
    )  # fmt: skip
    t0 = time.monotonic()
    first = fit_from()
    objective = FunctionObjective(x, y, float(ground_length), bool(free_offsets), units, float(min_transmission))
    if first.valid and first.max_error <= EXACT:  # met exactly: no search can do better
        return FunctionSynthesis(first, _mechanism(first, units), None)
    polish = time.monotonic() - t0  # the Freudenstein starts' polish; the last polishes the engine's answer alone
    opt = search(
        objective, seed=seed, seconds=_engine_seconds(seconds, polish), restarts=restarts, generations=generations,
        goal=GOAL, workers=workers, scheduler=scheduler, checkpoint=checkpoint,
    )  # fmt: skip
    fit = first
    if first.method != "exact":  # (three pairs met exactly but not valid: no start is polished)
        engine = fit_from(starts=[opt.x], freudenstein=False)  # the Freudenstein starts' answer is `first`
        fit = engine if engine.score < first.score else first
    return FunctionSynthesis(fit, _mechanism(fit, units), opt)


#: the engine's share of ``seconds`` at least (when the polish alone would take more)
ENGINE_SHARE = 0.25


def _engine_seconds(seconds: float, polish: float) -> float:
    """The engine's time: ``seconds`` less the polishes (the one done, ``polish``, of :data:`~.function.POLISH_STARTS`
    starts, and the last, of one).

    >>> _engine_seconds(12.0, 1.2), _engine_seconds(1.0, 0.9)
    (10.6, 0.25)
    """
    return max(seconds - polish * (1 + 1 / POLISH_STARTS), ENGINE_SHARE * seconds)


def _mechanism(fit: FunctionFit, units: str) -> Mechanism:
    from ..model import Mechanism

    return Mechanism.from_dict(fit.mechanism_dict(units))


def objective_vector(fit: FunctionFit, free: bool) -> FloatArray:
    """The :class:`~.function.FunctionObjective` design vector of a fit."""
    import math

    a, b, c, d = fit.lengths
    z = [float(fit.branch), math.log(a / d), math.log(b / d), math.log(c / d)]
    return np.array(z + [math.radians(fit.offsets[0]), math.radians(fit.offsets[1])] * free)
