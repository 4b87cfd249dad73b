"""``linkagekit edit``: the report's page served from 127.0.0.1, where the mechanism can be edited.

The page (``editor.js`` over the report's ``viewer.js``) never solves anything.  Each edit
(a joint dragged, a number typed, a joint or a link added, an assembly mode chosen) sends
the edited mechanism document to this server, which builds the :class:`Mechanism`, solves
it with :func:`linkagekit.analyze` and answers with the new document and its scene.  While
a joint is dragged the page asks for a coarse sweep and keeps only the newest request in
flight; on release it asks for the full sweep with checks, modes and forces.  A document
that does not solve is answered with its message, and the page keeps its last good picture.

The server is the standard library's threading HTTP server: it binds 127.0.0.1 only, serves
one page and three JSON calls under a random token, and refuses (403) a request without the
token, with a ``Host`` other than the loopback address, from another ``Origin``, or for any
other path.  Only the opened file (and its ``.bak`` backup) is ever written: ``save``
writes a temporary file and renames it over the old one, after copying the old one to the
backup, and refuses when the file changed on disk since it was opened or last saved, or is
read-only; a page load takes the file as it is on disk now.  Saves of one file take turns (in
this process, and with any program that takes an ``flock`` on it), and the file is checked once
more just before the rename (:meth:`Session.save` says what no check can exclude).  A symbolic
link FILE is followed (the file it points to is replaced, the link stays), a link ``FILE.bak``
never is (it is replaced); both writes go through :func:`~linkagekit.files.write_atomic`, and
every read of the file is bounded (:func:`~linkagekit.files.read_mechanism_file`).  The
temporary files a save killed half-way may leave (``.FILE.<hex>.tmp``, exactly that pattern) are removed when
the editor starts.  The browser is opened on a private redirect page (:func:`redirect_file`),
never with the token on its command line.

At most :data:`MAX_CONNECTIONS` connections are served at once (one thread each; more wait, then
are answered 503), and each request must arrive whole within :data:`TIMEOUT` of when it is
awaited (sooner when others wait for a handler): a client that stalls or trickles its request
is dropped.

Each solve (and the page) runs under a :class:`Watch`: past its time budget it is stopped and
answered 503 with a message; when its client has gone (a closed tab) it is stopped at once.
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import html
import io
import json
import math
import os
import re
import secrets
import select
import shutil
import socket
import stat
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, Literal
from urllib.parse import urlsplit

import numpy as np

from ..catalogue import input_units
from ..errors import InputError, LinkageError, MechanismFileError, one_line, shorten
from ..files import (
    dumps,
    from_bytes,
    locked,
    merge_comments,
    read_mechanism_file,
    stray_temporaries,
    write_atomic,
    yaml_data,
)
from ..model import Driver, Mechanism, parse_pair
from ..result import Result

#: samples of the coarse sweep solved while a joint is dragged
COARSE_SAMPLES = 73
#: samples of the coarse grid a class-3 drag's sweep reaches, every PROBE_EVERY-th move, past where
#: the previous move assembled (see Session._coarse)
WINDOW_MARGIN = 2
PROBE_EVERY = 5
#: drags whose coarse windows are remembered
MAX_WINDOWS = 16
#: the largest request body the server reads
MAX_BODY = 2 << 20
#: seconds a connection may wait for its next request to arrive whole (request line, headers and body; the idle
#: time before it included), and an answer may take to be sent: a client that stalls or trickles is dropped
TIMEOUT = 10.0
#: connections served at once, one thread each; more wait (in the system's queue) for one to end
MAX_CONNECTIONS = 64
#: seconds a request may still take to arrive once every handler is taken and a connection waits for one: idle
#: kept-alive connections and stalled clients make room sooner than TIMEOUT
CROWDED_SECONDS = 1.0
#: seconds between two looks of a waiting read at its deadline (which a crowded server brings forward)
READ_SLICE = 0.25
#: seconds a connection waits for a free handler before it is answered 503 (busy): a little longer than a stalled
#: connection may hold one (TIMEOUT), so that only solves that long (SOLVE_SECONDS) on every handler make it busy
BUSY_SECONDS = 12.0
#: seconds a save waits for another program's lock (flock) on the file before it says so
LOCK_SECONDS = 2.0
#: how a client that went away shows: it reset or closed its connection, or stopped sending
VANISHED = (ConnectionError, TimeoutError)
#: seconds one solve (or the page) may compute before it is stopped and answered with a message
SOLVE_SECONDS = 30.0
#: seconds between two looks of the watch at the solves under way (deadline passed? client gone?)
WATCH_INTERVAL = 0.05
#: levels of JSON nesting a request may have (a mechanism document needs about 5)
MAX_JSON_DEPTH = 64
#: texts of the file a save keeps the styles of (the newest saved ones and the file as opened)
KEPT_TEXTS = 8


class ConflictError(LinkageError):
    """The file changed on disk since the editor read or last saved it (or cannot be written as it is): 409."""

    exit_code = 1


class RequestError(InputError):
    """A request whose fields are not what the page sends (a joint the document lacks, a 'base' not a hash): 400."""


def shown(text: str) -> str:
    """``text`` with every lone surrogate (a file name's bytes that are not UTF-8) as U+FFFD, fit for HTML and JSON.

    >>> shown(os.fsdecode(b"m\\xff.yaml"))
    'm\ufffd.yaml'
    """
    return re.sub("[\ud800-\udfff]", "\ufffd", text)


def sweep_with_pose(mech: Mechanism, n: int | None = None) -> tuple[dict[str, np.ndarray], int]:
    """The file's sweep (or ``n`` samples evenly over it), with the reference pose's input in it.

    As in :func:`linkagekit.analyze`, a driver whose sweep has another number of samples than
    the first driver's stays at its pose value.

    Returns the inputs by driver and the index of the pose's sample, so that the page can
    show the pose itself: a dragged joint stays under the pointer.
    """
    from ..api import pose_inputs
    from .report import MAX_REPORT_SAMPLES

    pose = pose_inputs(mech)
    count = mech.drivers[0].sweep.count()
    n = n or (count if count <= MAX_REPORT_SAMPLES - 1 else MAX_REPORT_SAMPLES - 1)

    def along(d: Driver) -> np.ndarray:
        if d.sweep.count() != count:  # as lk.analyze: a sweep of another length stays at the pose's value
            return np.full(n, pose[d.name])
        return d.sweep.values() if n == count else np.linspace(d.sweep.start, d.sweep.stop, n)

    base = {d.name: along(d) for d in mech.drivers}
    first = mech.drivers[0].name
    x = base[first]
    near = np.flatnonzero(np.all([np.abs(base[k] - v) <= 1e-12 * max(1.0, abs(v)) for k, v in pose.items()], axis=0))
    if near.size:
        return base, int(near[0])
    ascending = x.size < 2 or x[-1] >= x[0]
    k = int(np.searchsorted(x, pose[first])) if ascending else int(x.size - np.searchsorted(x[::-1], pose[first]))
    return {name: np.insert(v, k, pose[name]) for name, v in base.items()}, k


#: a joint of a new pose this close to its place in the document (relative to the mechanism's size)
#: has not moved: it keeps the document's exact numbers
SAME_PLACE = 1e-9


def posed(mech: Mechanism, pose: Any, moved: Any = None) -> Mechanism:
    """``mech`` with the reference pose ``pose`` (joint -> [x, y]), as after a drag of the ``moved`` joints.

    Every dimension is read off the new pose (:meth:`Mechanism.with_pose`), except what the
    drag cannot have changed, which keeps the document's exact numbers: a joint not moved
    that is where the document has it keeps its coordinates (not the solver's rounding of
    them), a given length between two joints not moved stays given, and a link whose joints
    all kept their place keeps its centre of gravity.  ``moved`` (a list of joint names)
    defaults to the joints whose place differs from the document's.

    Examples
    --------
    >>> from linkagekit.files import load
    >>> m = load("examples/fivebar_two_drivers.yaml")
    >>> new = posed(m, {"P": [16.0, 89.0]}, ["P"])
    >>> new.link("crank1").lengths["A-C"], dict(new.link("link1").lengths)
    (30.0, {'C-E': 60.0})
    """
    _check_pose(mech, pose, moved)
    tol = SAME_PLACE * mech.length_scale
    here = {j: [z.real, z.imag] for j, z in mech.joints.items()}
    placed = mech.with_pose({j: pose.get(j, here[j]) for j in mech.joints}).joints  # checks the pose
    if moved is None:
        moved = [j for j in mech.joints if abs(placed[j] - mech.joints[j]) > tol]
    still = {j for j in mech.joints if j not in moved and abs(placed[j] - mech.joints[j]) <= tol}
    doc = mech.with_pose({j: here[j] if j in still else [z.real, z.imag] for j, z in placed.items()}).to_dict()
    old = mech.to_dict()["links"]
    for ln in mech.links:
        kept = {k: v for k, v in ln.lengths.items() if not set(parse_pair(k, ln.joints) or ()) & set(moved)}
        entry = doc["links"][ln.name]
        if isinstance(entry, list) and kept:
            entry = doc["links"][ln.name] = {"joints": entry}
        if kept:
            entry["lengths"] = kept
        if ln.cg_pose is not None and set(ln.joints) <= still:
            entry["cg"] = old[ln.name]["cg"]
    return Mechanism.from_dict(doc, source=mech.source)


def _check_pose(mech: Mechanism, pose: Any, moved: Any) -> None:
    """Refuse (:class:`RequestError`) a ``pose`` or ``moved`` that is not joints of ``mech`` and finite places."""
    if not isinstance(pose, dict):
        raise RequestError("'pose' must map joint names to [x, y]")
    for j, xy in pose.items():
        if j not in mech.joints:
            raise RequestError(f"pose: the mechanism has no joint '{shorten(j)}'")
        if not (isinstance(xy, list) and len(xy) == 2 and all(_finite(v) for v in xy)):
            raise RequestError(f"pose.{shorten(j)}: expected [x, y], two finite numbers, got {shorten(repr(xy))}")
    if moved is None:
        return
    if not isinstance(moved, list) or not all(isinstance(j, str) for j in moved):
        raise RequestError("'moved' must list joint names")
    for j in moved:
        if j not in mech.joints:
            raise RequestError(f"moved: the mechanism has no joint '{shorten(j)}'")


def _finite(v: Any) -> bool:
    """True for a finite number (not a bool; an int too large for a float is not finite)."""
    if isinstance(v, bool) or not isinstance(v, int | float):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _hash(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


_PATH_LOCKS: dict[str, threading.Lock] = {}
_PATH_LOCKS_LOCK = threading.Lock()


def path_lock(path: Path) -> threading.Lock:
    """The lock of the file ``path`` names (a link followed) in this process: its saves take it in turn, also
    those of two sessions of one file (two servers, or a ``./m.yaml`` and an ``m.yaml``)."""
    key = os.path.realpath(path)
    with _PATH_LOCKS_LOCK:
        return _PATH_LOCKS.setdefault(key, threading.Lock())


def _stamp(st: os.stat_result) -> tuple[int, int, int]:
    """What a write to a file changes of its status: its size, its modification and its change time."""
    return st.st_size, st.st_mtime_ns, st.st_ctime_ns


def _leading_comments(text: str) -> str:
    """The comment lines (and blank lines) at the top of a YAML file, kept when it is saved."""
    out = []
    for line in text.splitlines():
        if line.startswith("#") or not line.strip():
            out.append(line)
        else:
            break
    while out and not out[-1].strip():
        out.pop()
    return "\n".join(out) + "\n" if out else ""


class Session:
    """The file being edited: its text on disk, and the solves and saves of the page.

    Parameters
    ----------
    path : str or Path
        A mechanism file (YAML or JSON); it is loaded (and so validated) here.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        #: the file's name as the page and the answers show it (bytes that are not UTF-8 as U+FFFD)
        self.name = shown(self.path.name)
        data, _ = read_mechanism_file(self.path)  # bounded, a regular file only
        self._take(data, from_bytes(data, self.path))  # a bad file: MechanismFileError, exit 2, before serving
        for stray in stray_temporaries(self.path):  # left by an editor killed during a save
            with contextlib.suppress(OSError):
                stray.unlink()
        self.fmt: Literal["yaml", "json"] = "json" if self.path.suffix.lower() == ".json" else "yaml"
        self.backup = self.path.with_name(self.path.name + ".bak")
        self.lock = threading.Lock()
        #: the coarse-grid samples each recent drag solves (see :meth:`_coarse`), oldest first
        self.windows: dict[str, tuple[int, int, int]] = {}

    def _take(self, data: bytes, mech: Mechanism) -> None:
        """Take ``data``, the file's bytes as read now, and its mechanism as the state edited from here on."""
        self.mech = mech
        self.base = _hash(data)
        self.text = data.decode("utf-8-sig", errors="replace")
        #: the file's texts as opened and as saved since, newest first (at most :data:`KEPT_TEXTS`): what an
        #: edit undone writes back keeps the style they gave it (:meth:`_text_to_save`)
        self.texts = [self.text]

    def _read_now(self, then: str) -> tuple[bytes, os.stat_result]:
        """The file's bytes (bounded, as :func:`~linkagekit.files.load` reads them) and status, or a
        :class:`ConflictError` saying plainly why not, ending with ``then`` (what was not done)."""
        try:
            return read_mechanism_file(self.path)
        except MechanismFileError as exc:
            if not os.path.lexists(self.path):
                raise ConflictError(f"{self.path}: no such file any more (deleted or moved): {then}") from None
            raise ConflictError(f"{one_line(str(exc), 250)}: {then}") from None

    def refresh(self) -> None:
        """Take the file as it is on disk now when it changed since it was opened or saved here.

        A page load calls this: after another program changed the file, reloading the page edits
        the file as it is now.  A file that no longer loads (or is gone) raises :class:`ConflictError`
        naming it, and the editor keeps its state.
        """
        then = "fix it and reload the page"
        with self.lock:
            data, _ = self._read_now(then)
            if _hash(data) == self.base:
                return
            try:
                mech = from_bytes(data, self.path)
            except LinkageError as exc:
                raise ConflictError(f"changed on disk and no longer loads: {one_line(str(exc), 250)}: {then}") from None
            self._take(data, mech)

    # ---------------------------------------------------------------- solving
    def solve(self, request: dict[str, Any]) -> dict[str, Any]:
        """The answer to ``{"doc", "pose"?, "moved"?, "coarse"?, "at"?}``: the new document and its scene.

        ``pose`` maps joint names to new positions (file units): the mechanism takes them as
        its reference pose (:func:`posed`: every dimension read off it but those the
        ``moved`` joints cannot have changed).  ``coarse`` asks for :data:`COARSE_SAMPLES`
        samples over the sweep, no forces, no checks and no exact curve breaks; for a
        numerical (class-3) group only over the stretch where the previous coarse answer of
        the same drag assembled (:meth:`_coarse`).  Otherwise the file's sweep with forces,
        the text of ``check`` and the assembly modes at input ``at`` (driver -> value).
        """
        from ..api import analyze
        from ..checks import check, check_text
        from ..viz.scene import build_scene

        mech = self._mechanism(request)
        if request.get("modes_only"):
            return {"ok": True, **self._modes(mech, request.get("at"))}
        out: dict[str, Any] = {"ok": True, "doc": mech.to_dict()}
        if request.get("coarse"):
            res, out["pose_index"] = self._coarse(mech, request)
            out["scene"] = build_scene(res, exact_breaks=False).to_dict()
        else:
            inputs, out["pose_index"] = sweep_with_pose(mech)
            res = analyze(mech, inputs, dynamics=mech.has_dynamics)
            report = check(mech)  # its assembly range also gives the curves' breaks: computed once
            out["scene"] = build_scene(res, input_range=report.input_range).to_dict()
            out["checks"] = check_text(report.to_dict(), input_units(mech), mech.name or self.name)
            out.update(self._modes(mech, request.get("at")))
        out["lengths"] = {
            ln.name: {f"{a}-{b}": ln.length(a, b) for i, a in enumerate(ln.joints) for b in ln.joints[i + 1 :]}
            for ln in mech.links
            if ln.name != "ground" and len(ln.joints) >= 2
        }
        return out

    def _mechanism(self, request: dict[str, Any]) -> Mechanism:
        """The request's mechanism: its ``doc``, at the ``pose`` (or in the assembly ``mode``) it asks for."""
        doc = request.get("doc")
        if not isinstance(doc, dict):
            raise InputError("the request has no mechanism document ('doc')")
        mech = Mechanism.from_dict(doc, source=str(self.path))
        pose = request.get("pose")
        wanted = request.get("mode")
        if wanted is not None:  # an assembly mode, by its signs, at input 'at': its positions become the pose
            if not isinstance(wanted, dict):
                raise InputError("'mode' must map sign joints to +1 or -1")
            listed = self._modes(mech, request.get("at"))
            groups = request.get("mode_groups")  # a numerical group's mode: its index among the group's modes
            match = [
                m for m in listed["modes"] if m["signs"] == wanted and (groups is None or m.get("groups") == groups)
            ]
            if not match:
                raise InputError(
                    listed.get("modes_note")
                    or f"the mode {wanted} does not assemble at {listed.get('modes_at')}: move the input first"
                )
            # a mode changes no dimension: every given length stays exactly as the document has it
            return posed(mech, {j: list(xy) for j, xy in match[0]["joints"].items()}, [])
        return mech if pose is None else posed(mech, pose, request.get("moved"))

    def _coarse(self, mech: Mechanism, request: dict[str, Any]) -> tuple[Result, int]:
        """A drag's coarse sweep, solved, and the index of the pose's sample in it.

        The numerical walk of a class-3 group costs more at a sample that does not assemble
        (Newton fails, the step is halved ten times) than at one that does, and a drag changes
        the assembly range little from one move to the next: so the moves of one drag (the
        same ``doc`` and ``moved``) solve only the samples of the coarse grid that assembled
        at the previous move; every :data:`PROBE_EVERY`-th move reaches :data:`WINDOW_MARGIN`
        samples further on both sides, to follow a range that grows.  The first move solves
        the whole grid, as does a move after one where nothing assembled; the release solves
        the whole sweep.
        """
        from ..api import analyze, prepare

        inputs, index = sweep_with_pose(mech, COARSE_SAMPLES)
        if not prepare(mech).plan.numerical:
            return analyze(mech, inputs, dynamics=False), index
        key = _hash(json.dumps([request.get("doc"), request.get("moved")], sort_keys=True).encode())
        n = len(inputs[mech.drivers[0].name])
        lo, hi, moves = self.windows.get(key, (0, n - 1, 0))
        reach = WINDOW_MARGIN if moves % PROBE_EVERY == 0 else 0
        lo, hi = max(0, min(lo, index) - reach), min(max(hi, index) + reach, n - 1)
        res = analyze(mech, {k: v[lo : hi + 1] for k, v in inputs.items()}, dynamics=False)
        ok = np.flatnonzero(res.assembled)
        with self.lock:
            self.windows.pop(key, None)
            if ok.size:
                self.windows[key] = (lo + int(ok[0]), lo + int(ok[-1]), moves + 1)
            while len(self.windows) > MAX_WINDOWS:
                self.windows.pop(next(iter(self.windows)))
        return res, index - lo

    @staticmethod
    def _modes(mech: Mechanism, at: Any) -> dict[str, Any]:
        """The distinct assembly modes at input ``at`` (driver -> value; default the pose's)."""
        from ..checks import modes

        try:
            found = modes(mech, at if isinstance(at, dict) and at else None)
        except LinkageError as exc:  # too many sign steps, a bad input: no list, and say why
            return {"modes": [], "modes_note": one_line(str(exc), 200)}
        return {
            "modes": [
                {"signs": m.signs, "reference": m.reference, "joints": m.joints, "groups": m.groups}
                for m in found.modes
                if m.assembled and m.same_as is None
            ],
            "modes_at": found.input,
        }

    # ---------------------------------------------------------------- saving
    def save(self, request: dict[str, Any]) -> dict[str, Any]:
        """Write ``doc`` to the file, if the file is still as the editor last saw it (``base``).

        The old file is copied to ``FILE.bak`` first (a link of that name is replaced, never
        followed; the copy takes the file's mode and owner); the new text replaces the file in one
        step (:func:`~linkagekit.files.write_atomic`; a link FILE is followed).  A read-only file
        (no owner write bit) is not saved.  The file's comments are kept where its lines are
        (:meth:`_text_to_save`).  The saved file is read back and must give the same mechanism.

        No other writer's change is lost in between: the saves of this file in this process take turns
        (:func:`path_lock`), each holds an advisory lock on the file (:func:`~linkagekit.files.locked`, which
        another ``linkagekit edit`` or a program run under ``flock FILE`` honours) from its read to its
        rename, and the last step before the rename checks that the file is still the one read, unchanged
        (:meth:`_unchanged`).  A program that writes without the lock can still slip in between that check
        and the rename (microseconds), or write through a descriptor it opened before the rename (into the
        replaced file, which has no name any more): only mandatory locks, which POSIX does not have, could
        exclude it.
        """
        doc = request.get("doc")
        if not isinstance(doc, dict):
            raise InputError("the request has no mechanism document ('doc')")
        base = request.get("base", self.base)
        if not isinstance(base, str):
            raise RequestError(f"'base' must be the file's hash the page was given, got {shorten(repr(base))}")
        mech = Mechanism.from_dict(doc, source=str(self.path))
        with path_lock(self.path), self.lock, locked(self.path, LOCK_SECONDS, self._locked_out):
            old, st = self._read_now("not saved")
            if _hash(old) != base or _hash(old) != self.base:
                raise ConflictError(
                    f"{self.name} changed on disk since it was opened or saved here: not overwritten "
                    "(reload the page to edit the file as it is now)"
                )
            if not st.st_mode & stat.S_IWUSR:
                raise ConflictError(f"{self.name} is read-only: not saved")
            old_text = old.decode("utf-8-sig", errors="replace")
            text = self._text_to_save(mech, old_text)
            write_atomic(self.backup, old, follow=False, like=st)
            write_atomic(self.path, text.encode("utf-8"), before_replace=self._unchanged(old, st))
            data, _ = self._read_now("saved, but it cannot be read back")
            if from_bytes(data, self.path) != mech:  # pragma: no cover - save and load are tested to round-trip
                raise LinkageError(f"{self.path}: the saved file does not read back as the edited mechanism")
            self.base = _hash(data)
            self.mech = mech
            self.text = data.decode("utf-8")
            self.texts = [self.text, *self.texts[:-1][: KEPT_TEXTS - 2], self.texts[-1]]
        return {"ok": True, "base": self.base, "saved": str(self.path), "backup": str(self.backup), "text": self.text}

    def _locked_out(self, why: str) -> ConflictError:
        """The answer to a save whose file another program kept locked past :data:`LOCK_SECONDS`."""
        return ConflictError(f"{self.name} is {why}: not saved (save again when that program is done)")

    def _unchanged(self, old: bytes, st: os.stat_result) -> Callable[[Path], None]:
        """The last check of a save, just before its rename: the file (``target``) is still the one read (``st``),
        with the same size and times and the same bytes (``old``); else :class:`ConflictError`, nothing replaced."""

        def check(target: Path) -> None:
            try:
                now = os.lstat(target)
                same = os.path.samestat(now, st) and _stamp(now) == _stamp(st)
                same = same and read_mechanism_file(target)[0] == old
            except (OSError, LinkageError):
                same = False
            if not same:
                raise ConflictError(
                    f"{self.name} changed on disk while it was being saved (another program wrote it): not "
                    "overwritten (reload the page to edit the file as it is now)"
                )

        return check

    def _text_to_save(self, mech: Mechanism, old_text: str) -> str:
        """The file's new text: :func:`~linkagekit.files.dumps` in the old file's styles (where it has none, in
        those of the file as opened or saved before: an undone edit writes the file's ``49`` back, not ``49.0``),
        with the old file's comments put back where its lines match (:func:`~linkagekit.files.merge_comments`)
        when that text reads as the edited mechanism, else with its leading comment lines only."""
        body = dumps(mech, self.fmt, like=old_text, earlier=self.texts)
        if self.fmt != "yaml":
            return body
        merged = merge_comments(old_text, body)
        try:
            if Mechanism.from_dict(yaml_data(merged, str(self.path)), source=str(self.path)) == mech:
                return merged
        except LinkageError:
            pass
        return _leading_comments(old_text) + body

    # ---------------------------------------------------------------- the page
    def page(self, token: str) -> str:
        """The editor page: the report of the file's sweep, with the editor's script and state.

        The file is read again first (:meth:`refresh`): when another program changed it, the page
        edits it as it is now.
        """
        from ..api import analyze
        from .report import report_html

        self.refresh()
        inputs, index = sweep_with_pose(self.mech)
        res = analyze(self.mech, inputs)
        first = self.solve({"doc": self.mech.to_dict()})  # checks, modes, lengths: as after each edit
        state = {
            "token": token,
            "base": self.base,
            "file": self.name,
            "format": self.fmt,
            "pose_index": index,
            "answer": {k: v for k, v in first.items() if k != "scene"},
        }
        return report_html(res, source=self.text, checks_text=first.get("checks"), editor=state, start=index)


class SolveStopped(BaseException):
    """Raised inside a solve's thread by :class:`Watch`: its time budget is spent, or its client left.

    A ``BaseException``, so that no ``except Exception`` of the solver can swallow it; the
    request handler catches it (and only it).
    """


@dataclass
class _Solve:
    """One solve under way: the thread computing it, its client's socket, its deadline."""

    thread_id: int
    sock: socket.socket
    deadline: float
    #: why it was stopped ("budget" or "gone"), once the watch has stopped it
    reason: str | None = None


def _raise_in(thread_id: int, exc: type[BaseException] | None) -> None:
    """Have ``exc`` raised in thread ``thread_id`` at its next bytecode (``None``: cancel a pending one)."""
    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread_id), ctypes.py_object(exc) if exc else None)


