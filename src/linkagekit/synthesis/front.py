"""The trade between accuracy and transmission (``synthesize --pareto``): the designs no other beats in both.

A design *dominates* another when its max error is no larger and its smallest transmission angle no
smaller, one of the two strictly. :func:`non_dominated` keeps those no design dominates (one of
equal pairs); :func:`short_list` picks a few of them spread over the transmission angles, from the
most accurate to the best-transmitting.

Examples
--------
>>> import numpy as np
>>> err = np.array([0.01, 0.02, 0.015, 0.03, 0.02])
>>> mu = np.array([20.0, 35.0, 22.0, 30.0, 35.0])
>>> non_dominated(err, mu).tolist()   # 0.03 at 30 deg is beaten by 0.02 at 35; the two (0.02, 35) are one
[0, 2, 1]
"""

from __future__ import annotations

import numpy as np

#: designs of the short list at most
SHORT_LIST = 6


def non_dominated(error: np.ndarray, transmission: np.ndarray) -> np.ndarray:
    """Indices of the designs no other dominates, by increasing error (and transmission); one of equal pairs.

    Sorted by error, then by decreasing transmission, a design is kept when its transmission
    angle is larger than that of every design before it: every design before it is at least as
    accurate, so none of those dominates it only if none transmits as well.
    """
    e, m = np.asarray(error, float), np.asarray(transmission, float)
    order = np.lexsort((-m, e))
    best_before = np.maximum.accumulate(np.concatenate([[-np.inf], m[order]]))[:-1]
    return np.asarray(order[m[order] > best_before], int)


def short_list(error: np.ndarray, transmission: np.ndarray, k: int = SHORT_LIST) -> np.ndarray:
    """At most ``k`` of the non-dominated designs: the most accurate, the best-transmitting, and between them
    the most accurate one at or above each of ``k`` evenly spaced transmission angles.

    >>> short_list(np.array([1.0, 2, 3, 4, 5]), np.array([20.0, 21, 22, 40, 60]), k=3).tolist()
    [0, 3, 4]
    """
    front = non_dominated(error, transmission)
    m = np.asarray(transmission, float)[front]  # increasing along the front
    wanted = np.linspace(m[0], m[-1], max(k, 2))
    at = np.searchsorted(m, wanted - 1e-9 * (1 + abs(m[-1])))
    return np.asarray(front[np.unique(np.minimum(at, len(front) - 1))], int)
