"""Attack ``linkagekit edit`` as issue 23's tester did, and say what held (exit status 1 if anything failed).

Loopback only (127.0.0.1), bounded loops; it stops by itself (a few minutes on a quiet machine).
The editor runs as a child process (``serve`` with a solve budget of BUDGET seconds) on a copy of
``examples/triad_six_modes.yaml`` in a temporary directory, and is attacked with:

1. KILLS ``kill -9`` during saves: a client saves back and forth between two documents while the
   editor is killed at a random moment; after each kill FILE and FILE.bak must load, and the
   next editor started on FILE must remove any temporary file the kill left;
2. 500 concurrent requests (coarse solves and the page), every one of them answered;
3. 200 slow connections (headers sent one byte a second), while a normal request is answered;
   the server drops them MAX_CONNECTIONS at a time (the rest wait in the system's queue for a
   handler), each after its request timeout (TIMEOUT; CROWDED_SECONDS while others wait), so all
   within ceil(200 / MAX_CONNECTIONS) timeouts;
4. a solve that would take minutes (a 10,000-sample sweep of the class-3 triad), its client
   leaving after 1 s (a closed tab): the editor's CPU must be idle again well within BUDGET; and
   the same solve with the client waiting: answered 503 with a message after about BUDGET.

Throughout: no traceback (nothing at all) on the editor's stderr, and in the end no file in the
directory but FILE and FILE.bak.

    python benchmarks/attack_editor.py [KILLS [BUDGET]]
"""

from __future__ import annotations

import hashlib
import http.client
import json
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = "triad_six_modes.yaml"
TICK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


