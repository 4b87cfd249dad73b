"""``linkagekit edit`` under concurrent writers and hostile connections (review 8's open defects).

* Lost update: two sessions of one file (two editors, two tabs) never both save over each other;
  a write by another program in the instant before the rename (in place or by a rename) is not
  overwritten; a program that holds an ``flock`` on the file is waited for, and its change is seen;
  a lock held past ``LOCK_SECONDS`` is a conflict in one line, the file left alone.
* Stalled clients: a connection that sends part of a request and then trickles bytes (each read
  within the socket's timeout) or sends nothing more is dropped within ``TIMEOUT`` of when its request
  was awaited, while another client is answered at once; a request sent in pieces within the timeout,
  and a kept-alive connection's next request, are answered.
* Bounded handlers: more idle connections than ``MAX_CONNECTIONS`` never run more handler threads than
  that, and a normal request is answered once the idle ones time out; with every handler held, a
  connection is answered 503 (JSON) after ``BUSY_SECONDS``, and served again once one is freed.

Timeouts are the module's constants, shortened here so that no test takes more than a few seconds.
"""

from __future__ import annotations

import contextlib
import fcntl
import http.client
import json
import os
import socket
import threading
import time
from pathlib import Path

import pytest

import linkagekit as lk
from linkagekit.web import editor
from linkagekit.web.editor import ConflictError, EditorServer, Session
from test_editor import Client, _requests_in_flight, _serve, _stop, copy_example


@pytest.fixture
def server(tmp_path):
    """An in-process editor server on a copy of seed000 (as test_editor's)."""
    srv = _serve(Session(copy_example(tmp_path)))
    yield srv
    _stop(srv)


def _saves(*docs: tuple[Session, dict]) -> tuple[list[object], list[threading.Thread]]:
    """Each (session, doc) saved in a thread of its own, started: the answers (or exceptions) as they come, in that
    order, and the threads."""
    out: list[object] = [None] * len(docs)

    def one(i: int, s: Session, doc: dict) -> None:
        try:
            out[i] = s.save({"doc": doc, "base": s.base})
        except Exception as exc:  # noqa: BLE001 - returned to the test
            out[i] = exc

    threads = [threading.Thread(target=one, args=(i, s, d), daemon=True) for i, (s, d) in enumerate(docs)]
    for t in threads:
        t.start()
    return out, threads


# ============================================================================== lost updates
def test_two_sessions_of_one_file_never_both_save_over_each_other(tmp_path, monkeypatch):
    """Two editors of one file (here two sessions, one named through a link) both opened it; A's save is held
    between its check and its rename while B saves. B must wait for A and then be refused (409: the file
    changed since B opened it): the file is A's, and B's change is not silently lost over A's, nor A's under B's."""
    path = copy_example(tmp_path)
    alias = tmp_path / "alias.yaml"
    alias.symlink_to(path)
    a, b = Session(path), Session(alias)
    held, go = threading.Event(), threading.Event()
    real = editor.write_atomic

    def slow_write(p, data, *args, **kw):
        if threading.current_thread().name == "A" and Path(p) == path:
            held.set()
            go.wait(5)
        return real(p, data, *args, **kw)

    monkeypatch.setattr(editor, "write_atomic", slow_write)
    doc = a.mech.to_dict()
    out: dict[str, object] = {}

    def save(name: str, s: Session) -> None:
        try:
            out[name] = s.save({"doc": doc | {"name": name}, "base": s.base})
        except Exception as exc:  # noqa: BLE001 - checked below
            out[name] = exc

    ta = threading.Thread(target=save, args=("A", a), name="A", daemon=True)
    ta.start()
    assert held.wait(5)
    tb = threading.Thread(target=save, args=("B", b), name="B", daemon=True)
    tb.start()
    tb.join(0.5)
    waited = tb.is_alive()
    go.set()
    ta.join(10)
    tb.join(10)
    assert waited, f"B's save did not wait for A's: {out.get('B')!r}"
    assert isinstance(out["A"], dict) and out["A"]["ok"] is True, out
    assert isinstance(out["B"], ConflictError) and "changed on disk" in str(out["B"]), out
    assert lk.load(path).name == "A"
    assert alias.is_symlink()


