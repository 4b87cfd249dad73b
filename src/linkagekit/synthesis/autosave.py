"""The checkpoint of a ``--topology auto`` run: what it has done, saved so that a killed run resumes.

An auto run has three phases (:mod:`~.auto`): the screen of the topologies, the four-bar
search of its own, and the local searches of the topologies the screen chose. The checkpoint
(a ``.npz`` file: NumPy arrays and one JSON header, read with ``allow_pickle=False`` and every
array's size known before it is read, as the engine's checkpoints are: :func:`~.optimize.read_archive`)
is written atomically after the screen, after the four-bar search, and after every round of
the local searches (:data:`ROUND_SECONDS` each), and with the time used on Ctrl-C. The same
command given the same file skips what is done, starts the local searches from their best
designs so far, and keeps the clock: the run ends when the time its runs have recorded
reaches ``--seconds``. A run killed outright loses the work and the time since its last
checkpoint (a screen or a four-bar search under way is done again).

Examples
--------
>>> import numpy as np, tempfile, os
>>> path = os.path.join(tempfile.mkdtemp(), "run.npz")
>>> ck = Checkpoint(path, "k", dims={"fourbar": 7}.__getitem__, fourbar_dim=9)
>>> s = Saved(elapsed=3.0, seeds=[5], order=["fourbar"], screen=[(0.1, np.zeros(7))])
>>> ck.save(s)
>>> back = ck.load()
>>> back.order, back.elapsed, back.screen[0][1].shape
(['fourbar'], 3.0, (7,))
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, shorten
from .optimize import STOPS, Outcome, _number, _Refused, read_archive, write_archive

#: the checkpoint's format name and version
KIND, VERSION = "linkagekit-auto-checkpoint", 1
#: seconds of local searches between two checkpoints
ROUND_SECONDS = 10.0
#: topologies an auto run searches at most (the checkpoint holds no more)
MOST_SEARCHED = 64


@dataclass
class Best:
    """One topology's best design of the local searches so far, and what they cost."""

    x: np.ndarray
    cost: float
    starts: int
    designs: int
    seconds: float

    @classmethod
    def first(cls, out: Outcome) -> Best:
        """The best of a first round's outcome."""
        return cls(out.x, out.cost, out.restarts, out.evaluations, out.seconds)

    def merged(self, out: Outcome) -> Best:
        """This best and one more round's outcome."""
        x, cost = (self.x, self.cost) if self.cost <= out.cost else (out.x, out.cost)
        return Best(x, cost, self.starts + out.restarts, self.designs + out.evaluations, self.seconds + out.seconds)

    def outcome(self) -> Outcome:
        return Outcome(self.x, self.cost, self.starts, 0, self.designs, self.seconds, "time")


@dataclass
class Saved:
    """What an auto run has done (a new run: nothing).

    Attributes
    ----------
    elapsed : float
        Seconds its runs have taken.
    seeds : list of int, optional
        The local searches' seeds, one per topology searched.
    order : list of str, optional
        The topologies the screen chose (None: the screen is not done).
    screen : list of (float, ndarray)
        Their screen figures and designs.
    fourbar : Outcome, optional
        The four-bar search's outcome (None: not done).
    best : list of Best or None
        Each chosen topology's best design of the local searches so far.
    rounds : int
        Rounds of local searches done.
    """

    elapsed: float = 0.0
    seeds: list[int] | None = None
    order: list[str] | None = None
    screen: list[tuple[float, np.ndarray]] = field(default_factory=list)
    fourbar: Outcome | None = None
    best: list[Best | None] = field(default_factory=list)
    rounds: int = 0