def client_gone(sock: socket.socket) -> bool:
    """True when the peer of ``sock`` has closed or reset its connection (nothing is consumed)."""
    try:
        if hasattr(select, "poll"):
            poller = select.poll()
            poller.register(sock.fileno(), select.POLLIN)
            readable = bool(poller.poll(0))
        else:  # pragma: no cover - Windows
            readable = bool(select.select([sock], [], [], 0)[0])
        return readable and sock.recv(1, socket.MSG_PEEK) == b""
    except (OSError, ValueError):
        return True


class Watch:
    """The solves under way, each stopped at its deadline or as soon as its client has gone.

    The numerical walk of a class-3 group is a Python loop over samples, so a solve is stopped
    between two steps of it: :class:`SolveStopped` is raised in the solve's thread (CPython's
    ``PyThreadState_SetAsyncExc``), which unwinds it like any exception.  The solver itself
    knows nothing of this.  One daemon thread looks every :data:`WATCH_INTERVAL` seconds.

    Parameters
    ----------
    seconds : float
        The time budget of one solve (wall clock).
    """

    def __init__(self, seconds: float = SOLVE_SECONDS) -> None:
        self.seconds = float(seconds)
        self.lock = threading.Lock()
        self.solves: dict[int, _Solve] = {}
        self.thread: threading.Thread | None = None
        self.stopped = {"budget": 0, "gone": 0}

    @contextlib.contextmanager
    def solving(self, sock: socket.socket) -> Iterator[_Solve]:
        """Watch the solve that runs in this block; :class:`SolveStopped` may be raised anywhere in it."""
        solve = _Solve(threading.get_ident(), sock, time.monotonic() + self.seconds)
        with self.lock:
            self.solves[solve.thread_id] = solve
            if self.thread is None:
                self.thread = threading.Thread(target=self._run, name="linkagekit-edit-watch", daemon=True)
                self.thread.start()
        try:
            yield solve
        finally:
            with self.lock:
                self.solves.pop(solve.thread_id, None)
                if solve.reason is not None:
                    _raise_in(solve.thread_id, None)  # sent as the solve finished: not raised after it

    def _run(self) -> None:
        while True:
            time.sleep(WATCH_INTERVAL)
            now = time.monotonic()
            with self.lock:
                for solve in list(self.solves.values()):
                    reason = "budget" if now > solve.deadline else "gone" if client_gone(solve.sock) else None
                    if reason is not None:  # stopped once: it leaves the watch at once
                        solve.reason = reason
                        self.stopped[reason] += 1
                        del self.solves[solve.thread_id]
                        _raise_in(solve.thread_id, SolveStopped)


