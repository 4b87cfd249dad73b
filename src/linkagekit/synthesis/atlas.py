"""An atlas of normalised four-bar curves: built once, cached, looked up in milliseconds.

Each entry is a four-bar of the built-in ``fourbar`` design space (joints A, B, C, D, P at a
pose; :mod:`~linkagekit.synthesis.space`) moved, turned and scaled so that its tracer's curve
is in the normal position of :mod:`~linkagekit.synthesis.descriptors` (centroid 0, RMS radius
1, first harmonic's ellipse along the real axis), with that curve's descriptor. A curve of
targets with descriptor ``c + s w`` is then matched by the nearest descriptors, and an entry's
joints ``J`` put onto the targets as ``c + s J`` (``-s`` when the targets' other descriptor,
:func:`~.descriptors.flipped`, was the nearer).

Entries (:func:`make_chunk`, all of a chunk at once through the design axis)
    *closed*: a crank that turns fully (crank-rockers and double-cranks, both branches), its
    curve over one turn; *open*: any four-bar (Grashof or not) over a range of at least 90
    degrees of its crank where it assembles on one branch, the curve traced forth and back.
    Every entry keeps its transmission angle at least ``BUILD_TRANSMISSION`` over its sweep and
    stores the smallest one, so a query can ask for more.
Cache (:func:`build`, :func:`load`)
    One ``.npy`` file of float32 rows (``COLUMNS``) and a last marker row, named by the
    format version and the size, in ``LINKAGEKIT_CACHE_DIR`` or the user's cache directory
    (``platformdirs``). It is built in chunks, each written to a temporary file and renamed
    into place (an interrupted build resumes from its chunks; two processes building at once
    write the same chunks), then assembled into a temporary file renamed over the atlas. It is
    read with ``allow_pickle=False`` and memory-mapped; a file whose shape, type or marker is
    wrong is rebuilt. Temporary files of the atlas older than ``STALE`` seconds (left by a
    build killed by a signal, where ``finally`` never runs) are removed by the next build or load;
    a directory where the atlas file goes is an :class:`AtlasError` before anything is built.
Seeding a search (:func:`first_answer`)
    The ``NEAREST`` nearest entries that fit the problem's bounds are placed on the targets,
    refitted to them (:func:`refit`), posed with the tracer at its point nearest the first
    target (with ``shape_only``: put on the fixed ground pivots instead, :func:`on_pivots`),
    scored by the problem's own objective; the best few are polished by least squares
    (:func:`~.optimize.polish`), and the best of all, by the problem's dense check, is the
    atlas's answer; the designs, best first, seed the search (``optimize(..., initial=...)``).
    A partial problem (its sweep free) looks up the open entries: each one's sweep becomes the
    span of the design's sweep, its pose the share ``f`` of it (:func:`posed`).

``LINKAGEKIT_ATLAS_SIZE=0`` turns the atlas off.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError, LinkageError
from . import descriptors as de

if TYPE_CHECKING:
    from .objective import Problem
    from .space import DesignSpace

#: the atlas's format: a new number rebuilds every cached atlas
VERSION = 1
#: entries by default (``LINKAGEKIT_ATLAS_SIZE`` sets another)
SIZE = 1 << 20
#: entries per chunk of the build (and per temporary file)
CHUNK = 1 << 14
#: designs per call of the solver (small batches stay in cache)
SOLVE_BATCH = 512
#: samples of the crank along an entry's curve
SAMPLES = 96
#: share of the entries that are closed curves (the crank turns fully)
CLOSED_SHARE = 0.5
#: smallest transmission angle of every entry over its sweep (degrees)
BUILD_TRANSMISSION = 15.0
#: an open entry's crank sweeps at least this much (radians; a partial sweep's least, ``--partial``)
MIN_SWEEP = np.pi / 2
#: columns of a row: the descriptor, its squared norm, the joints A B C D P (x, y), the sweep, the
#: smallest transmission angle, the kind (0 closed, 1 open)
NDESC = de.size()
DESC, NORM, JOINTS, SWEEP, MU, KIND = 0, NDESC, NDESC + 1, NDESC + 11, NDESC + 12, NDESC + 13
COLUMNS = NDESC + 14
#: the last row of a whole file
MARKER = np.float32(1000.25 + VERSION)
#: entries looked up, placed and scored for a search's start; of them, polished
NEAREST, POLISHED, POLISH_NFEV = 256, 3, 60
#: entries looked up to find ``NEAREST`` that fit the problem's bounds (more when too few do); rounds of
#: their refit to the targets
LOOKED_UP, REFITS = (8192, 65536), 3
#: entries nearest in shape that the dense check measures whatever their search cost
CHECKED_NEAREST = 4
#: a temporary file of the atlas this old (seconds since written) has no writer left: a chunk is written,
#: and the atlas assembled, in seconds
STALE = 15 * 60.0
#: the box lengths are drawn from (log-uniform, in ground lengths) and the coupler point's frame
CRANK, LINKS, COUPLER_U, COUPLER_V = (0.05, 3.0), (0.1, 5.0), (-1.5, 2.5), (-2.0, 2.0)

Tick = Callable[[int, int], None]


class AtlasError(LinkageError):
    """The atlas cannot be built or read where it is cached."""


# ---------------------------------------------------------------------- where
def directory() -> Path:
    """The cache directory: ``LINKAGEKIT_CACHE_DIR`` or ``platformdirs.user_cache_dir("linkagekit")``."""
    given = os.environ.get("LINKAGEKIT_CACHE_DIR")
    if given:
        return Path(given)
    import platformdirs

    return Path(platformdirs.user_cache_dir("linkagekit"))


def size() -> int:
    """Entries of the atlas: ``LINKAGEKIT_ATLAS_SIZE`` or ``SIZE``, rounded down to whole chunks of ``CHUNK``.

    Below ``CHUNK`` entries the atlas is one chunk of them (at least 64). 0 turns the atlas off
    (searches start as without one).

    >>> saved = os.environ.get("LINKAGEKIT_ATLAS_SIZE")
    >>> os.environ["LINKAGEKIT_ATLAS_SIZE"] = str(2 * CHUNK + 100); size() == 2 * CHUNK
    True
    >>> os.environ["LINKAGEKIT_ATLAS_SIZE"] = "1000"; size()
    1000
    >>> _ = os.environ.pop("LINKAGEKIT_ATLAS_SIZE") if saved is None else os.environ.update(LINKAGEKIT_ATLAS_SIZE=saved)
    """
    raw = os.environ.get("LINKAGEKIT_ATLAS_SIZE", "")
    try:
        n = int(raw) if raw else SIZE
    except ValueError:
        n = -1
    if n < 0:
        raise InputError(f"LINKAGEKIT_ATLAS_SIZE: expected a whole number of entries (0: no atlas), got {raw!r}")
    if n == 0:
        return 0
    n = max(n, 64)
    per = chunk_entries(n)
    return (n // per) * per


def chunk_entries(n: int) -> int:
    """Entries per chunk of an atlas of ``n``."""
    return min(CHUNK, max(64, n))


def path(n: int | None = None) -> Path:
    """The atlas file of ``n`` entries (default :func:`size`) of this version."""
    return directory() / f"fourbar-atlas-v{VERSION}-{size() if n is None else n}.npy"


# ---------------------------------------------------------------------- entries
def _feasible(a: np.ndarray, b: np.ndarray, c: np.ndarray, mu: float) -> tuple[np.ndarray, np.ndarray]:
    """``[lo, hi]`` of ``cos theta`` where a four-bar (ground 1, crank a, coupler b, rocker c) assembles.

    With its transmission angle within ``[mu, 180 - mu]`` degrees: the diagonal ``f^2 = 1 + a^2 -
    2 a cos theta`` lies within ``b^2 + c^2 -+ 2 b c cos mu`` (the cosine rule at D).
    """
    cm = np.cos(np.radians(mu))
    f_lo, f_hi = b * b + c * c - 2 * b * c * cm, b * b + c * c + 2 * b * c * cm
    return (1 + a * a - f_hi) / (2 * a), (1 + a * a - f_lo) / (2 * a)


def _interval(lo: np.ndarray, hi: np.ndarray, side: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One interval ``[start, start + length]`` of crank angles with ``cos theta`` in ``[lo, hi]``.

    The whole turn, an interval about 0 or about pi, or (both ends inside) the one above the
    ground line (``side`` > 0) or below it. Empty: length <= 0.
    """
    alpha = np.arccos(np.clip(hi, -1, 1))
    beta = np.arccos(np.clip(lo, -1, 1))
    start = np.where(side > 0, alpha, -beta)
    length = beta - alpha
    about0 = hi >= 1
    start, length = np.where(about0, -beta, start), np.where(about0, 2 * beta, length)
    aboutpi = lo <= -1
    start, length = np.where(aboutpi, alpha, start), np.where(aboutpi, 2 * np.pi - 2 * alpha, length)
    full = about0 & aboutpi
    return np.where(full, 0.0, start), np.where(full, 2 * np.pi, length)