def _outside_write(path: Path, how: str) -> None:
    """Another program writes the file: in place (same length, same inode) or by a rename of a new file over it."""
    text = path.read_text().replace("Four-bar", "OUTSIDE!", 1)
    assert len(text) == len(path.read_text())
    if how == "in place":
        with open(path, "r+", encoding="utf-8") as f:
            f.write(text)
    else:
        other = path.with_name("outside.tmp")
        other.write_text(text)
        os.replace(other, path)


@pytest.mark.parametrize("how", ["in place", "by a rename"])
def test_a_write_just_before_the_rename_is_not_overwritten(tmp_path, monkeypatch, how):
    """Another program writes FILE after the save's hash check, as the new file is synced (the last step before
    its rename): the save is refused (409), FILE keeps that program's text, no temporary file is left, and the
    session still knows FILE as it opened it (a save after a reload works)."""
    from linkagekit import files

    path = copy_example(tmp_path)
    s = Session(path)
    real_fsync = os.fsync

    def fsync_then_write(fd: int) -> None:
        real_fsync(fd)
        name = os.readlink(f"/proc/self/fd/{fd}")
        if Path(name).name.startswith(f".{path.name}.") and ".bak." not in name:
            _outside_write(path, how)

    monkeypatch.setattr(files.os, "fsync", fsync_then_write)
    base = s.base
    with pytest.raises(ConflictError, match="changed on disk while it was being saved") as info:
        s.save({"doc": s.mech.to_dict() | {"name": "mine"}, "base": s.base})
    monkeypatch.undo()
    assert "\n" not in str(info.value)
    assert "OUTSIDE" in path.read_text() and lk.load(path).name != "mine"
    assert sorted(p.name for p in path.parent.iterdir()) == sorted([path.name, path.name + ".bak"])
    assert s.base == base
    s.refresh()
    assert s.save({"doc": s.mech.to_dict() | {"name": "mine"}, "base": s.base})["ok"] is True
    assert lk.load(path).name == "mine"


def test_a_save_waits_for_a_program_holding_an_flock_and_sees_its_change(tmp_path):
    """A program holds an exclusive flock on FILE while it rewrites it in place (as ``flock FILE cmd`` would):
    a save that starts meanwhile waits for the lock, then sees the change and is refused (409); the program's
    text stays (it is not written into a file the save has already replaced)."""
    path = copy_example(tmp_path)
    s = Session(path)
    locked, release = threading.Event(), threading.Event()

    def program() -> None:
        with open(path, "r+", encoding="utf-8") as f:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX)
            locked.set()
            release.wait(5)
            text = f.read().replace("Four-bar", "OUTSIDE!", 1)
            f.seek(0)
            f.write(text)
            f.flush()
            fcntl.flock(f.fileno(), fcntl.LOCK_UN)

    t = threading.Thread(target=program, daemon=True)
    t.start()
    assert locked.wait(5)
    out, (saver,) = _saves((s, s.mech.to_dict() | {"name": "mine"}))
    saver.join(0.3)
    waited = saver.is_alive()
    release.set()
    t.join(5)
    saver.join(5)
    assert waited, f"the save did not wait for the lock: {out[0]!r}"
    assert isinstance(out[0], ConflictError) and "changed on disk" in str(out[0]), out
    assert "OUTSIDE" in path.read_text() and lk.load(path).name != "mine"


def test_a_lock_held_past_the_wait_is_a_conflict_in_one_line(tmp_path, monkeypatch):
    """A program that keeps its flock on FILE longer than LOCK_SECONDS (0.2 s here): the save is refused in one
    line naming the file and the lock, soon after LOCK_SECONDS; FILE and its backup are left alone."""
    monkeypatch.setattr(editor, "LOCK_SECONDS", 0.2)
    path = copy_example(tmp_path)
    original = path.read_bytes()
    s = Session(path)
    with open(path, "rb") as f:
        fcntl.flock(f.fileno(), fcntl.LOCK_EX)
        t0 = time.monotonic()
        with pytest.raises(ConflictError) as info:
            s.save({"doc": s.mech.to_dict() | {"name": "mine"}, "base": s.base})
        elapsed = time.monotonic() - t0
    msg = str(info.value)
    assert msg.startswith(f"{path.name} is locked by another program") and "not saved" in msg and "\n" not in msg
    assert 0.2 <= elapsed < 2.0, elapsed
    assert path.read_bytes() == original and not path.with_name(path.name + ".bak").exists()
    assert s.save({"doc": s.mech.to_dict() | {"name": "mine"}, "base": s.base})["ok"] is True  # released: saved