#: the headers of every answer, besides its status, type, length and connection
_HEADERS = (
    ("Cache-Control", "no-store"),
    ("X-Content-Type-Options", "nosniff"),
    ("Referrer-Policy", "no-referrer"),
    (
        "Content-Security-Policy",
        "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data: blob:; "
        "connect-src 'self'; form-action 'none'; frame-ancestors 'none'",
    ),
)


class _Arrival(io.RawIOBase):
    """A connection's bytes as they arrive, every read within what is left of the request's ``deadline``.

    A socket's own timeout bounds each read, not their sum: a client that sends a byte now and then
    would hold its connection (and its thread) forever.  Past the deadline a read raises
    :class:`TimeoutError`, and the standard library's handler drops the connection.  A read waits
    :data:`READ_SLICE` at a time, so that a deadline brought forward (:meth:`hurry`) counts at once.
    The socket's timeout is :data:`TIMEOUT` again after each read, for the answer's writes.
    """

    def __init__(self, sock: socket.socket) -> None:
        super().__init__()
        self.sock = sock
        self.deadline = math.inf

    def readable(self) -> bool:
        return True

    def hurry(self, seconds: float) -> None:
        """Have the request arrive within ``seconds`` from now, if its deadline is later (from another thread)."""
        self.deadline = min(self.deadline, time.monotonic() + seconds)

    def readinto(self, buffer: Any) -> int:
        while True:
            left = self.deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("the request did not arrive in time")
            self.sock.settimeout(min(left, READ_SLICE))
            try:
                return self.sock.recv_into(buffer)
            except TimeoutError:
                continue  # look at the deadline again: it may have been brought forward
            finally:
                self.sock.settimeout(TIMEOUT)