def _poses(
    a: np.ndarray, b: np.ndarray, c: np.ndarray, w: np.ndarray, sign: np.ndarray, theta: np.ndarray
) -> np.ndarray:
    """Design vectors ``[A, B, C, D, P]`` (x, y each) of four-bars with A = 0, B = 1 at crank angle ``theta``."""
    C = a * np.exp(1j * theta)
    f = np.abs(1 - C)
    u = (1 - C) / f
    x = (b * b - c * c + f * f) / (2 * f)
    D = C + u * (x + 1j * sign * np.sqrt(np.maximum(b * b - x * x, 0.0)))
    P = C + (D - C) * w
    Z = np.stack([np.zeros_like(C), np.ones_like(C), C, D, P], axis=1)
    return np.stack([Z.real, Z.imag], axis=-1).reshape(len(a), 10)


def _draw(rng: np.random.Generator, n: int, closed: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` candidates: (design vectors (n, 10) at the sweep's start, sweeps (n,), usable (n,) bool)."""
    a = np.exp(rng.uniform(np.log(CRANK[0]), np.log(CRANK[1]), n))
    b, c = np.exp(rng.uniform(np.log(LINKS[0]), np.log(LINKS[1]), (2, n)))
    w = rng.uniform(*COUPLER_U, n) + 1j * rng.uniform(*COUPLER_V, n)
    sign = rng.choice([-1.0, 1.0], n)
    lo, hi = _feasible(a, b, c, BUILD_TRANSMISSION)
    start, length = _interval(lo, hi, rng.choice([-1.0, 1.0], n))
    if closed:
        ok = length >= 2 * np.pi
        sweep = np.full(n, 2 * np.pi)
        first = rng.uniform(0, 2 * np.pi, n)
    else:
        ok = length >= MIN_SWEEP
        sweep = rng.uniform(MIN_SWEEP, np.maximum(np.minimum(length, 1.9 * np.pi), MIN_SWEEP))
        first = start + rng.uniform(0, 1, n) * np.maximum(length - sweep, 0.0)
    return _poses(a, b, c, w, sign, first), sweep, ok


@cache
def _space() -> DesignSpace:
    from .space import builtin_space

    return builtin_space("fourbar", (0.5, 0.0), 1.0)


def curves(X: np.ndarray, sweep: np.ndarray, closed: bool, samples: int = SAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """The tracer's curves (N, samples) from each pose over its sweep, and the smallest transmission angles (N,).

    A closed curve: ``samples`` inputs over the turn (the last returns to the first); an open
    one: ``samples`` inputs from the sweep's start to its end. NaN where a design does not
    assemble. Through :func:`linkagekit.params.compile` and :func:`linkagekit.positions.solve`
    over the design axis, ``SOLVE_BATCH`` designs a call.
    """
    from ..params import compile as compile_params
    from ..positions import solve

    sp = _space()
    frac = np.arange(samples) / (samples if closed else samples - 1)
    P = np.empty((len(X), samples), complex)
    mu = np.empty(len(X))
    iC, iD, iB, iP = (sp.joint(j) for j in "CDBP")
    for s in range(0, len(X), SOLVE_BATCH):
        part = slice(s, s + SOLVE_BATCH)
        params = compile_params(sp.template, sp.poses(X[part]), sp.plan)
        q = params.pose_inputs[0][:, None] + sweep[part, None] * frac
        z = solve(params, q[None]).z
        P[part] = z[iP]
        u, v = z[iC] - z[iD], z[iB] - z[iD]
        with np.errstate(invalid="ignore"):
            cos = np.abs((np.conj(u) * v).real) / (np.abs(u) * np.abs(v))
            mu[part] = np.degrees(np.arccos(np.clip(np.max(cos, axis=1), 0.0, 1.0)))
    return P, mu


def _rows(X: np.ndarray, sweep: np.ndarray, closed: bool) -> np.ndarray:
    """Atlas rows (float32, ``COLUMNS``) of designs ``X`` with their sweeps; NaN rows where a curve fails."""
    P, mu = curves(X, sweep, closed)
    d = de.describe(P, closed)
    J = X.reshape(len(X), 5, 2) @ np.array([1.0, 1j])
    Jn = (J - d.center[:, None]) / d.scale[:, None]  # the design in its curve's normal position
    out = np.empty((len(X), COLUMNS), np.float32)
    out[:, DESC:NORM] = d.vector
    out[:, NORM] = np.sum(d.vector.astype(np.float32) ** 2, axis=1)
    out[:, JOINTS:SWEEP] = np.stack([Jn.real, Jn.imag], axis=-1).reshape(len(X), 10)
    out[:, SWEEP] = sweep
    out[:, MU] = mu
    out[:, KIND] = 0.0 if closed else 1.0
    bad = ~np.all(np.isfinite(P), axis=1) | ~np.isfinite(mu) | (mu < BUILD_TRANSMISSION - 1.0)
    out[bad] = np.nan
    return out


def make_chunk(index: int, entries: int) -> np.ndarray:
    """Chunk ``index`` of an atlas: ``entries`` rows, its closed ones first (the same for every build)."""
    rng = np.random.default_rng([VERSION, index])
    n_closed = int(round(entries * CLOSED_SHARE))
    parts = []
    for closed, want in ((True, n_closed), (False, entries - n_closed)):
        got: list[np.ndarray] = []
        have = 0
        while have < want:  # candidates in rounds: only a share of random four-bars is usable
            X, sweep, ok = _draw(rng, 10 * (want - have) + 64, closed)
            rows = _rows(X[ok][: want - have], sweep[ok][: want - have], closed)
            rows = rows[np.isfinite(rows[:, 0])]
            got.append(rows)
            have += len(rows)
        parts.append(np.concatenate(got)[:want])
    return np.concatenate(parts)


# ---------------------------------------------------------------------- cache
def _closed_rows(n: int) -> int:
    per = chunk_entries(n)
    return (n // per) * int(round(per * CLOSED_SHARE))


def _readable(file: Path, n: int) -> np.ndarray | None:
    """The memory-mapped atlas of ``n`` entries in ``file``, or None when it is missing, partial or not an atlas."""
    try:
        arr: np.ndarray = np.load(file, mmap_mode="r", allow_pickle=False)
    except (OSError, ValueError, EOFError):
        return None
    if arr.dtype != np.float32 or arr.shape != (COLUMNS, n + 1) or not np.all(arr[:, -1] == MARKER):
        return None
    nc = _closed_rows(n)
    kinds = arr[KIND, [0, nc - 1, nc, n - 1]] if nc < n else arr[KIND, [0, n - 1]]
    if not np.array_equal(kinds, [0, 0, 1, 1] if nc < n else [0, 0]):
        return None
    return arr


def _chunk_file(parts: Path, index: int) -> Path:
    return parts / f"chunk-{index:05d}.npy"


def _good_chunk(file: Path, entries: int) -> bool:
    try:
        arr = np.load(file, mmap_mode="r", allow_pickle=False)
    except (OSError, ValueError, EOFError):
        return False
    return bool(arr.dtype == np.float32 and arr.shape == (entries, COLUMNS) and np.isfinite(arr[-1, 0]))


def _place(file: Path) -> None:
    """Refuse a ``file`` path taken by something that is no file (a directory): one line, before any work."""
    if file.exists() and not file.is_file():
        raise AtlasError(f"{file}: is a directory, not the atlas file (remove it, or set LINKAGEKIT_CACHE_DIR)")


def _remove_stale(file: Path) -> None:
    """Temporary files of the atlas ``file`` and of its chunks that are older than ``STALE`` seconds, removed.

    A build killed by a signal leaves its temporary file (up to the atlas's size); no writer still owns
    one that old, so it would stay for ever.
    """
    parts = file.with_name(file.stem + ".parts")
    old = time.time() - STALE
    for tmp in [*file.parent.glob(f".{file.name}.*.tmp"), *parts.glob(".chunk-*.npy.*.tmp")]:
        with contextlib.suppress(OSError):  # gone already, or not ours to remove
            if tmp.stat().st_mtime < old:
                tmp.unlink()


def _temporary(file: Path) -> Path:
    """A new temporary file beside ``file``, of this writer alone (another process or thread has its own)."""
    fd, name = tempfile.mkstemp(dir=file.parent, prefix=f".{file.name}.", suffix=".tmp")
    os.close(fd)
    return Path(name)


def _write(file: Path, arr: np.ndarray) -> None:
    """``arr`` to ``file`` through a temporary file, renamed into place."""
    tmp = _temporary(file)
    try:
        with open(tmp, "wb") as f:
            np.save(f, arr)
        os.replace(tmp, file)
    finally:
        tmp.unlink(missing_ok=True)


def _build_chunk(parts: Path, index: int, entries: int) -> int:
    _write(_chunk_file(parts, index), make_chunk(index, entries))
    return index


def build(n: int | None = None, tick: Tick | None = None, workers: int | None = None) -> Path:
    """Build the atlas of ``n`` entries (default :func:`size`) unless a whole one is cached; returns its file.

    Chunks already written (by an interrupted build, or another process) are kept;
    ``workers`` processes build the rest (default: every core); ``tick(done, total)`` reports.
    """
    n = size() if n is None else n
    file = path(n)
    _place(file)
    _remove_stale(file)
    if _readable(file, n) is not None:
        return file
    parts = file.with_name(file.stem + ".parts")
    per = chunk_entries(n)
    total = n // per
    for _ in range(2):  # a second time when another build took the chunks away while finishing the same atlas
        try:
            parts.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise AtlasError(f"{parts}: cannot create the atlas's cache ({e.strerror or e})") from None
        todo = [i for i in range(total) if not _good_chunk(_chunk_file(parts, i), per)]
        with contextlib.suppress(FileNotFoundError):
            _run_chunks(parts, todo, per, total, tick, workers)
            _assemble(file, parts, n, per)
        if _readable(file, n) is not None:
            _clean(parts)
            return file
    raise AtlasError(f"{file}: the atlas could not be built")


def _clean(parts: Path) -> None:
    """The chunks and their directory removed (what a build still writing there will find gone: it stops)."""
    for f in parts.glob("*"):
        f.unlink(missing_ok=True)
    with contextlib.suppress(OSError):
        parts.rmdir()


def _run_chunks(parts: Path, todo: list[int], per: int, total: int, tick: Tick | None, workers: int | None) -> None:
    done = total - len(todo)
    if tick:
        tick(done, total)
    workers = min(workers or os.cpu_count() or 1, len(todo))
    from .distribute import daemonic

    if workers <= 1 or daemonic():  # a Pool's worker running synthesize(): the atlas is built here
        for i in todo:
            _build_chunk(parts, i, per)
            done += 1
            if tick:
                tick(done, total)
        return
    from concurrent.futures import as_completed

    from .distribute import Evaluator, workers_lost

    # the engine's pool: its processes leave Ctrl-C to this one, which kills them (a plain pool, left by `with`,
    # built every chunk queued before the build stopped: 12 s after a Ctrl-C, and a waiting worker's traceback)
    lost = "a worker process building the atlas died (killed?); run again to resume"
    with Evaluator((), workers) as pool, workers_lost(lost):
        for job in as_completed([pool.submit(_build_chunk, parts, i, per) for i in todo]):
            job.result()  # a chunk that failed fails the build
            done += 1
            if tick:
                tick(done, total)


def _assemble(file: Path, parts: Path, n: int, per: int) -> None:
    """The chunks into one file (closed rows first, then open; the marker last), renamed over ``file``."""
    tmp = _temporary(file)
    nc, pc = _closed_rows(n), int(round(per * CLOSED_SHARE))
    try:
        out = np.lib.format.open_memmap(tmp, mode="w+", dtype=np.float32, shape=(COLUMNS, n + 1))
        for i in range(n // per):
            chunk = np.load(_chunk_file(parts, i), allow_pickle=False)
            out[:, i * pc : (i + 1) * pc] = chunk[:pc].T
            out[:, nc + i * (per - pc) : nc + (i + 1) * (per - pc)] = chunk[pc:].T
        out[:, -1] = MARKER
        out.flush()
        del out
        os.replace(tmp, file)
    finally:
        tmp.unlink(missing_ok=True)


@dataclass(frozen=True)
class Atlas:
    """A loaded atlas: its columns (``COLUMNS`` x entries + 1, float32, memory-mapped) and where its closed entries end.

    Stored column by column, so each column of a kind is contiguous: a scan reads the
    descriptors straight from the file's pages, without a copy.
    """

    data: np.ndarray
    closed: int
    file: Path

    def __len__(self) -> int:
        return int(self.data.shape[1]) - 1

    def block(self, closed: bool) -> tuple[int, int]:
        """Row range of the closed or the open entries."""
        return (0, self.closed) if closed else (self.closed, len(self))

    def scan(self, closed: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Descriptors ``(NDESC, entries)``, their squared norms and transmission angles of one kind (views)."""
        lo, hi = self.block(closed)
        return self.data[DESC:NORM, lo:hi], self.data[NORM, lo:hi], self.data[MU, lo:hi]

    def entries(self, index: np.ndarray) -> np.ndarray:
        """Rows ``(k, COLUMNS)`` (float64) of the entries ``index``."""
        return np.asarray(self.data[:, index].T, float)


@cache
def _loaded(file: Path, n: int, mtime: float) -> Atlas | None:
    arr = _readable(file, n)
    return None if arr is None else Atlas(arr, _closed_rows(n), file)


def load(tick: Tick | None = None, workers: int | None = None) -> Atlas:
    """The atlas of :func:`size` entries: the cached one, or built now (a file that is not a whole atlas is rebuilt)."""
    n = size()
    file = path(n)
    _place(file)
    _remove_stale(file)
    for _ in range(2):
        try:
            mtime = file.stat().st_mtime
        except OSError:
            mtime = -1.0
        got = _loaded(file, n, mtime) if mtime >= 0 else None
        if got is not None:
            return got
        if mtime >= 0:
            file.unlink(missing_ok=True)  # a file there that is not a whole atlas: never trusted
        build(n, tick, workers)
    raise AtlasError(f"{file}: the atlas just built cannot be read")


# ---------------------------------------------------------------------- queries
@dataclass(frozen=True)
class Match:
    """Atlas entries placed onto a curve of targets, nearest first.

    Attributes
    ----------
    joints : ndarray, complex, shape (k, 5)
        Joints A, B, C, D, P of each design at its pose (the start of its sweep), placed.
    sweep : ndarray (k,)
        The crank's sweep from the pose (radians; 2 pi for a closed curve).
    transmission : ndarray (k,)
        The smallest transmission angle over the sweep (degrees).
    distance : ndarray (k,)
        Descriptor distance (the RMS distance of the normalised curves, in RMS radii).
    rows : ndarray of int (k,)
        The entries' rows.
    """

    joints: np.ndarray
    sweep: np.ndarray
    transmission: np.ndarray
    distance: np.ndarray
    rows: np.ndarray


def nearest(
    atlas: Atlas, points: np.ndarray, closed: bool = True, k: int = NEAREST, min_transmission: float = 0.0
) -> Match:
    """The ``k`` entries whose curves are nearest in shape to the polygon ``points`` (complex), placed onto it.

    An exact scan: ``|d|^2 - 2 d.q`` over every entry of the kind for both descriptors of the
    query, in float32; entries whose transmission angle falls below ``min_transmission`` are left out.
    """
    q = de.describe(np.asarray(points, complex), closed)
    lo, _ = atlas.block(closed)
    D, norm, mu = atlas.scan(closed)
    both = np.stack([q.vector, de.flipped(q.vector)]).astype(np.float32)
    dots = both @ D  # (2, entries)
    d0 = norm - 2.0 * dots[0]
    d1 = norm - 2.0 * dots[1]
    flip = d1 < d0
    best = np.minimum(d0, d1) + float(both[0] @ both[0])  # both descriptors have one norm
    best[mu < min_transmission] = np.inf
    k = min(k, len(best))
    idx = np.argpartition(best, k - 1)[:k] if k < len(best) else np.arange(len(best))
    idx = idx[np.argsort(best[idx], kind="stable")]
    idx = idx[np.isfinite(best[idx])]
    sel = atlas.entries(idx + lo)
    J = sel[:, JOINTS:SWEEP].reshape(len(idx), 5, 2) @ np.array([1.0, 1j])
    s = np.where(flip[idx], -q.scale, q.scale)
    placed = q.center + s[:, None] * J
    dist = np.sqrt(np.maximum(best[idx], 0.0))
    return Match(placed, sel[:, SWEEP], sel[:, MU], dist, idx + lo)


# ---------------------------------------------------------------------- seeding a search
@dataclass(frozen=True)
class Answer:
    """The atlas's answer to a path problem: design vectors of its space, best first.

    Attributes
    ----------
    designs : ndarray (k, dim)
        The placed (and posed) entries, the polished ones among them, best first.
    error : float
        The first design's largest target error over the targets' diagonal, by the problem's
        dense check (``inf`` if it breaks a constraint).
    cost : float
    seconds : float
        Time taken (the atlas's loading included).
    polished : int
        Designs polished by least squares before the answer was chosen.
    """

    designs: np.ndarray
    error: float
    cost: float
    seconds: float
    polished: int


def applies(problem: Problem) -> bool:
    """The atlas seeds a problem of the built-in four-bar, unless it is off.

    Its joints A, B, C, D, P all free, or C, D, P with ``--shape-only`` (which fixes the ground
    pivots); over a full turn (from the closed entries) or, ``partial`` and untimed, over a sweep
    whose start and span are design variables (from the open entries: an entry's sweep is the
    span, its pose within it the fraction ``f``). A partial problem with inputs (timed) takes
    its sweep from them, which no entry's sweep need match: not seeded.
    """
    sp = problem.space
    swept = not getattr(problem, "partial", False) or bool(getattr(problem, "swept", False))
    free = ("C", "D", "P") if _shape_only(problem) else ("A", "B", "C", "D", "P")
    return sp.topology == "fourbar" and sp.free == free and swept and size() > 0


def _shape_only(problem: Problem) -> bool:
    return bool(getattr(problem, "shape_only", False))


def on_pivots(problem: Problem, joints: np.ndarray) -> np.ndarray:
    """Design vectors (k, 6) of ``--shape-only``'s space: four-bars ``joints`` (k, 5) moved, turned and scaled
    so that A and B land on the space's fixed ground pivots (the objective places each curve on the targets)."""
    sp = problem.space
    base = sp.template.pose_array()
    A, B = (complex(*base[sp.joint(j)]) for j in "AB")
    s = (B - A) / (joints[:, 1] - joints[:, 0])
    J = A + s[:, None] * (joints[:, 2:] - joints[:, :1])
    return np.stack([J.real, J.imag], axis=-1).reshape(len(joints), 6)


def _turn(problem: Problem, joints: np.ndarray, samples: int, span: np.ndarray | None = None) -> np.ndarray:
    """Every joint (5, k, samples) of four-bars ``joints`` (k, 5) over a whole turn of the crank from their poses.

    With ``span`` (k,): over each one's sweep from its pose instead, both ends sampled.
    """
    from ..params import compile as compile_params
    from ..positions import solve

    sp = problem.space
    X = np.stack([joints.real, joints.imag], axis=-1).reshape(len(joints), 10)
    params = compile_params(sp.template, sp.poses(X), sp.plan)
    turn = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)[None, :]
    q = params.pose_inputs[0][:, None] + (turn if span is None else span[:, None] * np.linspace(0.0, 1.0, samples))
    z: np.ndarray = solve(params, q[None]).z
    return z


def refit(
    problem: Problem, joints: np.ndarray, rounds: int = REFITS, samples: int = 180, span: np.ndarray | None = None
) -> np.ndarray:
    """Four-bars ``joints`` (k, 5) moved, turned and scaled so that their curves fit the targets better.

    Their curves over a whole turn, or with ``span`` (k,) over each one's sweep from its pose.

    Iterated closest points: each target's nearest curve sample ``N_i``, then the similarity
    ``c + s z`` of least squares ``sum |T_i - c - s N_i|^2`` (a linear fit in the complex ``c, s``:
    ``s = sum (T_i - Tm) conj(N_i - Nm) / sum |N_i - Nm|^2``, ``c = Tm - s Nm``), applied to the
    joints. A descriptor matches whole curves at equal arc-length fractions; a few targets
    are not spread so, and this places the curve through them instead.
    """
    T = problem.targets
    P = problem.space.joint(problem.space.tracer)
    for _ in range(rounds):
        C = _turn(problem, joints, samples, span)[P]  # (k, samples)
        C = np.where(np.isfinite(C), C, np.inf)
        N = np.empty((len(joints), len(T)), complex)
        for i in range(0, len(T), 64):  # the (k, targets, samples) distances in bounded pieces
            d = np.abs(C[:, None, :] - T[None, i : i + 64, None])
            N[:, i : i + 64] = np.take_along_axis(C, np.argmin(d, axis=2), axis=1)
        Nm, Tm = N.mean(axis=1, keepdims=True), T.mean()
        with np.errstate(invalid="ignore", divide="ignore"):
            s = np.sum((T - Tm) * np.conj(N - Nm), axis=1) / np.sum(np.abs(N - Nm) ** 2, axis=1)
        ok = np.isfinite(s) & (s != 0)
        s, c = np.where(ok, s, 1.0), np.where(ok, Tm - s * Nm[:, 0], 0.0)
        joints = c[:, None] + s[:, None] * joints
    return joints


def posed(problem: Problem, joints: np.ndarray, samples: int = 360, span: np.ndarray | None = None) -> np.ndarray:
    """Design vectors of ``problem``'s space for four-bars ``joints`` (k, 5), posed with P nearest the first target.

    Turning the crank a whole turn from each pose on its branch, the pose moves to the sample
    where the tracer is nearest the first target (the built-in space keeps the tracer near it).
    With ``span`` (k,), a partial problem's: along each one's sweep from its pose instead, and the
    design vector ends with the sweep's variables ``f`` (the share of the sweep before the new
    pose: the sample's) and the span (:meth:`~.objective.Problem.sweep`).
    """
    sp = problem.space
    z = _turn(problem, joints, samples, span)  # (joints, k, samples)
    d = np.abs(z[sp.joint(sp.tracer)] - problem.targets[0])
    best = np.argmin(np.where(np.isfinite(d), d, np.inf), axis=1)
    Z = np.take_along_axis(z, best[None, :, None], axis=2)[:, :, 0]  # (joints, k)
    order = [sp.joint(j) for j in sp.free]
    X = np.stack([Z[order].real, Z[order].imag], axis=-1).transpose(1, 0, 2).reshape(len(joints), -1)
    return X if span is None else np.c_[X, best / (samples - 1), span]


def _fits(problem: Problem, joints: np.ndarray) -> np.ndarray:
    """Four-bars (k, 5) whose ground pivots and crank and rocker circles lie within the bounds of A, B, C, D.

    So every pose of C and D lies within them too (the tracer's box is checked once posed).
    """
    lo, hi = problem.bounds
    A, B, C, D = joints[:, 0], joints[:, 1], joints[:, 2], joints[:, 3]
    rc, rd = np.abs(C - A), np.abs(D - B)

    def inside(z: np.ndarray, r: np.ndarray | float, i: int) -> np.ndarray:
        ok: np.ndarray = (
            (z.real - r >= lo[2 * i])
            & (z.real + r <= hi[2 * i])
            & (z.imag - r >= lo[2 * i + 1])
            & (z.imag + r <= hi[2 * i + 1])
        )
        return ok

    fits: np.ndarray = inside(A, 0.0, 0) & inside(B, 0.0, 1) & inside(A, rc, 2) & inside(B, rd, 3)
    return fits


def _nearest_fitting(
    problem: Problem, atlas: Atlas, keep: Callable[[Match], np.ndarray], closed: bool | None = None
) -> Match:
    """Up to ``NEAREST`` nearest entries (closed, or open for a partial problem, or as ``closed`` says) that
    ``keep`` accepts.

    ``LOOKED_UP`` entries are looked up, more when too few are kept.
    """
    closed = not problem.partial if closed is None else closed
    for k in LOOKED_UP:
        m = nearest(atlas, problem.targets, closed, k, problem.min_transmission)
        ok = np.flatnonzero(keep(m))[:NEAREST]
        if len(ok) == NEAREST:
            break
    return Match(m.joints[ok], m.sweep[ok], m.transmission[ok], m.distance[ok], m.rows[ok])


def _placed(problem: Problem, atlas: Atlas) -> np.ndarray:
    """Design vectors of the nearest entries that fit the bounds, placed, refitted and posed on the targets."""
    m = _nearest_fitting(problem, atlas, lambda m: _fits(problem, m.joints))
    if len(m.rows) == 0:
        return np.zeros((0, problem.dim))
    span = m.sweep if problem.partial else None
    X = posed(problem, refit(problem, m.joints, span=span), span=span)
    return X if problem.partial else np.concatenate([X, _arcs_of_turns(problem, atlas)])


def turns_fully(joints: np.ndarray) -> np.ndarray:
    """Four-bars ``joints`` (k, 5: A, B, C, D, P) whose crank A-C turns fully.

    ``|C - B|`` takes every value in ``[|d - a|, d + a]`` (crank ``a``, ground ``d``) as the crank
    turns; the dyad C-D-B closes there iff ``|b - c| <= |C - B| <= b + c`` (coupler ``b``, rocker ``c``).

    >>> turns_fully(np.array([[0, 4, 1 + 0j, 3 + 3j, 0], [0, 2, 1.5 + 0j, 1 + 1j, 0]]))
    array([ True, False])
    """
    A, B, C, D = (joints[:, i] for i in range(4))
    a, b, c, d = np.abs(C - A), np.abs(D - C), np.abs(D - B), np.abs(B - A)
    ok: np.ndarray = (d + a <= b + c) & (np.abs(d - a) >= np.abs(b - c))
    return ok


def _arcs_of_turns(problem: Problem, atlas: Atlas) -> np.ndarray:
    """A full-turn problem whose targets lie on a part of a curve (six points on a line): the open entries nearest
    to the targets' open polygon whose crank turns fully (arcs of crank-rockers' curves), refitted and posed
    over a whole turn (the nearest distances over the whole curve are at most those over the arc)."""
    m = _nearest_fitting(problem, atlas, lambda m: _fits(problem, m.joints) & turns_fully(m.joints), closed=False)
    if len(m.rows) == 0:
        return np.zeros((0, problem.dim))
    return posed(problem, refit(problem, m.joints))


def _shaped(problem: Problem, atlas: Atlas) -> np.ndarray:
    """``--shape-only``: design vectors of the nearest entries within the bounds, on the fixed pivots.

    A partial problem's start at the sweep's start (``f = 0``) with the entry's span.
    """
    lo, hi = problem.bounds

    def vectors(m: Match) -> np.ndarray:
        X = on_pivots(problem, m.joints)
        return np.c_[X, np.zeros(len(X)), m.sweep] if problem.partial else X

    def inside(m: Match) -> np.ndarray:
        X = vectors(m)
        ok: np.ndarray = np.all((lo <= X) & (hi >= X), axis=1)
        return ok

    return vectors(_nearest_fitting(problem, atlas, inside))


def first_answer(
    problem: Problem,
    atlas: Atlas | None = None,
    polish: int = POLISHED,
    workers: int | None = None,
    until: float | None = None,
    first_until: float | None = None,
) -> Answer:
    """The atlas's answer to ``problem`` (see the module's description).

    Without ``until`` the same for the same problem and atlas: the polish is bounded by its
    evaluations, not by the clock, so a run resumed from its checkpoint gets the seeds the
    uninterrupted run had. ``until`` (a ``time.monotonic()`` deadline) bounds it by the clock too:
    the candidates are scored in chunks of :data:`COST_CHUNK` (the nearest first) until it passes,
    and each polish but the first stops there at its best point (200 shape-only targets of an open
    letter took 23 s of a 3 s budget: every evaluation places the curve by its nearest points); the
    first, the best candidate's, stops at ``first_until`` (the run's whole budget). An atlas
    not yet cached is built first, on ``workers`` processes (default: every core).
    """
    from .objective import best_index
    from .optimize import polish as local

    t0 = time.monotonic()
    atlas = atlas or load(build_report(), workers)
    X = _shaped(problem, atlas) if _shape_only(problem) else _placed(problem, atlas)
    lo, hi = problem.bounds
    X = X[np.all((lo <= X) & (hi >= X), axis=1)]
    if len(X) == 0:
        return Answer(np.zeros((0, problem.dim)), np.inf, np.inf, time.monotonic() - t0, 0)
    cost = _costs_in_time(problem, X, until)
    X = X[: len(cost)]
    # the best by the search's cost, and the nearest few by shape whatever theirs: the search's placement
    # of a partial arc (shape-only) can miss a curve that the dense check places exactly
    by_cost = np.argsort(cost, kind="stable")
    # the best candidate's polish gets the whole budget: cut at a quarter, the answer on 200 targets in 10 s was
    # 100 times worse
    done = [local(problem, x, POLISH_NFEV, until if k else first_until) for k, x in enumerate(X[by_cost[:polish]])]
    near = np.arange(min(CHECKED_NEAREST, len(X)))
    shown = np.concatenate([by_cost[:8], near[~np.isin(near, by_cost[:8])]])
    head = np.array(done + list(X[shown]))
    err, cost = problem.measure(head)
    order = np.lexsort((cost, err))
    designs = np.concatenate([head[order], X[by_cost[~np.isin(by_cost, shown)]]])
    k = best_index(err, cost)
    return Answer(designs, float(err[k]), float(cost[k]), time.monotonic() - t0, len(done))


#: designs of the atlas's answer scored at once while a deadline is checked
COST_CHUNK = 32


def _costs_in_time(problem: Problem, X: np.ndarray, until: float | None) -> np.ndarray:
    """The search's cost of the candidates ``X`` (the nearest first): of all, or, with a deadline ``until``, of
    those scored in chunks of :data:`COST_CHUNK` before it passed (the first chunk at least)."""
    if until is None:
        return np.asarray(problem.cost(X))
    parts = [np.asarray(problem.cost(X[:COST_CHUNK]))]
    for k in range(COST_CHUNK, len(X), COST_CHUNK):
        if time.monotonic() >= until:
            break
        parts.append(np.asarray(problem.cost(X[k : k + COST_CHUNK])))
    return np.concatenate(parts)


@dataclass(frozen=True)
class Info:
    """What is cached (:func:`info`).

    Attributes
    ----------
    file : Path
    version : int
        The format.
    entries, closed, open : int
        Entries in all, of closed curves, of open ones.
    built : bool
        A whole atlas is there.
    damaged : bool
        A file is there that is not a whole atlas (cut short, another shape, not an atlas): the next
        use deletes and rebuilds it.
    bytes : int
        The file's size on disk (0 when there is none).
    chunks : int
        Chunks an unfinished build has written (of ``entries // chunk_entries(entries)``).
    """

    file: Path
    version: int
    entries: int
    closed: int
    open: int
    built: bool
    damaged: bool
    bytes: int
    chunks: int


def info() -> Info:
    """What is cached, never building anything."""
    n = size()
    file = path(n)
    _place(file)
    built = _readable(file, n) is not None
    there = file.is_file()
    parts = file.with_name(file.stem + ".parts")
    chunks = len(list(parts.glob("chunk-*.npy"))) if parts.is_dir() and not built else 0
    nc = _closed_rows(n)
    return Info(file, VERSION, n, nc, n - nc, built, there and not built, file.stat().st_size if there else 0, chunks)


def build_report() -> Tick:
    """A progress report of a build on stderr: a bar on a terminal, else a line every tenth."""
    state: dict[str, object] = {}

    def tick(done: int, total: int) -> None:
        if sys.stderr.isatty():
            from rich.progress import Progress

            bar = state.get("bar")
            if bar is None:
                from rich.console import Console

                bar = Progress(console=Console(stderr=True), transient=True)
                bar.start()
                state["bar"], state["task"] = bar, bar.add_task("building the four-bar atlas", total=total)
            bar.update(state["task"], completed=done)  # type: ignore[attr-defined]
            if done >= total:
                bar.stop()  # type: ignore[attr-defined]
        elif done == 0 or done == total or done * 10 // total != (done - 1) * 10 // total:
            print(f"linkagekit: building the four-bar atlas (once): {done} of {total} chunks", file=sys.stderr)

    return tick