def test_a_save_over_http_against_a_held_lock_is_409(tmp_path, monkeypatch):
    """The same over HTTP: 409 with the one-line message and ``conflict``; the server keeps serving."""
    monkeypatch.setattr(editor, "LOCK_SECONDS", 0.2)
    path = copy_example(tmp_path)
    srv = _serve(Session(path))
    try:
        c = Client(srv)
        with open(path, "rb") as f:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX)
            status, _, body = c.save({"doc": srv.session.mech.to_dict(), "base": srv.session.base})
        got = json.loads(body)
        assert status == 409 and got["conflict"] is True and "locked by another program" in got["error"], got
        c.still_serving()
    finally:
        _stop(srv)


# ============================================================================== stalled clients
def _dropped(s: socket.socket, trickle: bytes, until: float) -> float | None:
    """Send ``trickle`` a byte every 0.1 s (each read of the server well within its timeout) until the server
    closes the connection: the time it did, or None if it had not by ``until``."""
    s.settimeout(0.1)
    for i in range(10_000):
        now = time.monotonic()
        if now > until:
            return None
        try:
            if s.recv(1) == b"":
                return now
        except TimeoutError:
            pass
        except ConnectionResetError:
            return now
        try:
            s.sendall(trickle[i % len(trickle) : i % len(trickle) + 1])
        except (BrokenPipeError, ConnectionResetError):
            return time.monotonic()
    return None


def _stalled_requests(srv: EditorServer) -> dict[str, tuple[bytes, bytes]]:
    """What a stalled client sends first, and then trickles."""
    head = f"POST /{srv.token}/api/solve HTTP/1.1\r\nHost: 127.0.0.1:{srv.port}\r\n"
    body = json.dumps({"doc": srv.session.mech.to_dict()}).encode()
    full = (head + f"Content-Type: application/json\r\nContent-Length: {len(body)}\r\n\r\n").encode()
    return {
        "half a request line": (f"GET /{srv.token}".encode(), b"/"),
        "headers, trickled": (head.encode(), b"X-Slow: a\r\n"),
        "headers, then half the body, trickled": (full + body[:100], b" "),
    }


@pytest.mark.parametrize("what", ["half a request line", "headers, trickled", "headers, then half the body, trickled"])
def test_a_stalled_client_is_dropped_within_the_timeout(server, monkeypatch, what):
    """A client sends part of a request, then a byte every 0.1 s (so that no single read of the server waits long)
    and never finishes. The server drops it within TIMEOUT (0.5 s here) of when it awaited the request, plus
    a margin, and answers another client meanwhile at once."""
    monkeypatch.setattr(editor, "TIMEOUT", 0.5)
    first, trickle = _stalled_requests(server)[what]
    s = socket.create_connection(("127.0.0.1", server.port), timeout=5)
    t0 = time.monotonic()
    s.sendall(first)
    c = Client(server)
    w0 = time.monotonic()
    status, _, _ = c.page()
    assert status == 200 and time.monotonic() - w0 < 2.0
    gone = _dropped(s, trickle, t0 + 3.0)
    s.close()
    assert gone is not None, f"{what}: still connected 3 s after it began (TIMEOUT 0.5 s)"
    assert 0.4 <= gone - t0 <= 1.5, f"{what}: dropped {gone - t0:.2f} s after it began (TIMEOUT 0.5 s)"


def test_a_client_that_sends_headers_then_nothing_is_dropped(server, monkeypatch):
    """A POST's headers and then silence (the body never comes): dropped within TIMEOUT plus a margin."""
    monkeypatch.setattr(editor, "TIMEOUT", 0.5)
    first, _ = _stalled_requests(server)["headers, then half the body, trickled"]
    s = socket.create_connection(("127.0.0.1", server.port), timeout=3)
    t0 = time.monotonic()
    s.sendall(first)
    with contextlib.suppress(ConnectionResetError):
        assert s.recv(1) == b""
    s.close()
    assert time.monotonic() - t0 <= 1.5