class _Handler(BaseHTTPRequestHandler):
    """One connection's requests: check where each comes from and what it asks, then answer it in JSON (or the page).

    Each request must arrive whole (request line, headers, body) within :data:`TIMEOUT` of when it is
    awaited (:class:`_Arrival`), or the connection is dropped.
    """

    server: EditorServer
    protocol_version = "HTTP/1.1"

    def setup(self) -> None:
        super().setup()
        self.connection.settimeout(TIMEOUT)  # read now, not at import: the tests shorten it
        self.rfile.close()  # the standard library's reader, replaced by one with a deadline
        self.arrival = _Arrival(self.connection)
        self.rfile = io.BufferedReader(self.arrival)
        with self.server.lock:
            self.server.arrivals.add(self.arrival)

    def finish(self) -> None:
        with self.server.lock:
            self.server.arrivals.discard(self.arrival)
        super().finish()

    def handle_one_request(self) -> None:
        self.arrival.deadline = time.monotonic() + TIMEOUT
        super().handle_one_request()

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base class's name
        pass  # quiet: the terminal shows the URL, not a request log

    #: set once an answer's status line is sent: an error after it cannot be answered any more
    answered = False

    def _send(self, code: int, body: bytes, ctype: str, with_body: bool = True) -> None:
        self.answered = True
        self.send_response(code)
        if code >= 400:
            # a refused request may leave its body unread on the connection: close it, so
            # that the next request is not read from the middle of this one
            self.send_header("Connection", "close")
            self.close_connection = True
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        for name, value in _HEADERS:
            self.send_header(name, value)
        self.end_headers()
        if with_body:
            self.wfile.write(body)

    def _json(self, code: int, doc: dict[str, Any], with_body: bool = True) -> None:
        text = json.dumps(doc, allow_nan=False, separators=(",", ":"), ensure_ascii=False)
        self._send(code, shown(text).encode("utf-8"), "application/json", with_body)

    def _html(self, code: int, message: str) -> None:
        """A short page that says ``message`` (what the browser shows where the editor would be)."""
        body = f"<!DOCTYPE html><title>linkagekit editor</title><p>{html.escape(message)}</p>"
        self._send(code, shown(body).encode("utf-8"), "text/html; charset=utf-8")

    def send_error(self, code: int, message: str | None = None, explain: str | None = None) -> None:
        """The standard library's error answers (an unknown method, a malformed request line or header) in the
        editor's JSON, with its headers, instead of its HTML page."""
        text = message or self.responses.get(code, ("error",))[0]
        if self.request_version == "HTTP/0.9":  # a request line it could not read: answer with a status and headers
            self.request_version = "HTTP/1.0"
        self.close_connection = True
        self._json(code, {"ok": False, "error": one_line(text, 200)}, with_body=self.command != "HEAD")

    def _guarded(self, handle: Any) -> None:
        """Run ``handle``; an exception it did not expect is answered 500 in one line (and one line on stderr),
        or, once the answer has begun, only reported; a client that went away is not answered."""
        self.answered = False  # one handler answers every request of a kept-alive connection
        try:
            handle()
        except VANISHED:
            raise
        except Exception as exc:  # noqa: BLE001 - a request must never go unanswered
            if self.answered:
                raise
            line = f"internal error: {type(exc).__name__}: {one_line(str(exc), 150)}"
            print(f"linkagekit edit: a request failed: {line}", file=sys.stderr, flush=True)
            self._json(500, {"ok": False, "error": line})

    def _allowed(self) -> str | None:
        """The path after the token, or None after answering 403."""
        srv = self.server
        host = self.headers.get("Host", "")
        if host not in srv.hosts:
            self._json(403, {"ok": False, "error": "forbidden: wrong Host"})
            return None
        origin = self.headers.get("Origin")
        if origin is not None and origin not in srv.origins:
            self._json(403, {"ok": False, "error": "forbidden: another origin"})
            return None
        parts = urlsplit(self.path)
        prefix = f"/{srv.token}/"
        if parts.query or not parts.path.startswith(prefix):
            self._json(403, {"ok": False, "error": "forbidden"})
            return None
        rest = parts.path[len(prefix) :]
        if rest not in srv.routes:
            self._json(403, {"ok": False, "error": "forbidden"})
            return None
        return rest

    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        self._guarded(self._get)

    def do_POST(self) -> None:  # noqa: N802 - http.server's name
        self._guarded(self._post)

    def _get(self) -> None:
        rest = self._allowed()
        if rest is None:
            return
        if rest != "":
            self._json(405, {"ok": False, "error": "use POST"})
            return
        try:
            with self.server.watch.solving(self.connection) as solve:
                page = self.server.session.page(self.server.token)
        except SolveStopped:
            self._stopped(solve, page=True)
            return
        except ConflictError as exc:  # the file changed on disk and no longer loads, or is gone
            self._html(409, one_line(str(exc), 300))
            return
        except LinkageError as exc:
            self._json(500, {"ok": False, "error": one_line(str(exc), 300)})
            return
        self._send(200, shown(page).encode("utf-8"), "text/html; charset=utf-8")

    def _stopped(self, solve: _Solve, page: bool = False) -> None:
        """Answer a solve the watch stopped: nothing when its client left, else a message naming the budget.

        A solve request gets JSON; the page itself (``page``) a short HTML page, and the same
        message as one line in the terminal, since nothing else would show it.
        """
        if solve.reason == "gone":
            self.close_connection = True
            return
        seconds = self.server.watch.seconds
        if page:
            message = (
                f"the page took longer than the editor's solve budget ({seconds:g} s): give the file's drivers "
                "a coarser sweep (a larger step or a shorter range), or start the editor with a larger --solve-seconds"
            )
            print(f"linkagekit: {message}", file=sys.stderr, flush=True)
            self._html(503, message)
            return
        self._json(
            503,
            {
                "ok": False,
                "stopped": True,
                "error": f"stopped after {seconds:g} s, the editor's time budget for one solve: "
                "sweep fewer samples (a larger step or a shorter range) and try again",
            },
        )

    def _post(self) -> None:
        rest = self._allowed()
        if rest is None:
            return
        if rest == "":
            self._json(405, {"ok": False, "error": "use GET"})
            return
        if self.headers.get("Content-Type", "").split(";")[0].strip() != "application/json":
            self._json(415, {"ok": False, "error": "send application/json"})
            return
        try:
            length = int(self.headers.get("Content-Length", ""))
        except ValueError:
            self._json(411, {"ok": False, "error": "a Content-Length is needed"})
            return
        if not 0 <= length <= MAX_BODY:
            self._json(413, {"ok": False, "error": f"a request of at most {MAX_BODY} bytes"})
            return
        request = _parse(self.rfile.read(length))
        if isinstance(request, str):
            self._json(400, {"ok": False, "error": request})
            return
        if rest == "api/save":  # never stopped half-way: a save is short, and writes
            self._json(*self._answer(rest, request))
            return
        try:
            with self.server.watch.solving(self.connection) as solve:
                answer = self._answer(rest, request)
        except SolveStopped:
            self._stopped(solve)
            return
        self._json(*answer)

    def _answer(self, call: str, request: dict[str, Any]) -> tuple[int, dict[str, Any]]:
        """The status and JSON answer of a solve or save (written by the caller, outside these excepts)."""
        session = self.server.session
        try:
            return 200, session.solve(request) if call == "api/solve" else session.save(request)
        except ConflictError as exc:
            return 409, {"ok": False, "error": one_line(str(exc), 300), "conflict": True}
        except RequestError as exc:
            return 400, {"ok": False, "error": one_line(str(exc), 300)}
        except LinkageError as exc:
            # a document that does not solve: the page keeps its last good picture and shows this
            return 200, {"ok": False, "error": one_line(str(exc), 300)}
        except Exception as exc:  # noqa: BLE001 - a request must never take the server down
            return 500, {"ok": False, "error": f"internal error: {type(exc).__name__}: {one_line(str(exc), 200)}"}


