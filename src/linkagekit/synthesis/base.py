r"""What the synthesis engine searches: the :class:`Objective` interface and its :class:`Score`.

The engine (:func:`linkagekit.synthesis.optimize.optimize`: differential evolution and
CMA-ES over whole generations, a least-squares polish, restarts, checkpoints, local worker
processes or a Dask cluster) knows nothing of points, poses or angles. It sees a box of
design vectors and an object that scores batches of them. Path generation
(:class:`~linkagekit.synthesis.objective.Problem`), motion generation
(:mod:`linkagekit.synthesis.motion`), function generation and a user's own objective are
such objects.

What an objective provides
--------------------------
``bounds``
    Lower and upper bounds of the design vector (``dim`` follows from them).
``score(X)``
    The search's score of a batch ``X`` (N, dim) of designs, vectorized over the designs:
    a :class:`Score` with the ``cost`` the search lowers, the ``error`` (the largest
    error of the design, in the objective's relative measure: what the goal and the
    choice of the best design compare) and the ``violation`` (0 for a feasible design).
``check(X)``
    The dense final check a result is reported by (one branch, no jumps, transmission
    angle, a full turn where asked): a :class:`Score` too. The default is ``score``.
``fingerprint()``
    A short digest of everything that defines the problem, so that a checkpoint is only
    continued by the run it belongs to.
``residuals(X)``
    (N, r) residuals whose squared sum is the cost, for the local least-squares polish.
    The default is ``sqrt(cost)``, which works but polishes slowly: give the real ones.
``mechanism(x)``
    The design as a :class:`~linkagekit.model.Mechanism` (optional: the engine never
    calls it; the task that runs the engine does).

Optional refinements: ``scale`` (the designs' typical length: finite-difference steps and
the test of two designs being the same are relative to it), ``variants()`` (cheaper
versions of the objective the searches may take turns with; the polish and the choice of
the best always use the objective itself), ``polish_methods`` (the two bounded methods of
:func:`scipy.optimize.least_squares`, the better first).

An objective must be picklable (it is sent to worker processes and to a Dask cluster), so
keep it a plain (data)class of arrays and numbers, not a closure.

Examples
--------
A toy objective: the point of the unit box nearest to ``(0.3, 0.7)``, infeasible where
``x0 > 0.9``:

>>> import numpy as np
>>> class Toy(Objective):
...     bounds = (np.zeros(2), np.ones(2))
...     def score(self, X):
...         d = np.abs(X - [0.3, 0.7])
...         return Score(np.sum(d * d, axis=1), d.max(axis=1), np.maximum(X[:, 0] - 0.9, 0.0))
...     def residuals(self, X):
...         return X - [0.3, 0.7]
...     def fingerprint(self):
...         return "toy"
>>> err, cost = Toy().measure(np.array([[0.3, 0.7], [0.95, 0.7]]))
>>> err.tolist()
[0.0, inf]
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..geometry import FloatArray

if TYPE_CHECKING:
    from ..model import Mechanism


@dataclass(frozen=True)
class Score:
    """Scores of N designs.

    Attributes
    ----------
    cost : ndarray (N,)
        What the search lowers (a smooth measure, with an exact penalty for the violation).
    error : ndarray (N,)
        The design's largest error in the objective's relative measure (dimensionless,
        e.g. a distance over the targets' diagonal); ``inf`` or NaN where it has none.
    violation : ndarray (N,)
        How far from feasible the design is: 0 for a feasible one.
    """

    cost: FloatArray
    error: FloatArray
    violation: FloatArray


class Objective(ABC):
    """What to synthesise, as the engine sees it (see the module's description).

    Subclass it and give ``bounds``, :meth:`score` and :meth:`fingerprint`; give
    :meth:`residuals` for a fast polish and :meth:`check` for a dense final check.
    """

    @property
    @abstractmethod
    def bounds(self) -> tuple[FloatArray, FloatArray]:
        """Lower and upper bounds (dim,) of the design vector."""

    @property
    def dim(self) -> int:
        """Length of the design vector."""
        return len(self.bounds[0])

    @property
    def scale(self) -> float:
        """The designs' typical length: finite-difference steps are ``1e-7 * scale``."""
        return 1.0

    @property
    def polish_methods(self) -> tuple[str, str]:
        """Both bounded methods of :func:`scipy.optimize.least_squares`, the one that suits the objective first."""
        return ("trf", "dogbox")

    @abstractmethod
    def score(self, X: FloatArray) -> Score:
        """The search's score of designs ``X`` (N, dim): one vectorized call, no loop per design."""

    def cost(self, X: FloatArray) -> FloatArray:
        """The cost (N,) of designs ``X`` (N, dim): what a worker computes for a generation."""
        return self.score(X).cost

    def residuals(self, X: FloatArray) -> FloatArray:
        """Residuals (N, r) of designs ``X`` whose squared sum is the cost (the local polish's)."""
        return np.sqrt(np.maximum(self.cost(X), 0.0))[:, None]

    def check(self, X: FloatArray) -> Score:
        """The dense check a result is reported by (default: :meth:`score`)."""
        return self.score(X)

    def measure(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(error, cost)`` of designs ``X`` by :meth:`check`; the error is ``inf`` for an infeasible design."""
        s = self.check(np.atleast_2d(np.asarray(X, float)))
        ok = np.isfinite(s.error) & (s.violation == 0)
        return np.where(ok, s.error, np.inf), np.asarray(s.cost, float)

    @abstractmethod
    def fingerprint(self) -> str:
        """A digest of everything that defines the problem (to match a checkpoint to its run)."""

    def variants(self) -> tuple[Objective, ...]:
        """The objective and cheaper versions of it that searches may use in turn (default: itself only)."""
        return (self,)

    def transmission(self, X: FloatArray) -> FloatArray:
        """The smallest transmission angle (degrees) of designs ``X`` by the dense check; NaN: none (``--pareto``)."""
        return np.full(len(np.atleast_2d(X)), np.nan)

    def raised(self, degrees: float) -> Objective | None:
        """The objective with its transmission bound ``degrees`` higher (``--pareto``'s searches); None: no bound."""
        return None

    def mechanism(self, x: FloatArray) -> Mechanism:
        """The design ``x`` (dim,) as a mechanism (needed by the task that writes a file)."""
        raise NotImplementedError(f"{type(self).__name__} does not build a mechanism")


def digest(*parts: Any) -> str:
    """A 16-hex-digit digest of arrays and ``repr``-able values: the usual :meth:`Objective.fingerprint`.

    >>> digest(np.arange(3.0), "motion") == digest(np.arange(3.0), "motion") != digest(np.arange(3.0), "path")
    True
    """
    import hashlib

    h = hashlib.sha256()
    for p in parts:
        if isinstance(p, np.ndarray):
            h.update(np.ascontiguousarray(p).tobytes())
        else:
            h.update(repr(p).encode())
    return h.hexdigest()[:16]