def test_requests_within_the_timeout_are_answered(server, monkeypatch):
    """The deadline is per request: on one kept-alive connection, three requests each sent in three pieces 0.05 s
    apart, 0.2 s after the previous answer, are all answered, though the connection lives longer than TIMEOUT."""
    monkeypatch.setattr(editor, "TIMEOUT", 0.5)
    doc = json.dumps({"doc": server.session.mech.to_dict(), "coarse": True}).encode()
    head = (
        f"POST /{server.token}/api/solve HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n"
        f"Content-Type: application/json\r\nContent-Length: {len(doc)}\r\n\r\n"
    ).encode()
    sock = socket.create_connection(("127.0.0.1", server.port), timeout=5)
    t0 = time.monotonic()
    for _ in range(3):
        time.sleep(0.2)
        for piece in (head[:20], head[20:] + doc[:50], doc[50:]):
            sock.sendall(piece)
            time.sleep(0.05)
        r = http.client.HTTPResponse(sock)
        r.begin()
        assert r.status == 200 and json.loads(r.read())["ok"] is True
    assert time.monotonic() - t0 > 0.5
    sock.close()
    Client(server).still_serving()


# ============================================================================== bounded handlers
def _handlers() -> int:
    return len(_requests_in_flight())


def test_idle_connections_beyond_the_limit_wait_for_a_free_handler(tmp_path, monkeypatch):
    """10 idle connections against MAX_CONNECTIONS = 4 (TIMEOUT 0.5 s): never more than 4 handler threads, and a
    normal request that came after them is answered once they time out, four at a time (about 1.5 s); every idle
    connection is dropped."""
    monkeypatch.setattr(editor, "MAX_CONNECTIONS", 4)
    monkeypatch.setattr(editor, "TIMEOUT", 0.5)
    monkeypatch.setattr(editor, "BUSY_SECONDS", 3.0)
    srv = _serve(Session(copy_example(tmp_path)))
    try:
        before = _handlers()
        idle = [socket.create_connection(("127.0.0.1", srv.port), timeout=5) for _ in range(10)]
        most = 0
        answer: dict[str, object] = {}

        def normal() -> None:
            t0 = time.monotonic()
            answer["status"] = Client(srv).page()[0]
            answer["seconds"] = time.monotonic() - t0

        t = threading.Thread(target=normal, daemon=True)
        t.start()
        deadline = time.monotonic() + 6
        while t.is_alive() and time.monotonic() < deadline:
            most = max(most, _handlers() - before)
            t.join(0.01)
        assert most <= 4, f"{most} handler threads for a limit of 4"
        assert answer.get("status") == 200 and answer["seconds"] < 4.0, answer
        for s in idle:
            s.settimeout(3)
            with contextlib.suppress(ConnectionResetError):
                assert s.recv(1) == b""
            s.close()
    finally:
        _stop(srv)


def test_a_crowded_server_has_idle_connections_make_room_sooner(tmp_path, monkeypatch):
    """10 idle connections against MAX_CONNECTIONS = 4 with a long TIMEOUT (5 s): once a connection waits for a
    handler, those that have not sent their request must send it within CROWDED_SECONDS (0.3 s here), so a
    normal request that came after them is answered in about 3 x 0.3 s, not 3 x 5 s (the idle ones before it
    dropped). A request under way is not cut: a solve whose request arrived, running on one handler, is answered."""
    monkeypatch.setattr(editor, "MAX_CONNECTIONS", 4)
    monkeypatch.setattr(editor, "TIMEOUT", 5.0)
    monkeypatch.setattr(editor, "CROWDED_SECONDS", 0.3)
    monkeypatch.setattr(editor, "BUSY_SECONDS", 3.0)
    srv = _serve(Session(copy_example(tmp_path)))
    try:
        doc = srv.session.mech.to_dict()
        solving = threading.Thread(target=lambda: answers.append(Client(srv).solve({"doc": doc})[0]), daemon=True)
        answers: list[int] = []
        solving.start()  # a full sweep with checks, taking a handler before the idle connections come
        time.sleep(0.05)
        idle = [socket.create_connection(("127.0.0.1", srv.port), timeout=5) for _ in range(10)]
        t0 = time.monotonic()
        status, _, _ = Client(srv).page()
        took = time.monotonic() - t0
        assert status == 200 and took < 3.0, (status, took)
        solving.join(10)
        assert answers == [200]
        dropped = 0
        for s in idle:
            s.settimeout(0.05)
            try:
                dropped += s.recv(1) == b""
            except ConnectionResetError:
                dropped += 1
            except TimeoutError:
                pass
            s.close()
        assert dropped >= 6, f"{dropped} idle connections made room (at least 10 - 4 had to, for the request)"
    finally:
        _stop(srv)