class Editor:
    """``linkagekit edit FILE`` as a child process (its URL read from its first line)."""

    def __init__(self, path: Path, budget: float) -> None:
        code = (
            "import sys, contextlib; from linkagekit.web.editor import serve\n"
            "with contextlib.suppress(KeyboardInterrupt):  # as linkagekit edit: Ctrl-C stops it quietly\n"
            f"    serve(sys.argv[1], 0, open_browser=False, solve_seconds={budget!r})"
        )
        self.proc = subprocess.Popen(
            [sys.executable, "-c", code, str(path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        line = self.proc.stdout.readline().strip() if self.proc.stdout else ""
        if not line.startswith("http://127.0.0.1:"):
            raise SystemExit(
                f"the editor did not start: {line!r} {self.proc.stderr.read() if self.proc.stderr else ''}"
            )
        self.doc: dict = {}  # the file's document, once read
        rest = line[len("http://127.0.0.1:") :]
        self.port, self.token = int(rest.split("/")[0]), rest.split("/")[1]

    def request(self, method: str, call: str, body: dict | None = None, timeout: float = 120) -> tuple[int, dict]:
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=timeout)
        data = json.dumps(body).encode() if body is not None else None
        headers = {"Content-Type": "application/json"} if data is not None else {}
        conn.request(method, f"/{self.token}/{call}", body=data, headers=headers)
        r = conn.getresponse()
        raw = r.read()
        conn.close()
        return r.status, (json.loads(raw) if r.getheader("Content-Type", "").startswith("application/json") else {})

    def raw_post(self, body: dict) -> socket.socket:
        data = json.dumps(body).encode()
        s = socket.create_connection(("127.0.0.1", self.port), timeout=10)
        s.sendall(
            f"POST /{self.token}/api/solve HTTP/1.1\r\nHost: 127.0.0.1:{self.port}\r\n"
            f"Content-Type: application/json\r\nContent-Length: {len(data)}\r\n\r\n".encode()
            + data
        )
        return s

    def cpu_seconds(self) -> float:
        fields = Path(f"/proc/{self.proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / TICK

    def stop(self, kill: bool = False) -> str:
        """Stop it (SIGINT, or SIGKILL) and return its stderr."""
        self.proc.send_signal(signal.SIGKILL if kill else signal.SIGINT)
        _, err = self.proc.communicate(timeout=30)
        return err


def _two_docs(path: Path) -> list[dict]:
    import linkagekit as lk

    doc = lk.load(path).to_dict()
    return [doc | {"name": "attack A"}, doc | {"name": "attack B"}]


def kills_during_saves(path: Path, budget: float, kills: int, findings: dict) -> None:
    """Saves killed at random moments: FILE and FILE.bak always load; temporaries removed at the next start."""
    import linkagekit as lk

    docs, left, bad, saves = _two_docs(path), 0, [], 0
    rng = random.Random(23)
    for k in range(kills):
        ed = Editor(path, budget)  # removes what the previous kill left
        strays = [p.name for p in path.parent.iterdir() if p.name.endswith(".tmp")]
        if strays:
            bad.append(f"kill {k}: temporaries still there after a restart: {strays}")
        stop = threading.Event()

        def save_loop(ed: Editor = ed, stop: threading.Event = stop) -> None:
            nonlocal saves
            i = 0
            while not stop.is_set():
                base = hashlib.sha256(path.read_bytes()).hexdigest()
                try:
                    ed.request("POST", "api/save", {"doc": docs[i % 2], "base": base}, timeout=10)
                    saves += 1
                except (OSError, http.client.HTTPException):
                    return
                i += 1

        t = threading.Thread(target=save_loop, daemon=True)
        t.start()
        time.sleep(rng.uniform(0.05, 0.4))
        err = ed.stop(kill=True)
        stop.set()
        t.join(15)
        left += sum(p.name.endswith(".tmp") for p in path.parent.iterdir())
        for f in (path, path.with_name(path.name + ".bak")):
            try:
                if f.exists():
                    lk.load(f)
            except Exception as exc:  # noqa: BLE001 - a finding
                bad.append(f"kill {k}: {f.name} does not load: {exc}")
        if err.strip():
            bad.append(f"kill {k}: stderr {err.strip()[:200]!r}")
    findings["kills"] = {"kills": kills, "saves": saves, "temporaries left by kills": left, "failures": bad}


def concurrent(ed: Editor, n: int, findings: dict) -> None:
    """n clients at once, each a coarse solve (or every 10th the page): every one answered."""
    doc = coarse_request(ed)
    statuses: list[int] = []
    busy: list[int] = []
    errors: list[str] = []
    lock = threading.Lock()
    start = threading.Barrier(n, timeout=60)

    def one(i: int) -> None:
        try:
            start.wait()
            status, answer = ed.request("GET", "") if i % 10 == 0 else ed.request("POST", "api/solve", doc)
            with lock:
                statuses.append(status)
                busy.extend([i] if answer.get("busy") else [])
        except Exception as exc:  # noqa: BLE001 - a finding
            with lock:
                errors.append(f"{type(exc).__name__}: {exc}")

    t0 = time.monotonic()
    threads = [threading.Thread(target=one, args=(i,), daemon=True) for i in range(n)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(300)
    findings["concurrent"] = {
        "requests": n,
        "answered": len(statuses),
        "statuses": sorted(set(statuses)),
        "seconds": round(time.monotonic() - t0, 1),
        "stopped by the budget (503, with its message)": statuses.count(503) - len(busy),
        "no handler free (503, busy)": len(busy),
        "failures": errors[:5] + ([f"status {s}" for s in set(statuses) if s not in (200, 503)]),
    }


def coarse_request(ed: Editor) -> dict:
    """A coarse solve of the file's mechanism (as the page sends while a joint is dragged)."""
    status, answer = ed.request("POST", "api/solve", {"doc": ed.doc, "coarse": True})
    return {"doc": answer.get("doc", ed.doc), "coarse": True}


def slow_connections(ed: Editor, n: int, findings: dict) -> None:
    """n connections sending their headers one byte a second; a normal request meanwhile."""
    from math import ceil

    from linkagekit.web.editor import MAX_CONNECTIONS, TIMEOUT

    window = ceil(n / MAX_CONNECTIONS) * TIMEOUT + 10  # dropped MAX_CONNECTIONS at a time, TIMEOUT apart
    socks = [socket.create_connection(("127.0.0.1", ed.port), timeout=30) for _ in range(n)]
    head = f"GET /{ed.token}/ HTTP/1.1\r\n".encode()
    t0 = time.monotonic()
    for s in socks:
        s.sendall(head[:1])
    time.sleep(1)
    for s in socks:
        s.sendall(head[1:2])
    w0 = time.monotonic()
    status, _ = ed.request("POST", "api/solve", coarse_request(ed), timeout=window)
    normal = time.monotonic() - w0
    closed = 0
    for s in socks:  # the server drops each after its request timeout
        s.settimeout(max(1.0, window - (time.monotonic() - t0)))
        try:
            closed += s.recv(1) == b""
        except ConnectionResetError:
            closed += 1
        except OSError:
            pass
        s.close()
    findings["slow"] = {
        "connections": n,
        "normal request": status,
        "normal seconds": round(normal, 2),
        "dropped by the server": closed,
        "failures": ([] if status == 200 else [f"normal request {status}"])
        + ([] if closed == n else [f"{n - closed} slow connections still open after {window:g} s"]),
    }


def long_solves(ed: Editor, budget: float, findings: dict) -> None:
    """A minutes-long solve: abandoned after 1 s (CPU idle again soon), then waited for (503 after BUDGET)."""
    doc = dict(ed.doc)
    doc["drivers"] = [dict(ed.doc["drivers"][0]) | {"angles": {"start": 0, "stop": 3600, "step": 0.36}}]
    s = ed.raw_post({"doc": doc})
    time.sleep(1.0)
    s.close()
    t0 = time.monotonic()
    freed = None
    last = ed.cpu_seconds()
    while time.monotonic() - t0 < budget + 10:
        time.sleep(0.25)
        now = ed.cpu_seconds()
        if now - last < 0.02:  # under 8 % of a core over a quarter of a second: idle
            freed = time.monotonic() - t0
            break
        last = now
    w0 = time.monotonic()
    status, answer = ed.request("POST", "api/solve", {"doc": doc}, timeout=budget + 60)
    waited = time.monotonic() - w0
    failures = []
    if freed is None or freed > budget:
        failures.append(f"the CPU was still busy {budget + 10:g} s after the tab closed")
    if status != 503 or "budget" not in answer.get("error", ""):
        failures.append(f"the long solve was answered {status} {answer}")
    findings["long solve"] = {
        "budget s": budget,
        "CPU idle after the tab closed, s": None if freed is None else round(freed, 2),
        "answer": status,
        "answered after s": round(waited, 2),
        "message": answer.get("error"),
        "failures": failures,
    }


def main(kills: int = 50, budget: float = 5.0) -> int:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / EXAMPLE
        shutil.copyfile(ROOT / "examples" / EXAMPLE, path)
        findings: dict = {}
        t0 = time.monotonic()
        kills_during_saves(path, budget, kills, findings)
        ed = Editor(path, budget)
        import linkagekit as lk

        ed.doc = lk.load(path).to_dict()
        concurrent(ed, 500, findings)
        slow_connections(ed, 200, findings)
        long_solves(ed, budget, findings)
        err = ed.stop()
        left = sorted(p.name for p in path.parent.iterdir())
        findings["end"] = {
            "editor stderr": err.strip()[:500],
            "files": left,
            "seconds": round(time.monotonic() - t0, 1),
            "failures": ([f"stderr: {err.strip()[:300]!r}"] if err.strip() else [])
            + ([] if left == sorted([path.name, path.name + ".bak"]) else [f"stray files: {left}"]),
        }
    failed = 0
    for name, f in findings.items():
        fails = f.pop("failures")
        failed += len(fails)
        print(f"{name}: {'OK' if not fails else 'FAILED'}: " + json.dumps(f))
        for line in fails:
            print(f"  FAILURE: {line}")
    print("all held" if not failed else f"{failed} failure(s)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(int(sys.argv[1]) if len(sys.argv) > 1 else 50, float(sys.argv[2]) if len(sys.argv) > 2 else 5.0))
