"""How much a design's accuracy depends on making it exactly: the tolerance line of ``synthesize``.

A path generator is built with every joint a little off its place. Each joint but the tracer is
moved in turn by :data:`SHARE` of the targets' diagonal, along +x, -x, +y and -y; each of those
designs is solved over the written sweep (:data:`SAMPLES` inputs, one batch of designs), and its
max error is each target's distance to its curve (the chords at its nearest sample), the largest
over the targets. The worst of them
says how a design answers a workshop's error: a sound four-bar's max error moves by about the
step, while one with its ground pivots a hair apart and the tracer far out on a short coupler
(the shape an optimiser finds where the targets ask for more than a four-bar can do) loses
several times its accuracy.

Examples
--------
>>> import numpy as np
>>> import linkagekit as lk
>>> mech = lk.load("examples/seed000_fourbar.yaml")
>>> curve = lk.analyze(mech, {"crank": np.linspace(0, 360, 12, endpoint=False)}).point("P")
>>> tol = tolerance(mech, curve, "P")
>>> tol.joint in mech.joint_names and tol.worst > 0
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .tracer import chords_to

#: how far one joint is moved, as a fraction of the targets' bounding-box diagonal
SHARE = 1e-3
#: inputs over the sweep each moved design is solved at
SAMPLES = 1441


@dataclass(frozen=True)
class Tolerance:
    """The worst of the designs with one joint moved.

    Attributes
    ----------
    step : float
        How far each joint was moved (the file's length unit).
    worst : float
        The largest max error of those designs (inf: one of them does not assemble over the sweep).
    joint : str
        The joint whose move gave it.
    exact : float
        The max error of the design as it is, measured alike (the same samples of its sweep).
    """

    step: float
    worst: float
    joint: str
    exact: float

    @property
    def gain(self) -> float:
        """How many times the step the worst move adds to the max error."""
        return (self.worst - self.exact) / self.step


def tolerance(mech: Any, targets: np.ndarray, tracer: str, share: float = SHARE) -> Tolerance:
    """The worst max error of ``mech`` with one joint (not ``tracer``) moved by ``share`` of the ``targets``'
    diagonal (complex, (m,)), over the sweep of its first driver. The links are the pose's (a file with exact
    ``lengths``, which synthesis never writes, keeps them whatever the move)."""
    from ..api import analyze

    T = np.asarray(targets, complex)
    step = share * float(np.hypot(np.ptp(T.real), np.ptp(T.imag)))
    names = [j for j in mech.joint_names if j != tracer]
    moves = [(tracer, 0, 0.0)] + [(j, axis, sign) for j in names for axis in (0, 1) for sign in (1.0, -1.0)]
    poses = np.repeat(mech.pose_array()[None], len(moves), axis=0)  # the first as it is
    for i, (j, axis, sign) in enumerate(moves):
        poses[i, mech.joint_names.index(j), axis] += sign * step
    res = analyze(mech, {mech.drivers[0].name: _sweep(mech)}, poses=poses, rates=False, dynamics=False)
    P = res.point(tracer)  # (moves, samples)
    worst = np.where(np.all(res.assembled, axis=1), np.max(_distances(P, T), axis=1), np.inf)
    i = 1 + int(np.argmax(worst[1:]))
    return Tolerance(step, float(worst[i]), moves[i][0], float(worst[0]))


def _distances(P: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Each target's distance (D, m) to the polyline through each row of samples ``P`` (D, n): to its nearest
    sample's two chords (a sample alone is up to half a chord off: on an accurate design that was all the error).

    >>> _distances(np.array([[0, 1, 2 + 0j]]), np.array([0.5 + 0.1j, 3 + 0j])).round(12).tolist()
    [[0.1, 1.0]]
    """
    rows = np.arange(P.shape[0])[:, None]
    with np.errstate(invalid="ignore"):
        k = np.argmin(np.abs(P[:, None, :] - T[None, :, None]), axis=2)  # (D, m)
        near = np.abs(P[rows, k] - T[None, :]) ** 2
    return np.asarray(np.sqrt(np.fmin(near, chords_to(P, np.isfinite(P), T, k))))


def _sweep(mech: Any) -> np.ndarray:
    """:data:`SAMPLES` inputs from the first to the last of the first driver's sweep (the file's, or its default)."""
    values = np.asarray(mech.drivers[0].sweep.values(), float)
    return np.linspace(values[0], values[-1], SAMPLES)