@dataclass(frozen=True)
class Checkpoint:
    """An auto run's checkpoint file.

    Attributes
    ----------
    path : str
    key : str
        The run's problem and settings (a digest): a checkpoint of another run is refused.
    dims : callable
        A topology's name -> the length of its design vector (KeyError: no topology of the run).
    fourbar_dim : int
        The four-bar search's design length.
    """

    path: str
    key: str
    dims: Callable[[str], int]
    fourbar_dim: int

    def save(self, s: Saved) -> None:
        """Write ``s`` atomically."""
        arrays = {f"screen_x_{i}": np.asarray(x, float) for i, (_, x) in enumerate(s.screen)}
        arrays.update({f"best_x_{i}": b.x for i, b in enumerate(s.best) if b is not None})
        four = s.fourbar
        if four is not None:
            arrays["fourbar_x"] = np.asarray(four.x, float)
        header = {
            "format": f"{KIND}/{VERSION}",
            "key": self.key,
            "elapsed": s.elapsed,
            "seeds": s.seeds,
            "order": s.order,
            "screen": [float(f) for f, _ in s.screen],
            "fourbar": None if four is None else _outcome_numbers(four),
            "best": [None if b is None else [b.cost, b.starts, b.designs, b.seconds] for b in s.best],
            "rounds": s.rounds,
        }
        write_archive(Path(self.path), _finite(header), arrays)

    def load(self) -> Saved | None:
        """The saved progress, or None when the file does not exist yet (refused: one line naming the file)."""
        got: list[Saved] = []

        def expected(header: dict[str, Any]) -> dict[str, Any]:
            if header.get("key") != self.key:
                raise InputError(f"{self.path}: this checkpoint belongs to another run (other targets or options)")
            got.append(self._parsed(header))
            return self._shapes(got[0])

        read = read_archive(Path(self.path), KIND, VERSION, expected)
        if read is None:
            return None
        try:
            return _with_arrays(got[0], read[1])
        except InputError as e:
            raise InputError(f"{self.path}: {e}") from None

    def _parsed(self, h: dict[str, Any]) -> Saved:
        """The header's numbers and names, each checked (the arrays come later)."""
        order = h["order"]
        if order is not None and not (isinstance(order, list) and 0 < len(order) <= MOST_SEARCHED):
            raise _Refused("'order' is not a list of topologies")
        k = len(order or [])
        for name in order or []:
            self._dim(name)
        seeds, screen, best = h["seeds"], h["screen"], h["best"]
        if order is not None and not (isinstance(seeds, list) and len(seeds) == k):
            raise _Refused(f"'seeds' is not a list of {k} seeds")
        if not (isinstance(screen, list) and len(screen) == k and isinstance(best, list) and len(best) in (0, k)):
            raise _Refused(f"'screen' and 'best' are not lists of {k}")
        return Saved(
            elapsed=_number(h["elapsed"], "elapsed", 0.0, 1e12, float),
            seeds=None if order is None else [_number(x, "seed", 0, 2**63) for x in seeds],
            order=None if order is None else [str(n) for n in order],
            screen=[(_number(f, "screen", 0.0, np.inf, float), np.zeros(0)) for f in screen],
            fourbar=None if h["fourbar"] is None else _outcome(h["fourbar"]),
            best=[None if b is None else _best(b) for b in best],
            rounds=_number(h["rounds"], "rounds", 0, 1e12),
        )

    def _dim(self, name: Any) -> int:
        try:
            return int(self.dims(str(name)))
        except KeyError:
            raise _Refused(f"{shorten(repr(name))} is no topology of this run") from None

    def _shapes(self, s: Saved) -> dict[str, Any]:
        """Every array the checkpoint must hold: name -> (smallest shape, largest shape)."""
        dims = [((self._dim(n),),) * 2 for n in s.order or []]
        out: dict[str, Any] = {f"screen_x_{i}": d for i, d in enumerate(dims)}
        out.update({f"best_x_{i}": dims[i] for i, b in enumerate(s.best) if b is not None})
        if s.fourbar is not None:
            out["fourbar_x"] = ((self.fourbar_dim,),) * 2
        return out


#: the largest magnitude of a saved design's number (a mechanism file holds none above 1e12)
MOST = 1e12


def _with_arrays(s: Saved, arrays: dict[str, np.ndarray]) -> Saved:
    for name, a in arrays.items():  # a hand-edited or damaged file: NaN reached the targets' check, 1e300 the writer
        if not np.all(np.isfinite(a)) or np.max(np.abs(a), initial=0.0) > MOST:
            raise InputError(f"not a usable linkagekit checkpoint (array {name} holds a number that is no design's)")
    s.screen = [(f, np.asarray(arrays[f"screen_x_{i}"], float)) for i, (f, _) in enumerate(s.screen)]
    for i, b in enumerate(s.best):
        if b is not None:
            b.x = np.asarray(arrays[f"best_x_{i}"], float)
    if s.fourbar is not None:
        s.fourbar = Outcome(np.asarray(arrays["fourbar_x"], float), *_fields(s.fourbar))
    return s


def _fields(o: Outcome) -> tuple[Any, ...]:
    return o.cost, o.restarts, o.generations, o.evaluations, o.seconds, o.stopped_by


def _outcome_numbers(o: Outcome) -> list[Any]:
    return [float(o.cost), int(o.restarts), int(o.generations), int(o.evaluations), float(o.seconds), o.stopped_by]


def _outcome(v: Any) -> Outcome:
    """The four-bar search's outcome from its header entry (its design comes with the arrays)."""
    if not (isinstance(v, list) and len(v) == 6 and v[5] in STOPS):
        raise _Refused("'fourbar' is not an outcome")
    cost = _number(v[0], "fourbar cost", 0.0, np.inf, float)
    restarts, generations, designs = (_number(x, "fourbar count", 0, 1e18) for x in v[1:4])
    seconds = _number(v[4], "fourbar seconds", 0.0, 1e12, float)
    return Outcome(np.zeros(0), cost, restarts, generations, designs, seconds, str(v[5]))


def _best(v: Any) -> Best:
    if not (isinstance(v, list) and len(v) == 4):
        raise _Refused("a 'best' entry is not [cost, starts, designs, seconds]")
    cost = _number(v[0], "best cost", 0.0, np.inf, float)
    counts = _number(v[1], "starts", 0, 1e18), _number(v[2], "designs", 0, 1e18)
    return Best(np.zeros(0), cost, *counts, _number(v[3], "best seconds", 0.0, 1e12, float))


def _finite(header: dict[str, Any]) -> dict[str, Any]:
    """``header`` with an infinite cost written as a large number (JSON has no infinity)."""

    def fix(v: Any) -> Any:
        if isinstance(v, float) and not np.isfinite(v):
            return 1e308
        if isinstance(v, list):
            return [fix(x) for x in v]
        return v

    return {k: fix(v) for k, v in header.items()}