def json_depth(value: Any) -> int:
    """The nesting depth of parsed JSON (a scalar: 0), without recursion.

    >>> json_depth({"a": [1, {"b": []}]})
    4
    """
    deepest, stack = 0, [(value, 0)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict | list):
            deepest = max(deepest, depth + 1)
            stack.extend((v, depth + 1) for v in (item.values() if isinstance(item, dict) else item))
    return deepest


def _parse(body: bytes) -> dict[str, Any] | str:
    """A request body's JSON object, or the message (a ``str``) saying why it is refused."""
    try:
        request = json.loads(body.decode("utf-8"), parse_constant=_no_constant)
    except (ValueError, UnicodeDecodeError) as exc:
        return f"bad JSON: {one_line(str(exc), 120)}"
    except RecursionError:  # the parser's own limit (about 1000 levels)
        return f"bad JSON: nested deeper than {MAX_JSON_DEPTH} levels"
    if json_depth(request) > MAX_JSON_DEPTH:
        return f"bad JSON: nested deeper than {MAX_JSON_DEPTH} levels"
    if not isinstance(request, dict):
        return "bad request: expected a JSON object"
    return request


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows")


class EditorServer(ThreadingHTTPServer):
    """The editor's HTTP server on 127.0.0.1 (``port`` 0: a free port)."""

    daemon_threads = True
    #: connections the system holds until the server accepts them (socketserver's default is 5: a burst
    #: of requests beyond it waited for the client's SYN retransmission, a second or more; with 128, 500
    #: clients at once while solves hold the interpreter lost 150 connections, reset: Linux's SYN cookies
    #: admit a connection the full queue then drops).  The system caps it (net.core.somaxconn).
    request_queue_size = 1024
    routes = ("", "api/solve", "api/save")
    #: set once the server stops: a request broken by the shutdown is not reported
    closing = False
    #: set when a connection found no free handler: the next ones are answered 503 at once until one is free
    full = False

    def __init__(
        self, session: Session, port: int = 0, token: str | None = None, solve_seconds: float = SOLVE_SECONDS
    ) -> None:
        if not isinstance(port, int) or isinstance(port, bool) or not 0 <= port <= 65535:
            raise InputError(f"--port: expected 0 to 65535, got {port!r}")
        self.session = session
        self.watch = Watch(solve_seconds)
        #: the free connection handlers (:data:`MAX_CONNECTIONS`, read now: the tests lower it)
        self.slots = threading.BoundedSemaphore(MAX_CONNECTIONS)
        #: the readers of the connections served now (:meth:`_crowded` brings their deadlines forward)
        self.arrivals: set[_Arrival] = set()
        #: the connections that hold one of :attr:`slots` (:meth:`_free` gives it back once)
        self.holding: set[Any] = set()
        self.lock = threading.Lock()
        self.token = token or secrets.token_urlsafe(24)
        try:
            super().__init__(("127.0.0.1", port), _Handler)
        except OSError as exc:
            raise InputError(f"--port {port}: cannot listen on 127.0.0.1 ({exc.strerror or exc})") from None
        self.port = int(self.server_address[1])
        self.hosts = {f"127.0.0.1:{self.port}", f"localhost:{self.port}"}
        self.origins = {f"http://{h}" for h in self.hosts}

    def process_request(self, request: Any, client_address: Any) -> None:
        """Serve the connection in a thread of its own once one of the :data:`MAX_CONNECTIONS` is free.

        This runs in the accepting thread: it waits for a free handler up to :data:`BUSY_SECONDS`
        (meanwhile the system queues the connections that come), then answers 503 (:meth:`_busy`), and,
        until a handler is free again, answers the next connections 503 at once (a queue of them must not
        wait :data:`BUSY_SECONDS` each).  While it waits, the requests under way must arrive within
        :data:`CROWDED_SECONDS` (:meth:`_crowded`).  A server that stops ends the wait.
        """
        deadline = time.monotonic() + (0.0 if self.full else BUSY_SECONDS)
        while not self.slots.acquire(timeout=min(0.1, max(0.0, deadline - time.monotonic()))):
            self._crowded()
            if self.closing or time.monotonic() >= deadline:
                self.full = True
                self._busy(request)
                return
        self.full = False
        with self.lock:
            self.holding.add(request)
        try:
            super().process_request(request, client_address)
        except BaseException:  # no thread, or a signal while it started: its handler is free again
            self._free(request)
            raise

    def _free(self, request: Any) -> None:
        """Give back the handler ``request`` holds, once: its thread and the accepting thread may both try (a
        SIGINT in ``Thread.start`` comes after the thread began; a second release would raise ValueError
        in place of the KeyboardInterrupt, and the server would go on serving)."""
        with self.lock:
            if request not in self.holding:
                return
            self.holding.remove(request)
        self.slots.release()

    def _crowded(self) -> None:
        """Every handler is taken and a connection waits: the connections that are still to send their request
        (idle kept-alive ones, stalled clients) must send it within :data:`CROWDED_SECONDS`, or make room."""
        with self.lock:
            for arrival in self.arrivals:
                arrival.hurry(CROWDED_SECONDS)

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            self._free(request)

    def _busy(self, request: socket.socket) -> None:
        """Answer 503 to a connection no handler was free for, without ever waiting on it (the accepting thread)."""
        body = json.dumps({"ok": False, "busy": True, "error": "the editor is busy: try again"}).encode()
        head = [
            "HTTP/1.1 503 Service Unavailable",
            "Content-Type: application/json",
            f"Content-Length: {len(body)}",
            "Connection: close",
            "Retry-After: 1",
            *(f"{name}: {value}" for name, value in _HEADERS),
        ]
        with contextlib.suppress(OSError):
            request.setblocking(False)
            with contextlib.suppress(BlockingIOError):
                request.recv(1 << 16)  # what arrived of its request: closed unread, it would reset the connection
            request.send("\r\n".join(head).encode() + b"\r\n\r\n" + body)
        self.shutdown_request(request)

    def handle_error(self, request: Any, client_address: Any) -> None:
        """Report a request that failed: nothing for a client that went away, one line for anything else.

        socketserver's default prints a traceback between dashed lines.  A client that closes its
        connection before its answer (the page sends a newer request, the tab is closed), one that
        stops sending (:data:`TIMEOUT`), and a socket error while the server stops are normal here.
        """
        exc = sys.exc_info()[1]
        if isinstance(exc, VANISHED) or (self.closing and isinstance(exc, OSError)):
            return
        where = client_address[0] if isinstance(client_address, tuple) and client_address else "a client"
        print(
            f"linkagekit edit: a request from {where} failed: {type(exc).__name__}: {one_line(str(exc), 120)}",
            file=sys.stderr,
        )

    def shutdown(self) -> None:
        """Stop :meth:`serve_forever` (from another thread); requests broken by it are not reported."""
        self.closing = True
        super().shutdown()

    def server_close(self) -> None:
        """Close the listening socket; requests broken by it are not reported."""
        self.closing = True
        super().server_close()

    @property
    def url(self) -> str:
        """The page's address, with its token."""
        return f"http://127.0.0.1:{self.port}/{self.token}/"


