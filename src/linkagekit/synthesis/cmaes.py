r"""CMA-ES over a box, one whole generation at a time, with a state that is plain arrays.

The covariance matrix adaptation evolution strategy (Hansen, "The CMA Evolution Strategy: A
Tutorial", arXiv:1604.00772, the default parameters of its table 1), in ``(mu/mu_w, lambda)``
form with rank-one and rank-mu updates and cumulative step-size adaptation:

.. math::

    x_k = m + \sigma B D z_k, \quad z_k \sim N(0, I), \qquad
    m' = m + \sigma \textstyle\sum_i w_i y_{i:\lambda}, \quad y = (x - m) / \sigma,

    p_\sigma' = (1 - c_\sigma) p_\sigma + \sqrt{c_\sigma (2 - c_\sigma) \mu_w}\, C^{-1/2} \langle y \rangle_w,
    \qquad \sigma' = \sigma \exp\Big(\frac{c_\sigma}{d_\sigma}\Big(\frac{|p_\sigma'|}{E|N(0, I)|} - 1\Big)\Big),

    p_c' = (1 - c_c) p_c + h_\sigma \sqrt{c_c (2 - c_c) \mu_w}\, \langle y \rangle_w,

    C' = (1 - c_1 - c_\mu + (1 - h_\sigma) c_1 c_c (2 - c_c)) C + c_1 p_c' p_c'^T
         + c_\mu \textstyle\sum_i w_i y_{i:\lambda} y_{i:\lambda}^T.

The search runs in the unit box ``[0, 1]^n`` (the design box scaled); a sample outside it is
reflected back in (``u -> 1 - |(u mod 2) - 1|``), so every design evaluated is within the
bounds and the strategy itself sees no boundary.

Why not the ``cma`` package: a synthesis run must save the optimizer's whole state after
every generation in a file that is read without executing anything, and continue from it to
the same result; ``cma`` keeps its state in objects that only pickle can restore and draws
from NumPy's global random state. Here the state is :meth:`CMAES.state` (arrays and numbers)
and the random numbers come from the run's own generator. ``tests/test_cmaes.py`` checks it
against ``cma`` on standard functions.

Examples
--------
>>> import numpy as np
>>> es = CMAES(np.full(4, 0.9), 0.2, np.random.default_rng(1))
>>> for _ in range(150):
...     X = es.ask()
...     es.tell(X, np.sum((X - 0.3) ** 2, axis=1))
>>> bool(np.allclose(es.best_x, 0.3, atol=1e-6))
True
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..geometry import FloatArray

#: the numbers of a state, beside its arrays
_SCALARS = ("sigma", "generation", "evaluations", "best_f", "lam")
_ARRAYS = ("mean", "C", "ps", "pc", "best_x", "history", "last_X", "last_f")


def reflect(u: FloatArray) -> FloatArray:
    """``u`` folded into ``[0, 1]`` by reflection at the faces (period 2)."""
    return 1.0 - np.abs(np.mod(u, 2.0) - 1.0)


class CMAES:
    """The strategy's state and its ask/tell steps.

    Parameters
    ----------
    mean : ndarray (n,)
        Start of the search, in the unit box.
    sigma : float
        Initial step size (unit-box lengths).
    rng : numpy.random.Generator
        Source of every random number (its state is part of a checkpoint).
    lam : int, optional
        Population size (default ``4 + floor(3 ln n)``).
    """

    def __init__(self, mean: np.ndarray, sigma: float, rng: np.random.Generator, lam: int | None = None) -> None:
        n = len(mean)
        self.n = n
        self.rng = rng
        self.lam = int(lam or 4 + int(3 * np.log(n)))
        mu = self.lam // 2
        w = np.log(mu + 0.5) - np.log(np.arange(1, mu + 1))
        self.weights = w / w.sum()
        self.mueff = 1.0 / np.sum(self.weights**2)
        me = self.mueff
        self.cc = (4 + me / n) / (n + 4 + 2 * me / n)
        self.cs = (me + 2) / (n + me + 5)
        self.c1 = 2 / ((n + 1.3) ** 2 + me)
        self.cmu = min(1 - self.c1, 2 * (me - 2 + 1 / me) / ((n + 2) ** 2 + me))
        self.damps = 1 + 2 * max(0.0, np.sqrt((me - 1) / (n + 1)) - 1) + self.cs
        self.chi_n = np.sqrt(n) * (1 - 1 / (4 * n) + 1 / (21 * n * n))
        self.mean = np.asarray(mean, float).copy()
        self.sigma = float(sigma)
        self.sigma0 = float(sigma)
        self.C = np.eye(n)
        self.ps = np.zeros(n)
        self.pc = np.zeros(n)
        self.generation = 0
        self.evaluations = 0
        self.best_x = reflect(self.mean)
        self.best_f = np.inf
        self.history = np.zeros(0)  # best cost of each generation, the latest last
        self.last_X = np.zeros((0, n))  # the last generation, in the box, best first
        self.last_f = np.zeros(0)
        self._y = np.zeros((0, n))

    # ------------------------------------------------------------------ steps
    def _eig(self) -> tuple[np.ndarray, np.ndarray]:
        C = (self.C + self.C.T) / 2
        d2, B = np.linalg.eigh(C)
        return B, np.sqrt(np.maximum(d2, 1e-300))

    def ask(self) -> np.ndarray:
        """The next generation: ``lam`` designs (lam, n) in the unit box."""
        B, D = self._eig()
        z = self.rng.standard_normal((self.lam, self.n))
        self._y = (z * D) @ B.T
        return reflect(self.mean + self.sigma * self._y)

    def tell(self, X: np.ndarray, f: np.ndarray) -> None:
        """Update from the generation ``X`` (as returned by :meth:`ask`) and its costs ``f``."""
        f = np.where(np.isfinite(f), f, np.inf)
        order = np.argsort(f, kind="stable")
        n, mu = self.n, len(self.weights)
        y = self._y[order[:mu]]
        yw = self.weights @ y
        B, D = self._eig()
        c_inv_half = (B / D) @ B.T
        self.mean = self.mean + self.sigma * yw
        cs, cc, c1, cmu, me = self.cs, self.cc, self.c1, self.cmu, self.mueff
        self.ps = (1 - cs) * self.ps + np.sqrt(cs * (2 - cs) * me) * (c_inv_half @ yw)
        g = self.generation + 1
        norm_ps = float(np.linalg.norm(self.ps))
        hsig = norm_ps / np.sqrt(1 - (1 - cs) ** (2 * g)) / self.chi_n < 1.4 + 2 / (n + 1)
        self.pc = (1 - cc) * self.pc + hsig * np.sqrt(cc * (2 - cc) * me) * yw
        rank_mu = (y.T * self.weights) @ y
        self.C = (
            (1 - c1 - cmu + (1 - hsig) * c1 * cc * (2 - cc)) * self.C + c1 * np.outer(self.pc, self.pc) + cmu * rank_mu
        )
        self.sigma *= float(np.exp(min(1.0, (cs / self.damps) * (norm_ps / self.chi_n - 1))))
        self.generation = g
        self.evaluations += len(X)
        if f[order[0]] < self.best_f:
            self.best_f, self.best_x = float(f[order[0]]), np.array(X[order[0]], float)
        self.history = np.append(self.history, f[order[0]])[-self.history_length :]
        self.last_X, self.last_f = np.array(X[order], float), np.array(f[order], float)

    # ------------------------------------------------------------------ stopping
    @property
    def history_length(self) -> int:
        return 10 + int(np.ceil(30 * self.n / self.lam))

    def stop(self, tolfun: float = 1e-14, tolx: float = 1e-12, max_condition: float = 1e14) -> str | None:
        """Why the strategy has converged or stalled (None while it has not)."""
        if self.generation == 0:
            return None
        d = np.sqrt(np.maximum(np.diag(self.C), 0.0))
        if self.sigma * float(d.max()) < tolx:
            return "tolx"
        full = len(self.history) >= self.history_length
        if full and np.ptp(np.concatenate([self.history, self.last_f[np.isfinite(self.last_f)]])) < tolfun:
            return "tolfun"
        ev = np.linalg.eigvalsh((self.C + self.C.T) / 2)
        if ev.min() <= 0 or ev.max() / ev.min() > max_condition:
            return "condition"
        if self.sigma * float(d.max()) > 1e3 * self.sigma0:
            return "diverged"
        return None

    # ------------------------------------------------------------------ state
    def state(self) -> dict[str, Any]:
        """Everything that changes between generations: arrays, numbers and the generator's state."""
        out: dict[str, Any] = {k: np.array(getattr(self, k)) for k in _ARRAYS}
        out.update({k: getattr(self, k) for k in _SCALARS})
        out["rng"] = self.rng.bit_generator.state
        return out

    def restore(self, saved: dict[str, Any]) -> None:
        """Continue from :meth:`state` (of a strategy made with the same arguments)."""
        for k in _ARRAYS:
            setattr(self, k, np.array(saved[k], float))
        self.last_X = self.last_X.reshape(-1, self.n)
        self.sigma = float(saved["sigma"])
        self.generation = int(saved["generation"])
        self.evaluations = int(saved["evaluations"])
        self.best_f = float(saved["best_f"])
        if int(saved["lam"]) != self.lam:
            raise ValueError(f"population {saved['lam']} saved, {self.lam} expected")
        self.rng.bit_generator.state = saved["rng"]