def test_with_every_handler_held_a_connection_gets_503_then_is_served_once_one_is_free(tmp_path, monkeypatch):
    """MAX_CONNECTIONS = 2 held by two idle connections (TIMEOUT 5 s): a request is answered 503 (the editor's
    JSON, busy) after BUSY_SECONDS (0.6 s), the next one at once (no second wait); once the idle connections
    close, a request is answered 200."""
    monkeypatch.setattr(editor, "MAX_CONNECTIONS", 2)
    monkeypatch.setattr(editor, "TIMEOUT", 5.0)
    monkeypatch.setattr(editor, "BUSY_SECONDS", 0.6)
    srv = _serve(Session(copy_example(tmp_path)))
    try:
        idle = [socket.create_connection(("127.0.0.1", srv.port), timeout=5) for _ in range(2)]
        c = Client(srv)  # its connections queue behind the idle ones, which take the two handlers
        for k in range(2):
            t0 = time.monotonic()
            status, headers, body = c.page()
            took = time.monotonic() - t0
            got = json.loads(body)
            assert status == 503 and got == {"ok": False, "busy": True, "error": "the editor is busy: try again"}
            assert headers.get("Content-Type") == "application/json" and "Content-Security-Policy" in headers
            assert (0.55 <= took < 2.5) if k == 0 else took < 0.5, (k, took)
        for s in idle:
            s.close()
        deadline = time.monotonic() + 5
        while (status := c.page()[0]) == 503 and time.monotonic() < deadline:  # until their handlers have ended
            time.sleep(0.05)
        assert status == 200, "the closed connections still hold their handlers"
        c.still_serving()
    finally:
        _stop(srv)


def test_a_signal_while_a_handler_starts_stops_the_server_and_frees_its_slot(tmp_path, monkeypatch, capsys):
    """SIGINT can land in ``Thread.start`` after the handler's thread began (CI stop 40: the handler freed its
    slot, the accepting thread freed it again, BoundedSemaphore raised ValueError in place of the
    KeyboardInterrupt, and ``linkagekit edit`` went on serving).  Here the thread runs to its end and then the
    interrupt comes: it must propagate as KeyboardInterrupt, and every slot must be free exactly once."""
    import socketserver

    monkeypatch.setattr(editor, "MAX_CONNECTIONS", 3)
    srv = EditorServer(Session(copy_example(tmp_path)), 0)
    done = threading.Event()
    run_thread = srv.process_request_thread

    def thread_then_done(request, address):
        try:
            run_thread(request, address)
        finally:
            done.set()

    start = socketserver.ThreadingMixIn.process_request

    def start_then_signal(self, request, address):
        start(self, request, address)
        assert done.wait(10), "the handler's thread did not finish"
        raise KeyboardInterrupt

    monkeypatch.setattr(srv, "process_request_thread", thread_then_done)
    monkeypatch.setattr(socketserver.ThreadingMixIn, "process_request", start_then_signal)
    ours, theirs = socket.socketpair()
    try:
        theirs.close()  # the handler reads nothing and ends
        with pytest.raises(KeyboardInterrupt):
            srv.process_request(ours, ("127.0.0.1", 1))
        assert all(srv.slots.acquire(blocking=False) for _ in range(3)), "a slot was not given back"
        assert not srv.slots.acquire(blocking=False), "a slot was given back twice"
    finally:
        srv.server_close()
    assert "Semaphore" not in capsys.readouterr().err