def serve(
    path: str | Path, port: int = 0, open_browser: bool = True, ready: Any = None, solve_seconds: float = SOLVE_SECONDS
) -> None:
    """Serve the editor of ``path`` until interrupted; print its URL first (docs/commands.md, `edit`)."""
    session = Session(path)
    server = EditorServer(session, port, solve_seconds=solve_seconds)
    print(server.url, flush=True)
    if ready is not None:
        ready(server)
    with contextlib.ExitStack() as stack:
        stack.callback(server.server_close)
        if open_browser:
            import webbrowser

            private = stack.enter_context(redirect_file(server.url))
            threading.Thread(target=webbrowser.open, args=(private.as_uri(),), daemon=True).start()
        server.serve_forever(poll_interval=0.2)


@contextlib.contextmanager
def redirect_file(url: str) -> Iterator[Path]:
    """A private page that sends the browser to ``url``, for as long as the block runs.

    The browser is opened on this file, not on the URL: a browser's command line can be read by
    every local user (``/proc/PID/cmdline``), and the URL's token is all that guards the editor.
    The file is readable by its owner only (0600, in a fresh 0700 directory); it and its directory
    are removed when the block ends.
    """
    folder = Path(tempfile.mkdtemp(prefix="linkagekit-edit-"))
    try:
        page = folder / "open-editor.html"
        fd = os.open(page, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600)
        link = html.escape(url)
        with open(fd, "w", encoding="utf-8") as f:
            f.write(
                f'<!DOCTYPE html><meta charset="utf-8"><meta http-equiv="refresh" content="0;url={link}">'
                f"<title>linkagekit editor</title><script>window.location.replace({json.dumps(url)})</script>"
                f'<p><a href="{link}">Open the linkagekit editor</a></p>\n'
            )
        yield page
    finally:
        shutil.rmtree(folder, ignore_errors=True)
