"""``linkagekit edit``: the server's security, the Session's solves and saves, and the command line.

Written as an independent review of ``src/linkagekit/web/editor.py`` against
mechanism-format.md sections 2 and 5 (the browser side is ``test_editor_browser.py``).
Every test works on a copy of an example in ``tmp_path``; ``examples/`` is never written.

* Session: a solve without a pose gives back the file's pose at the shown sample; a pose
  moves the reference pose (``Mechanism.with_pose``: dimensions read off it, the pose's own
  input in the sweep, the joints at that sample equal to the pose); coarse solves are small;
  save writes FILE (``lk.load`` gives the edited mechanism), keeps the old bytes in FILE.bak
  and the leading comment lines, refuses (and leaves the file alone) when the file changed on
  disk or the document is invalid; a JSON file stays JSON.
* Security, with plain ``http.client`` against an in-process server: it binds 127.0.0.1; a
  missing or wrong token, any path but the page and the two calls, a query string, a foreign
  ``Origin``, a wrong or missing ``Host`` get 403; malformed JSON, a non-object body, NaN,
  bad UTF-8, a huge or missing ``Content-Length``, a missing or non-JSON ``Content-Type`` get
  a 4xx JSON error, and the server keeps serving; a refused request with a body does not
  leave that body to be read as the next request on the same connection; save requests,
  whatever they carry, write FILE and FILE.bak only (the whole tree is compared).
* Command line: bad ``--port`` values and a port in use exit 2 with one line; a bad file
  exits 2 with one line and serves nothing; the real command prints its URL first, serves the
  page and the solver, and stops on SIGINT with status 0 and no traceback.
"""

from __future__ import annotations

import hashlib
import http.client
import json
import math
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

import linkagekit as lk
from helpers import interruptible, leading_comments
from linkagekit.errors import LinkageError
from linkagekit.web.editor import ConflictError, EditorServer, Session, posed

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
SEED000 = "seed000_fourbar.yaml"
URL_RE = re.compile(r"^http://127\.0\.0\.1:(\d+)/([A-Za-z0-9_\-]{16,})/$")


# ----------------------------------------------------------------------------- helpers
def copy_example(tmp_path: Path, name: str = SEED000, sub: str = "work") -> Path:
    d = tmp_path / sub
    d.mkdir(parents=True, exist_ok=True)
    dst = d / name
    shutil.copyfile(EXAMPLES / name, dst)
    return dst


def close(a: float, b: float, size: float = 1.0, rel: float = 1e-9) -> bool:
    return math.isclose(float(a), float(b), rel_tol=rel, abs_tol=rel * size)


def tree(root: Path) -> dict[str, str]:
    """Every file under root (relative name -> sha256 of its bytes)."""
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def joints_at(scene: dict, i: int) -> dict[str, tuple[float, float]]:
    cols = scene["columns"]
    return {j: (cols[f"{j}.x"][i], cols[f"{j}.y"][i]) for j in scene["joints"]}


@pytest.fixture
def server(tmp_path):
    """An in-process editor server on a copy of seed000 (in tmp_path/work)."""
    path = copy_example(tmp_path)
    srv = EditorServer(Session(path), 0)
    t = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    t.start()
    yield srv
    srv.shutdown()
    srv.server_close()
    t.join(5)


class Client:
    """Plain HTTP against one server: a fresh connection per request unless one is given."""

    def __init__(self, srv: EditorServer) -> None:
        self.srv = srv
        self.port = srv.port
        self.token = srv.token

    def conn(self) -> http.client.HTTPConnection:
        return http.client.HTTPConnection("127.0.0.1", self.port, timeout=10)

    def request(self, method, path, body=None, headers=None, conn=None, ctype="application/json"):
        c = conn or self.conn()
        h = {}
        if body is not None and ctype is not None:
            h["Content-Type"] = ctype
        h.update(headers or {})
        if isinstance(body, str):
            body = body.encode("utf-8")
        c.request(method, path, body=body, headers=h)
        r = c.getresponse()
        data = r.read()
        if conn is None:
            c.close()
        return r.status, dict(r.getheaders()), data

    def raw(self, method, path, headers, body=b"", skip_host=False):
        """A request with exactly these headers (http.client adds none but Host unless skip_host)."""
        c = self.conn()
        c.putrequest(method, path, skip_host=skip_host, skip_accept_encoding=True)
        for k, v in headers.items():
            c.putheader(k, v)
        c.endheaders()
        if body:
            c.send(body)
        r = c.getresponse()
        data = r.read()
        c.close()
        return r.status, dict(r.getheaders()), data

    def page(self):
        return self.request("GET", f"/{self.token}/")

    def solve(self, req: dict, **kw):
        return self.request("POST", f"/{self.token}/api/solve", json.dumps(req), **kw)

    def save(self, req: dict, **kw):
        return self.request("POST", f"/{self.token}/api/save", json.dumps(req), **kw)

    def still_serving(self) -> None:
        status, headers, body = self.page()
        assert status == 200 and b'data-role="mechanism"' in body, (status, body[:200])
        doc = self.srv.session.mech.to_dict()
        status, _, body = self.solve({"doc": doc, "coarse": True})
        assert status == 200 and json.loads(body)["ok"] is True, (status, body[:200])


def json_error(status: int, headers: dict, body: bytes, what: str) -> dict:
    ctype = {k.lower(): v for k, v in headers.items()}.get("content-type", "")
    assert ctype.startswith("application/json"), (
        f"{what}: {status} answered with Content-Type {ctype!r}: {body[:200]!r}"
    )
    doc = json.loads(body)
    assert isinstance(doc, dict) and doc.get("ok") is False, f"{what}: {doc}"
    assert isinstance(doc.get("error"), str) and doc["error"], f"{what}: no error message: {doc}"
    return doc


# ============================================================================== Session
def test_session_solve_gives_back_the_file_pose(tmp_path):
    path = copy_example(tmp_path)
    s = Session(path)
    mech = lk.load(path)
    out = s.solve({"doc": mech.to_dict()})
    assert out["ok"] is True
    sc = out["scene"]
    i = out["pose_index"]
    inputs = sc["columns"]["input:crank"]
    assert len(inputs) == 361 and inputs[0] == 0.0 and inputs[-1] == 360.0, "the file's sweep, 0..360 step 1"
    assert inputs[i] == 0.0, f"the pose's input is 0 deg, shown sample {i} has {inputs[i]}"
    for j, (x, y) in joints_at(sc, i).items():
        z = mech.joints[j]
        assert close(x, z.real, 6) and close(y, z.imag, 6), (j, x, y, z)
    assert "checks" in out and "crank-rocker" in out["checks"], out.get("checks", "")[:300]
    assert len(out["modes"]) == 2 and sum(m["reference"] for m in out["modes"]) == 1, out["modes"]
    assert Mechanism_of(out["doc"]) == lk.Mechanism.from_dict(mech.to_dict())


def Mechanism_of(doc):  # noqa: N802 - reads as a constructor
    return lk.Mechanism.from_dict(doc)


@pytest.mark.parametrize("coarse", [True, False])
def test_session_solve_with_pose_moves_the_reference_pose(tmp_path, coarse):
    """Dragging D: the new reference pose, lengths read off it, D where it was put at the shown sample."""
    path = copy_example(tmp_path)
    s = Session(path)
    mech = lk.load(path)
    new_d = [1.3, 4.5]
    out = s.solve({"doc": mech.to_dict(), "pose": {"D": new_d}, "coarse": coarse})
    assert out["ok"] is True
    m2 = lk.Mechanism.from_dict(out["doc"])
    assert m2.joints["D"] == complex(*new_d)
    for j in ("A", "B", "C", "P"):
        assert m2.joints[j] == mech.joints[j], j
    drawn = {j: [z.real, z.imag] for j, z in mech.joints.items()} | {"D": new_d}
    want = m2.with_pose(drawn)
    # Mechanism.with_pose of the drawn configuration, but for the given lengths that the drag of D cannot
    # have changed (issue 23): those between two other joints stay exactly as given
    for ln in mech.links:
        kept = {k: v for k, v in ln.lengths.items() if "D" not in k.split("-")}
        assert dict(m2.link(ln.name).lengths) == kept, (ln.name, m2.link(ln.name).lengths, kept)
        assert m2.link(ln.name).joints == want.link(ln.name).joints
    assert m2.with_pose(drawn) == want and m2.joints == want.joints
    assert m2 == posed(mech, drawn, ["D"]), "the answer's document is the drawn configuration, given lengths kept"
    cd = abs(complex(*new_d) - mech.joints["C"])
    assert close(out["lengths"]["coupler"]["C-D"], cd, 5), (out["lengths"], cd)
    sc, i = out["scene"], out["pose_index"]
    n = len(sc["columns"]["input:crank"])
    if coarse:
        assert 30 <= n <= 200, f"a coarse solve has {n} samples"
        assert "checks" not in out and "modes" not in out
    else:
        assert n == 361
    for j, (x, y) in joints_at(sc, i).items():
        z = m2.joints[j]
        assert close(x, z.real, 6) and close(y, z.imag, 6), (j, x, y, z)


def test_session_pose_off_the_sweep_grid_is_inserted(tmp_path):
    """Dragging the crank pin to 37.5 deg: that input is a sample of the sweep, and the one shown."""
    path = copy_example(tmp_path)
    s = Session(path)
    mech = lk.load(path)
    a = math.radians(37.5)
    c = [2 * math.cos(a), 2 * math.sin(a)]
    out = s.solve({"doc": mech.to_dict(), "pose": {"C": c}})
    xs = out["scene"]["columns"]["input:crank"]
    i = out["pose_index"]
    assert close(xs[i], 37.5, 360), xs[i]
    assert list(xs) == sorted(xs), "the sweep stays ascending"
    assert 361 <= len(xs) <= 362
    x, y = joints_at(out["scene"], i)["C"]
    assert close(x, c[0], 2) and close(y, c[1], 2)


def test_session_save_writes_file_backup_and_keeps_comments(tmp_path):
    path = copy_example(tmp_path)
    original = path.read_bytes()
    s = Session(path)
    out = s.solve({"doc": lk.load(path).to_dict(), "pose": {"D": [1.25, 4.6], "P": [5.5, 3.25]}})
    before = tree(path.parent)
    got = s.save({"doc": out["doc"], "base": s.base})
    assert got["ok"] is True
    assert set(tree(path.parent)) == set(before) | {path.name + ".bak"}, sorted(tree(path.parent))
    back = path.with_name(path.name + ".bak")
    assert back.read_bytes() == original, "FILE.bak holds the previous file byte for byte"
    saved = lk.load(path)
    assert saved == lk.Mechanism.from_dict(out["doc"])
    assert saved.joints["D"] == complex(1.25, 4.6) and saved.joints["P"] == complex(5.5, 3.25)
    text = path.read_text(encoding="utf-8")
    assert leading_comments(text) == leading_comments(original.decode()), "the leading comment lines are kept"
    assert got["base"] == hashlib.sha256(path.read_bytes()).hexdigest()
    # a second save from the same session: the backup is now the first saved version
    first = path.read_bytes()
    out2 = s.solve({"doc": out["doc"], "pose": {"D": [1.0, 4.7]}})
    assert s.save({"doc": out2["doc"], "base": got["base"]})["ok"] is True
    assert back.read_bytes() == first
    assert lk.load(path).joints["D"] == complex(1.0, 4.7)


def test_session_save_keeps_every_comment_where_its_line_is(tmp_path):
    """Comments between keys, inside the joints block and at the end of lines (one of them on a moved joint's
    line, one holding a ``#`` inside quotes before it) survive a drag and a save: the saved text is the old text
    with only the moved joints' coordinates changed, and it reads as the edited mechanism."""
    path = copy_example(tmp_path)
    text = path.read_text(encoding="utf-8")
    text = text.replace("joints:\n", "# where the joints are, in cm\njoints:\n  # the ground pivots\n")
    text = text.replace("  D: [", "  # the rocker's tip, dragged below\n  D: [")
    text = text.replace("  B: [4, 1]", "  B: [4, 1]  # ground, right")
    D_line = next(line for line in text.splitlines() if line.startswith("  D: ["))
    text = text.replace(D_line, D_line + "   # moved: keep me")
    text = text.replace("name: Romero-Nunez 2016 four-bar (t1 = +1, t2 = -1)", 'name: "four-bar #1"  # quoted hash')
    path.write_text(text, encoding="utf-8")
    s = Session(path)
    out = s.solve({"doc": lk.load(path).to_dict(), "pose": {"D": [1.25, 4.6], "P": [5.5, 3.25]}})
    assert s.save({"doc": out["doc"], "base": s.base})["ok"] is True
    saved = path.read_text(encoding="utf-8")
    assert lk.load(path) == lk.Mechanism.from_dict(out["doc"])
    old_lines, new_lines = text.splitlines(), saved.splitlines()
    assert len(new_lines) == len(old_lines)
    # every comment line stays where it was, the trailing comments on their lines
    for i, line in enumerate(old_lines):
        if line.lstrip().startswith("#"):
            assert new_lines[i] == line, (i, line, new_lines[i])
    i = old_lines.index(D_line + "   # moved: keep me")
    assert new_lines[i] == "  D: [1.25, 4.6]   # moved: keep me"
    assert "  B: [4, 1]  # ground, right" in new_lines
    assert next(x for x in new_lines if x.startswith("name:")).endswith("#1'  # quoted hash")


def test_session_save_keeps_the_leading_comments_before_a_document_start(tmp_path):
    """A file whose header comments come before ``---`` (or a ``%YAML`` directive) keeps them on save, as it
    did before comments were merged: the marker lines are not written again, but the comments above them are
    the file's, not the marker's."""
    path = copy_example(tmp_path)
    original = path.read_text(encoding="utf-8")
    head = leading_comments(original)
    assert len(head) > 5
    for marker in ("---\n", "%YAML 1.2\n# between the directive and the start\n---\n"):
        text = original.replace("format: linkagekit/1", marker + "format: linkagekit/1")
        text = text.replace("  B: [4, 1]", "  B: [4, 1]  # ground, right")
        path.write_text(text, encoding="utf-8")
        s = Session(path)
        assert s.save({"doc": s.mech.to_dict(), "base": s.base})["ok"] is True
        saved = path.read_text(encoding="utf-8")
        assert lk.load(path) == s.mech
        assert leading_comments(saved) == head + ["# between the directive and the start"] * ("%" in marker), marker
        assert "  B: [4, 1]  # ground, right" in saved.splitlines(), marker


def test_session_save_reads_an_escaped_quote_as_part_of_the_string(tmp_path):
    """``"a\\"  #b"`` is one double-quoted string (``\\"`` does not end it): the ``#b"`` inside it is not a
    comment, so it is not written again after the value as if it were one."""
    path = copy_example(tmp_path)
    text = path.read_text(encoding="utf-8")
    name = next(line for line in text.splitlines() if line.startswith("name:"))
    path.write_text(text.replace(name, 'name: "a\\"  #b"  # real comment'), encoding="utf-8")
    s = Session(path)
    assert s.mech.name == 'a"  #b'
    assert s.save({"doc": s.mech.to_dict(), "base": s.base})["ok"] is True
    saved = path.read_text(encoding="utf-8")
    assert lk.load(path) == s.mech
    line = next(x for x in saved.splitlines() if x.startswith("name:"))
    assert line.count("#b") == 1 and line.endswith("  # real comment"), line


def test_session_save_keeps_the_sections_in_the_files_order_and_their_comments(tmp_path):
    """The scotch yoke's file has ``sliders:`` before ``drivers:`` (the model writes them after): a save keeps the
    sections where the file has them, so the comments on the sliders' lines stay on them."""
    path = copy_example(tmp_path, "scotch_yoke.yaml")
    text = path.read_text(encoding="utf-8")
    text = text.replace("sliders:\n", "# the two prismatic pairs\nsliders:\n")
    text = text.replace("direction: [1, 0]}", "direction: [1, 0]}  # horizontal guide")
    path.write_text(text, encoding="utf-8")
    s = Session(path)
    assert s.save({"doc": s.mech.to_dict(), "base": s.base})["ok"] is True
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lk.load(path) == s.mech
    assert lines.index("sliders:") < lines.index("drivers:")
    assert lines[lines.index("sliders:") - 1] == "# the two prismatic pairs"
    assert lines[lines.index("sliders:") + 1].endswith("direction: [1, 0]}  # horizontal guide")


def test_session_save_refuses_when_the_file_changed_on_disk(tmp_path):
    path = copy_example(tmp_path)
    s = Session(path)
    doc = s.solve({"doc": lk.load(path).to_dict(), "pose": {"D": [1.25, 4.6]}})["doc"]
    changed = path.read_text() + "# changed by someone else\n"
    path.write_text(changed)
    with pytest.raises(ConflictError):
        s.save({"doc": doc, "base": s.base})
    assert path.read_text() == changed
    assert not path.with_name(path.name + ".bak").exists()


def test_session_save_refuses_a_stale_base(tmp_path):
    path = copy_example(tmp_path)
    original = path.read_bytes()
    s = Session(path)
    doc = s.solve({"doc": lk.load(path).to_dict(), "pose": {"D": [1.25, 4.6]}})["doc"]
    with pytest.raises(ConflictError):
        s.save({"doc": doc, "base": "0" * 64})
    assert path.read_bytes() == original


def test_session_save_of_an_invalid_document_writes_nothing(tmp_path):
    path = copy_example(tmp_path)
    original = path.read_bytes()
    s = Session(path)
    doc = lk.load(path).to_dict()
    doc["joints"]["D"] = list(doc["joints"]["P"])  # two joints of the coupler at one spot
    with pytest.raises(LinkageError):
        s.save({"doc": doc, "base": s.base})
    assert path.read_bytes() == original
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]


def test_session_json_file_stays_json(tmp_path):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(lk.load(EXAMPLES / SEED000).to_dict(), indent=2))
    s = Session(path)
    doc = s.solve({"doc": lk.load(path).to_dict(), "pose": {"D": [1.25, 4.6]}, "coarse": True})["doc"]
    assert s.save({"doc": doc, "base": s.base})["ok"] is True
    assert isinstance(json.loads(path.read_text()), dict), "a JSON file is saved as JSON"
    assert lk.load(path).joints["D"] == complex(1.25, 4.6)


def test_session_of_a_bad_file_raises_a_linkage_error(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("format: linkagekit/1\njoints: {A: [0, 0]}\nlinks: {ground: [A], crank: [A, Z]}\n")
    with pytest.raises(LinkageError):
        Session(bad)
    with pytest.raises(LinkageError):
        Session(tmp_path / "missing.yaml")


# ============================================================================== security
def test_binds_loopback_only(server):
    assert server.server_address[0] == "127.0.0.1"
    assert URL_RE.match(server.url), server.url
    assert len(server.token) >= 16


def test_page_and_calls_with_the_token(server):
    c = Client(server)
    status, headers, body = c.page()
    assert status == 200
    h = {k.lower(): v for k, v in headers.items()}
    assert h["content-type"].startswith("text/html")
    assert "default-src 'none'" in h.get("content-security-policy", ""), h
    assert b'data-role="mechanism"' in body and b'id="lk-editor"' in body
    c.still_serving()


def forbidden_requests(token: str, port: int) -> list[tuple[str, str, str, dict, str | None]]:
    """(what, method, path, headers, body) that must all get 403."""
    doc = json.dumps({"doc": {}})
    return [
        ("no token", "GET", "/", {}, None),
        ("no token, API", "POST", "/api/solve", {}, doc),
        ("wrong token", "GET", "/" + "x" * len(token) + "/", {}, None),
        ("wrong token, API", "POST", "/" + "x" * len(token) + "/api/save", {}, doc),
        ("token prefix", "GET", f"/{token[:-1]}/", {}, None),
        ("token without the slash", "GET", f"/{token}", {}, None),
        ("dot-dot", "GET", f"/{token}/../etc/passwd", {}, None),
        ("encoded dot-dot", "GET", f"/{token}/%2e%2e/%2e%2e/etc/passwd", {}, None),
        ("other API", "POST", f"/{token}/api/other", {}, doc),
        ("other API, GET", "GET", f"/{token}/api/other", {}, None),
        ("a file under the token", "GET", f"/{token}/x", {}, None),
        ("a query", "GET", f"/{token}/x?y=1", {}, None),
        ("a query on the page", "GET", f"/{token}/?y=1", {}, None),
        ("a query on the API", "POST", f"/{token}/api/solve?y=1", {}, doc),
        ("double slash, no token", "GET", "//evil.example/", {}, None),
        ("foreign Origin", "GET", f"/{token}/", {"Origin": "http://evil.example"}, None),
        ("foreign Origin, solve", "POST", f"/{token}/api/solve", {"Origin": "http://evil.example"}, doc),
        ("foreign Origin, save", "POST", f"/{token}/api/save", {"Origin": "https://evil.example"}, doc),
        ("Origin null", "POST", f"/{token}/api/save", {"Origin": "null"}, doc),
        ("Origin, other port", "POST", f"/{token}/api/solve", {"Origin": f"http://127.0.0.1:{port + 1}"}, doc),
        ("Origin, https", "POST", f"/{token}/api/solve", {"Origin": f"https://127.0.0.1:{port}"}, doc),
        ("Host rebinding", "GET", f"/{token}/", {"Host": "evil.example"}, None),
        ("Host rebinding with port", "GET", f"/{token}/", {"Host": f"evil.example:{port}"}, None),
        ("Host rebinding, save", "POST", f"/{token}/api/save", {"Host": f"evil.example:{port}"}, doc),
        ("Host, other port", "GET", f"/{token}/", {"Host": f"127.0.0.1:{port + 1}"}, None),
        ("Host suffix", "GET", f"/{token}/", {"Host": f"127.0.0.1:{port}.evil.example"}, None),
        ("Host without port", "GET", f"/{token}/", {"Host": "127.0.0.1"}, None),
    ]


def test_forbidden_requests_get_403(server):
    c = Client(server)
    bad = []
    for what, method, path, headers, body in forbidden_requests(server.token, server.port):
        hdrs = dict(headers)
        if "Host" in hdrs:  # http.client would add its own Host: send exactly this one
            if body is not None:
                hdrs["Content-Type"] = "application/json"
                hdrs["Content-Length"] = str(len(body))
            status, rh, data = c.raw(method, path, hdrs, (body or "").encode(), skip_host=True)
        else:
            status, rh, data = c.request(method, path, body, headers=hdrs)
        if status != 403:
            bad.append(f"{what}: {method} {path} {headers} -> {status} {data[:120]!r}")
        else:
            json_error(status, rh, data, what)
    assert not bad, "requests that must be refused with 403:\n  " + "\n  ".join(bad)
    c.still_serving()


def test_missing_host_is_refused(server):
    c = Client(server)
    status, headers, body = c.raw("GET", f"/{server.token}/", {}, skip_host=True)
    assert status == 403, (status, body[:200])
    c.still_serving()


def test_forbidden_requests_write_nothing(server, tmp_path):
    """The refused save requests above leave the directory as it was."""
    before = tree(tmp_path)
    c = Client(server)
    doc = server.session.mech.to_dict()
    doc["joints"]["D"] = [1.25, 4.6]
    body = json.dumps({"doc": doc, "base": server.session.base})
    for origin in ("http://evil.example", "null"):
        status, _, _ = c.request("POST", f"/{server.token}/api/save", body, headers={"Origin": origin})
        assert status == 403
    status, _, _ = c.request("POST", "/" + "y" * len(server.token) + "/api/save", body)
    assert status == 403
    assert tree(tmp_path) == before


@pytest.mark.parametrize(
    "what, body, ctype, want",
    [
        ("malformed JSON", "{bad", "application/json", 400),
        ("truncated JSON", '{"doc": {', "application/json", 400),
        ("a list", "[1, 2]", "application/json", 400),
        ("a string", '"doc"', "application/json", 400),
        ("a number", "3", "application/json", 400),
        ("null", "null", "application/json", 400),
        ("NaN", '{"doc": NaN}', "application/json", 400),
        ("Infinity", '{"coarse": Infinity}', "application/json", 400),
        ("bad UTF-8", b'{"doc": "\xff\xfe"}', "application/json", 400),
        ("empty body", "", "application/json", 400),
        ("no Content-Type", '{"doc": {}}', None, 415),
        ("text/plain (a cross-site form)", '{"doc": {}}', "text/plain", 415),
        ("form encoded", "doc=1", "application/x-www-form-urlencoded", 415),
    ],
)
def test_bad_bodies_get_4xx_json(server, what, body, ctype, want):
    c = Client(server)
    for call in ("api/solve", "api/save"):
        status, headers, data = c.request("POST", f"/{server.token}/{call}", body, ctype=ctype)
        assert 400 <= status < 500, f"{what} to {call}: status {status} {data[:200]!r}"
        assert status == want, f"{what} to {call}: status {status}, expected {want}: {data[:200]!r}"
        json_error(status, headers, data, f"{what} to {call}")
    c.still_serving()


def test_huge_or_missing_content_length(server):
    c = Client(server)
    t0 = time.monotonic()
    status, headers, data = c.raw(
        "POST", f"/{server.token}/api/solve", {"Content-Type": "application/json", "Content-Length": str(10**12)}
    )
    assert status == 413, (status, data[:200])
    json_error(status, headers, data, "huge Content-Length")
    assert time.monotonic() - t0 < 5, "a huge Content-Length is refused at once, not read"
    status, headers, data = c.raw(
        "POST", f"/{server.token}/api/solve", {"Content-Type": "application/json", "Content-Length": "-5"}
    )
    assert 400 <= status < 500, (status, data[:200])
    json_error(status, headers, data, "negative Content-Length")
    status, headers, data = c.raw("POST", f"/{server.token}/api/solve", {"Content-Type": "application/json"})
    assert 400 <= status < 500, (status, data[:200])
    json_error(status, headers, data, "no Content-Length")
    status, headers, data = c.raw(
        "POST", f"/{server.token}/api/save", {"Content-Type": "application/json", "Content-Length": "abc"}
    )
    assert 400 <= status < 500, (status, data[:200])
    # a body just over the limit, actually sent
    big = b'{"doc": "' + b"x" * (3 << 20) + b'"}'
    try:
        status, headers, data = c.request("POST", f"/{server.token}/api/solve", big)
        assert status == 413, (status, data[:200])
    except (ConnectionResetError, BrokenPipeError):
        pass  # the server may close the connection before the body is sent: refused all the same
    c.still_serving()


def test_invalid_documents_are_answered_not_crashed(server):
    """A document or pose that does not solve: a JSON answer with ok false and a message, never a 500."""
    c = Client(server)
    doc = server.session.mech.to_dict()
    cases = {
        "no doc": {},
        "doc not a mapping": {"doc": [1]},
        "joints not a mapping": {"doc": {"joints": 5}},
        "pose not a mapping": {"doc": doc, "pose": [1, 2]},
        "pose not numbers": {"doc": doc, "pose": {"D": "x"}},
        "pose null coordinate": {"doc": doc, "pose": {"D": [1, None]}},
        "pose too large": {"doc": doc, "pose": {"D": [1e308, 1e308]}},
        "two joints of a link at one spot": {"doc": doc, "pose": {"D": doc["joints"]["P"]}},
    }
    bad = []
    for what, req in cases.items():
        status, headers, data = c.solve(req)
        try:
            got = json.loads(data)
        except ValueError:
            bad.append(f"{what}: {status} not JSON: {data[:120]!r}")
            continue
        if status >= 500 or got.get("ok") is not False or not got.get("error"):
            bad.append(f"{what}: {status} {got if len(data) < 300 else data[:200]}")
    assert not bad, "\n  ".join(bad)
    c.still_serving()


def test_a_refused_request_does_not_poison_its_connection(server):
    """HTTP/1.1 keep-alive: after a refused POST with a body, the next request on the SAME
    connection gets its own answer (the server reads the refused body, or closes the connection;
    it must not read the body as the next request)."""
    c = Client(server)
    body = json.dumps({"doc": server.session.mech.to_dict()})
    bad = []
    refusals = [
        ("foreign Origin", "api/solve", {"Origin": "http://evil.example"}, "application/json"),
        ("text/plain", "api/solve", {}, "text/plain"),
        ("other path", "api/other", {}, "application/json"),
    ]
    for what, call, headers, ctype in refusals:
        conn = c.conn()
        try:
            status, _, _ = c.request("POST", f"/{server.token}/{call}", body, headers=headers, conn=conn, ctype=ctype)
            assert 400 <= status < 500, (what, status)
            try:
                status2, h2, data2 = c.request("GET", f"/{server.token}/", conn=conn)
            except (http.client.HTTPException, ConnectionError) as exc:
                bad.append(f"after {what}: the next request on the connection failed: {exc!r}")
                continue
            if status2 != 200:
                bad.append(f"after {what}: the next request on the connection got {status2} {data2[:80]!r}")
        finally:
            conn.close()
    assert not bad, "\n  ".join(bad)


def test_save_writes_only_the_file_and_its_backup(server, tmp_path):
    """Whatever a save request carries, only FILE and FILE.bak change under tmp_path."""
    c = Client(server)
    path = server.session.path
    before = tree(tmp_path)
    original = path.read_bytes()
    doc = server.session.mech.to_dict()
    doc["joints"]["D"] = [1.25, 4.6]
    doc["name"] = "../../evil"
    requests = [
        {"doc": doc, "base": server.session.base, "path": "../evil.yaml", "file": "/tmp/evil.yaml"},
        {"doc": doc | {"source": str(tmp_path / "evil.yaml")}, "backup": str(tmp_path / "evil.bak")},
        {"doc": doc, "format": "json", "saved": "../x"},
    ]
    rel = str(path.relative_to(tmp_path))
    for k, req in enumerate(requests):
        status, _, data = c.save(req)
        got = json.loads(data)
        assert status == 200, (k, status, got)
        if k == 0:
            assert got["ok"] is True, got
            assert (tmp_path / (rel + ".bak")).read_bytes() == original
        after = tree(tmp_path)
        changed = sorted(n for n in set(before) | set(after) if before.get(n) != after.get(n))
        assert set(changed) <= {rel, rel + ".bak"}, f"save request {k} wrote other files: {changed}"
    assert lk.load(path).joints["D"] == complex(1.25, 4.6)
    assert not list(tmp_path.parent.glob("evil*")) and not Path("/tmp/evil.yaml").exists()


def test_save_over_http_conflict_is_409_and_keeps_the_file(server):
    c = Client(server)
    path = server.session.path
    doc = server.session.mech.to_dict()
    doc["joints"]["D"] = [1.25, 4.6]
    changed = path.read_text() + "# edited elsewhere\n"
    path.write_text(changed)
    status, headers, data = c.save({"doc": doc, "base": server.session.base})
    assert status == 409, (status, data[:200])
    got = json_error(status, headers, data, "conflict")
    assert "changed" in got["error"]
    assert path.read_text() == changed
    c.still_serving()


# ============================================================================== command line
def cli(*args: str, preexec=interruptible) -> subprocess.Popen:  # type: ignore[no-untyped-def]
    return subprocess.Popen(
        [sys.executable, "-m", "linkagekit.cli", *args],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
        preexec_fn=preexec,
    )


def finish(proc: subprocess.Popen, timeout: float = 30) -> tuple[int, str, str]:
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        pytest.fail(f"`{' '.join(proc.args[3:])}` still running after {timeout} s (stderr {err!r})")
    return proc.returncode, out, err


def one_line_exit_2(code: int, out: str, err: str, what: str) -> None:
    assert code == 2, f"{what}: exit status {code}, expected 2 (stdout {out!r}, stderr {err!r})"
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].strip(), f"{what}: stderr is not one line: {err!r}"
    assert "Traceback" not in err
    assert "http://" not in out, f"{what}: printed a URL, so it served: {out!r}"


def test_cli_bad_port_values_exit_2_with_one_line(tmp_path):
    path = copy_example(tmp_path)
    values = ["abc", "-1", "65536", "99999999999999999999", "1.5", "", "0x50", " "]
    procs = {v: cli("edit", str(path), "--port", v, "--no-browser") for v in values}
    bad = []
    for v, p in procs.items():
        code, out, err = finish(p)
        try:
            one_line_exit_2(code, out, err, f"--port {v!r}")
        except AssertionError as exc:
            bad.append(str(exc))
    assert not bad, "\n".join(bad)


def test_cli_port_in_use_exits_2(tmp_path):
    path = copy_example(tmp_path)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        code, out, err = finish(cli("edit", str(path), "--port", str(port), "--no-browser"))
    one_line_exit_2(code, out, err, f"--port {port} (in use)")


def test_cli_bad_file_exits_2_before_serving(tmp_path):
    bad_yaml = tmp_path / "broken.yaml"
    bad_yaml.write_text("joints: [A: {\n")
    bad_mech = tmp_path / "unknown.yaml"
    bad_mech.write_text(
        "format: linkagekit/1\njoints: {A: [0, 0], C: [1, 0]}\nlinks: {ground: [A], crank: [A, Z]}\n"
        "drivers: [{link: crank, pivot: A, toward: C}]\n"
    )
    cases = {
        "missing file": str(tmp_path / "missing.yaml"),
        "broken YAML": str(bad_yaml),
        "unknown joint": str(bad_mech),
        "a directory": str(tmp_path),
    }
    procs = {k: cli("edit", v, "--no-browser") for k, v in cases.items()}
    bad = []
    for k, p in procs.items():
        code, out, err = finish(p)
        try:
            one_line_exit_2(code, out, err, k)
        except AssertionError as exc:
            bad.append(str(exc))
    assert not bad, "\n".join(bad)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def served_url(proc: subprocess.Popen) -> str:
    """The first line the editor prints on stdout (its address), read within 30 s."""
    box: list[str] = []
    reader = threading.Thread(target=lambda: box.append(proc.stdout.readline()), daemon=True)
    reader.start()
    reader.join(30)
    assert box and box[0], f"no URL on stdout within 30 s (exit {proc.poll()}, stderr {proc.stderr})"
    return box[0].rstrip("\n")


@pytest.mark.parametrize("explicit_port", [False, True])
def test_cli_serves_then_stops_on_sigint(tmp_path, explicit_port):
    path = copy_example(tmp_path)
    before = path.read_bytes()
    port = free_port() if explicit_port else None
    args = ["edit", str(path), "--no-browser"] + (["--port", str(port)] if port else [])
    proc = cli(*args)
    try:
        url = served_url(proc)
        m = URL_RE.match(url)
        assert m, f"the first stdout line is not http://127.0.0.1:PORT/TOKEN/: {url!r}"
        if port:
            assert int(m.group(1)) == port
        with urllib.request.urlopen(url, timeout=30) as r:
            assert r.status == 200
            page = r.read().decode()
        assert "data-joint" in page and 'data-role="input"' in page
        doc = lk.load(path).to_dict()
        req = urllib.request.Request(
            url + "api/solve",
            data=json.dumps({"doc": doc, "pose": {"D": [1.25, 4.6]}, "coarse": True}).encode(),
            headers={"Content-Type": "application/json"},
            method="POST",
        )
        with urllib.request.urlopen(req, timeout=30) as r:
            got = json.loads(r.read())
        assert got["ok"] is True and got["doc"]["joints"]["D"] == [1.25, 4.6]
        # the token is needed
        bad = url.rsplit("/", 2)[0] + "/nottheright" + "token" * 4 + "/"
        with pytest.raises(urllib.error.HTTPError) as exc:
            urllib.request.urlopen(bad, timeout=30)
        assert exc.value.code == 403
        proc.send_signal(signal.SIGINT)
        code, out, err = finish(proc, 15)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert code == 0, f"SIGINT: exit status {code}, stderr {err!r}"
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert len(err.strip().splitlines()) <= 1, err
    assert path.read_bytes() == before, "serving alone does not write the file"
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]


def _ignore_term() -> None:
    """``preexec_fn``: SIGINT back to its default (:func:`interruptible`), SIGTERM ignored, as ``trap '' TERM``."""
    interruptible()
    signal.signal(signal.SIGTERM, signal.SIG_IGN)


@pytest.mark.parametrize("ignored", [False, True])
def test_cli_stops_on_sigterm_as_on_sigint_unless_it_was_ignored(tmp_path, ignored):
    """``kill PID`` (SIGTERM, as a service manager stops it) ended the editor with status -15 and no word; it stops as
    on Ctrl-C: status 0, one line, nothing left beside the file. Started with SIGTERM ignored (``trap '' TERM``) it
    stays ignored, as Python leaves an ignored SIGINT (the handler overrode that: review 19e)."""
    import time as clock

    path = copy_example(tmp_path)
    proc = cli("edit", str(path), "--no-browser", "--port", "0", preexec=_ignore_term if ignored else interruptible)
    try:
        assert URL_RE.match(served_url(proc))
        proc.send_signal(signal.SIGTERM)
        if ignored:
            clock.sleep(0.5)
            assert proc.poll() is None, "SIGTERM, ignored by its starter, stopped the editor"
            proc.send_signal(signal.SIGINT)
        code, out, err = finish(proc, 15)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert code == 0 and err == "linkagekit: editor stopped\n", (code, err)
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]


def test_session_chooses_a_mode_of_a_numerical_group(tmp_path):
    """A class-3 triad: the modes listed carry their group index; asking for another one by its
    signs and group index makes its positions the pose (lk.analyze of the answer gives them back)."""
    path = tmp_path / "triad.yaml"
    path.write_text(
        "format: linkagekit/1\nunits: {length: mm, angle: deg}\n"
        "joints: {O: [0, 0], A: [20, 0], B0: [120, -10], C0: [60, 80], J1: [50, 30], J2: [95, 35], J3: [70, 55]}\n"
        "links: {ground: [O, B0, C0], crank: [O, A], l1: [A, J1], l2: [B0, J2], l3: [C0, J3], tern: [J1, J2, J3]}\n"
        "drivers: [{link: crank, pivot: O, toward: A}]\n"
    )
    s = Session(path)
    doc = lk.load(path).to_dict()
    listed = s.solve({"doc": doc, "modes_only": True, "at": {"crank": 0.0}})
    modes = listed["modes"]
    assert len(modes) >= 2 and all(m["groups"] for m in modes)
    other = next(m for m in modes if not m["reference"])
    got = s.solve({"doc": doc, "mode": other["signs"], "mode_groups": other["groups"], "at": {"crank": 0.0}})
    assert got["ok"], got
    m2 = lk.Mechanism.from_dict(got["doc"])
    res = lk.analyze(m2, {"crank": [0.0]})
    for j, (x, y) in other["joints"].items():
        assert abs(res.point(j)[0] - complex(x, y)) < 1e-9 * 100, (j, res.point(j)[0], (x, y))


# ============================================================================== vanished clients, many clients
def _requests_in_flight() -> list[threading.Thread]:
    """The server's request threads still running (socketserver names them after their target)."""
    return [t for t in threading.enumerate() if "process_request_thread" in t.name and t.is_alive()]


def _wait_for_requests(seconds: float = 60.0) -> None:
    deadline = time.monotonic() + seconds
    while _requests_in_flight():
        assert time.monotonic() < deadline, f"requests still running after {seconds} s"
        time.sleep(0.02)


def test_a_client_that_goes_away_is_not_reported(server, capfd):
    """A client that sends a full solve and resets its connection before the answer: the server
    fails to write the answer (a reset or broken pipe), says nothing on stderr, and keeps serving."""
    c = Client(server)
    body = json.dumps({"doc": server.session.mech.to_dict()}).encode()  # a full sweep: the answer is ~100 kB
    head = (
        f"POST /{server.token}/api/solve HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n"
        f"Content-Type: application/json\r\nContent-Length: {len(body)}\r\n\r\n"
    ).encode()
    for _ in range(3):
        s = socket.create_connection(("127.0.0.1", server.port), timeout=10)
        s.sendall(head + body)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # close with a reset
        s.close()
    _wait_for_requests()
    c.still_serving()
    _wait_for_requests()
    out, err = capfd.readouterr()
    assert err == "", f"a vanished client was reported on stderr: {err!r}"


def test_an_unexpected_error_is_one_line(server, capfd, monkeypatch):
    """An exception the handler does not expect: a 500 whose JSON error is one line, one short line
    on stderr, no traceback anywhere; the server keeps serving."""

    def broken(token: str) -> str:
        raise RuntimeError("the page broke\nwith a second line")

    monkeypatch.setattr(server.session, "page", broken)
    c = Client(server)
    status, headers, body = c.page()
    got = json_error(status, headers, body, "a page that broke")
    assert status == 500 and "RuntimeError: the page broke with a second line" in got["error"], got
    assert "\n" not in got["error"] and "Traceback" not in got["error"]
    _wait_for_requests()
    monkeypatch.undo()
    c.still_serving()
    _wait_for_requests()
    out, err = capfd.readouterr()
    lines = err.splitlines()
    assert len(lines) == 1 and "RuntimeError" in lines[0] and "the page broke" in lines[0], err
    assert len(lines[0]) <= 200 and "Traceback" not in err, err


def test_many_concurrent_connections_are_all_answered(server):
    """200 clients connect at once (loopback): every one gets its answer, within a bounded time."""
    n, seconds = 200, 60.0
    assert server.request_queue_size >= 128
    start = threading.Barrier(n, timeout=30)
    answers: list[int] = []
    failures: list[str] = []
    lock = threading.Lock()

    def one(i: int) -> None:
        try:
            start.wait()
            conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=seconds)
            conn.request("GET", f"/{'x' * 24}/", headers={"Connection": "close"})
            r = conn.getresponse()
            r.read()
            conn.close()
            with lock:
                answers.append(r.status)
        except Exception as exc:  # noqa: BLE001 - collected and reported below
            with lock:
                failures.append(f"client {i}: {type(exc).__name__}: {exc}")

    t0 = time.monotonic()
    clients = [threading.Thread(target=one, args=(i,), daemon=True) for i in range(n)]
    for t in clients:
        t.start()
    for t in clients:
        t.join(max(0.0, seconds - (time.monotonic() - t0)))
    elapsed = time.monotonic() - t0
    assert not any(t.is_alive() for t in clients), f"clients still waiting after {elapsed:.1f} s"
    assert not failures, f"{len(failures)} of {n} failed, e.g. {failures[:3]}"
    assert answers == [403] * n, sorted(set(answers))
    Client(server).still_serving()


# ============================================================================== issue 23: the editor under faults
def _serve(session: Session, **kw) -> EditorServer:
    srv = EditorServer(session, 0, **kw)
    threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True).start()
    return srv


def _stop(srv: EditorServer) -> None:
    srv.shutdown()
    srv.server_close()


def test_two_drivers_with_sweeps_of_different_lengths_open(tmp_path):
    """A valid two-driver file whose second crank is swept 0..0 (one sample against 361): every
    command opens it (lk.analyze holds that driver at its pose value), and so does the editor."""
    path = tmp_path / "fivebar.yaml"
    text = (EXAMPLES / "fivebar_two_drivers.yaml").read_text(encoding="utf-8")
    path.write_text(text.replace("angles: {start: -60, stop: 300, step: 1}", "angles: {start: 0, stop: 0, step: 1}"))
    session = Session(path)
    res = lk.analyze(session.mech)
    page = session.page("t" * 24)
    assert 'data-role="mechanism"' in page
    answer = session.solve({"doc": session.mech.to_dict()})
    assert answer["ok"] is True
    cols = answer["scene"]["columns"]
    assert len(cols["input:crank1"]) == res.n == 361
    assert answer["pose_index"] == 120 and cols["input:crank1"][120] == 120.0  # the pose's own input
    assert res.inputs["crank2"] == pytest.approx([60.0] * 361, abs=1e-9)  # held at the pose's value
    assert cols["input:crank2"] == pytest.approx([60.0] * 361, abs=1e-9)


@pytest.mark.parametrize("body", ["[" * 5000 + "]" * 5000, '{"a":' * 500 + "1" + "}" * 500])
def test_deeply_nested_json_is_refused_in_one_line(server, capfd, body):
    """JSON nested past the parser's recursion limit, or past MAX_JSON_DEPTH: 400 with one line,
    no traceback, and the server keeps serving."""
    c = Client(server)
    status, headers, data = c.request("POST", f"/{c.token}/api/solve", body)
    doc = json_error(status, headers, data, "deep JSON")
    assert status == 400 and "nested deeper than" in doc["error"], doc
    c.still_serving()
    _wait_for_requests()
    assert capfd.readouterr().err == ""


def _long_triad_doc(session: Session) -> dict:
    doc = session.mech.to_dict()
    doc["drivers"][0]["angles"] = {"start": 0, "stop": 3600, "step": 0.36}  # 10,001 samples of a class-3 group
    return doc


def test_a_solve_over_its_budget_is_stopped_with_a_message(tmp_path, capfd):
    """A 10,000-sample sweep of the class-3 triad (minutes of walking) against a budget of 0.5 s:
    answered 503 with a message naming the budget, after about the budget (CPU time bounded),
    and the server then answers the next request."""
    session = Session(copy_example(tmp_path, "triad_six_modes.yaml"))
    srv = _serve(session, solve_seconds=0.5)
    try:
        c = Client(srv)
        cpu0 = time.process_time()
        status, headers, data = c.solve({"doc": _long_triad_doc(session)})
        cpu = time.process_time() - cpu0
        doc = json_error(status, headers, data, "a long solve")
        assert status == 503 and doc.get("stopped") is True and "0.5 s" in doc["error"], doc
        assert cpu < 5.0, f"the stopped solve used {cpu:.1f} CPU-s"
        assert srv.watch.stopped["budget"] == 1
        srv.watch.seconds = 60.0
        status, _, data = c.solve({"doc": session.mech.to_dict(), "coarse": True})
        assert status == 200 and json.loads(data)["ok"] is True
    finally:
        _stop(srv)
    _wait_for_requests()
    assert capfd.readouterr().err == ""


def test_a_page_over_its_budget_is_a_readable_page_and_one_line(tmp_path, capfd):
    """A file whose own sweep takes longer than the budget: the page is a short HTML page that
    says what to do (not JSON in the browser), and the terminal gets the same in one line."""
    path = copy_example(tmp_path, "triad_six_modes.yaml")
    long_doc = _long_triad_doc(Session(path))
    lk.save(lk.Mechanism.from_dict(long_doc), path)
    srv = _serve(Session(path), solve_seconds=0.5)
    try:
        c = Client(srv)
        status, headers, data = c.request("GET", f"/{c.token}/")
        assert status == 503 and headers.get("Content-Type", "").startswith("text/html"), (status, headers)
        text = data.decode()
        assert "solve budget (0.5 s)" in text and "--solve-seconds" in text and "<p>" in text
    finally:
        _stop(srv)
    _wait_for_requests()
    err = capfd.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("linkagekit: the page took longer than the editor's solve budget"), err


def test_a_solve_whose_client_left_is_stopped(tmp_path, capfd):
    """The same long solve, its client closing the connection 0.2 s after sending it (a closed
    tab): the watch stops it (long before the 60 s budget), nothing is written to stderr, and
    the request's thread ends."""
    session = Session(copy_example(tmp_path, "triad_six_modes.yaml"))
    srv = _serve(session, solve_seconds=60.0)
    try:
        body = json.dumps({"doc": _long_triad_doc(session)}).encode()
        s = socket.create_connection(("127.0.0.1", srv.port), timeout=10)
        s.sendall(
            f"POST /{srv.token}/api/solve HTTP/1.1\r\nHost: 127.0.0.1:{srv.port}\r\n"
            f"Content-Type: application/json\r\nContent-Length: {len(body)}\r\n\r\n".encode()
            + body
        )
        time.sleep(0.2)
        s.close()
        _wait_for_requests(30.0)  # hangs for minutes without the watch
        assert srv.watch.stopped == {"budget": 0, "gone": 1}
    finally:
        _stop(srv)
    assert capfd.readouterr().err == ""


def test_the_watch_never_stops_a_finished_solve(tmp_path):
    """Many quick solves under a tiny budget race the watch: each is either answered or stopped
    (503), and a stop is never raised later in the thread (the server keeps answering)."""
    session = Session(copy_example(tmp_path))
    srv = _serve(session, solve_seconds=0.02)
    try:
        c = Client(srv)
        doc = session.mech.to_dict()
        seen = set()
        for _ in range(30):
            status, _, data = c.solve({"doc": doc, "coarse": True})
            seen.add(status)
            assert status in (200, 503), data[:200]
        srv.watch.seconds = 30.0
        c.still_serving()
    finally:
        _stop(srv)


def test_save_through_a_symlink_replaces_the_real_file(tmp_path):
    """FILE is a symbolic link to a file in another directory: saving (the editor's save and
    lk.save) replaces the real file, the link stays a link to it, and no temporary is left."""
    real = copy_example(tmp_path, sub="real")
    link = tmp_path / "work" / SEED000
    link.parent.mkdir()
    link.symlink_to(real)
    session = Session(link)
    doc = session.mech.to_dict()
    doc["name"] = "through the link"
    session.save({"doc": doc, "base": session.base})
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert lk.load(real).name == "through the link"
    lk.save(lk.load(real), link)
    assert link.is_symlink() and lk.load(real).name == "through the link"
    left = {p.name for p in (tmp_path / "real").iterdir()} | {p.name for p in (tmp_path / "work").iterdir()}
    assert left == {SEED000, SEED000 + ".bak"}, left


def test_stray_temporaries_are_removed_at_start_and_nothing_else(tmp_path):
    """What a save killed half-way leaves (.FILE.<12 hex>.tmp, .FILE.bak.<12 hex>.tmp) is removed
    when the editor opens FILE; names that only look alike, other files' temporaries, and a link
    named like a temporary stay."""
    path = copy_example(tmp_path)
    d = path.parent
    ours = [f".{SEED000}.0123456789ab.tmp", f".{SEED000}.bak.a1b2c3d4e5f6.tmp"]
    others = [
        f".{SEED000}.0123456789AB.tmp",  # not our (lower-case) hex
        f".{SEED000}.0123456789a.tmp",  # 11 digits
        f".{SEED000}.0123456789ab.tmp.keep",
        ".other.yaml.0123456789ab.tmp",
        f"{SEED000}.0123456789ab.tmp",  # not hidden
    ]
    for name in ours + others:
        (d / name).write_text("partial")
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    (d / f".{SEED000}.ffffffffffff.tmp").symlink_to(victim)
    Session(path)
    left = {p.name for p in d.iterdir()}
    assert not set(ours) & left
    assert set(others) | {SEED000, f".{SEED000}.ffffffffffff.tmp"} == left
    assert victim.read_text() == "keep me"


def _dragged(session: Session, joint: str, dx: float, dy: float, coarse: bool = False) -> dict:
    """The answer to a drag as the page sends it: the drawn pose at the pose's sample, ``joint`` moved."""
    doc = session.mech.to_dict()
    first = session.solve({"doc": doc, "coarse": True})
    at = joints_at(first["scene"], first["pose_index"])
    pose = {j: list(xy) for j, xy in at.items()}
    pose[joint] = [pose[joint][0] + dx, pose[joint][1] + dy]
    return session.solve({"doc": doc, "pose": pose, "moved": [joint], "coarse": coarse})


@pytest.mark.parametrize("moved", [True, False])
def test_save_after_a_drag_changes_only_what_the_drag_changed(tmp_path, moved):
    """The five-bar's tracer P dragged (the page's drawn pose: the solver's numbers, e.g.
    -14.999999999999991 for -15), then saved: the file differs from the original in exactly
    two lines: P's coordinates, and link1's lengths, which lose the two pairs through P and keep
    C-E: 60.  Every other line, its flow style and its integers (30, not 30.0) stay as written.
    Without 'moved' the server finds the moved joint itself."""
    path = copy_example(tmp_path, "fivebar_two_drivers.yaml")
    original = path.read_text(encoding="utf-8").splitlines()
    session = Session(path)
    doc = session.mech.to_dict()
    first = session.solve({"doc": doc, "coarse": True})
    at = joints_at(first["scene"], first["pose_index"])
    assert at["C"] != (-15.0, 25.9807621135332)  # the drawn pose is the solver's rounding of the file's
    pose = {j: list(xy) for j, xy in at.items()}
    pose["P"] = [16.5, 89.25]
    request = {"doc": doc, "pose": pose} | ({"moved": ["P"]} if moved else {})
    answer = session.solve(request)
    assert answer["ok"], answer
    session.save({"doc": answer["doc"], "base": session.base})
    saved = path.read_text(encoding="utf-8").splitlines()
    changed = [(a, b) for a, b in zip(original, saved, strict=True) if a != b]
    assert changed == [
        ("  P: [16.1807300401858, 88.6526224191045]", "  P: [16.5, 89.25]"),
        (
            "  link1: {joints: [C, E, P], lengths: {C-E: 60, E-P: 20, C-P: 70}}",
            "  link1: {joints: [C, E, P], lengths: {C-E: 60}}",
        ),
    ], changed


def test_save_keeps_block_style_and_a_drag_keeps_exact_numbers(tmp_path):
    """A file written in block style stays in block style where it was; a number such as -7.8
    that the drag did not touch is written -7.8 (not the solver's -7.799999999999999); the crank
    pin C dragged: its coordinates change and the crank's given length goes (read off the pose)."""
    path = tmp_path / "block.yaml"
    path.write_text(
        "format: linkagekit/1\nname: block\nunits:\n  length: mm\n  angle: deg\njoints:\n  A: [0, 0]\n"
        "  B: [-7.1, 0.3]\n  C: [1.86, 2.48]\n  D: [-6.1, 4.7]\n  E: [-7.8, 6.1]\nlinks:\n  ground: [A, B]\n"
        "  crank:\n    joints: [A, C]\n    lengths:\n      A-C: 3.1\n  coupler: [C, D]\n  rocker: [B, D, E]\n"
        "drivers:\n  - link: crank\n    pivot: A\n    toward: C\n    angles: {start: 0, stop: 360, step: 5}\n",
        encoding="utf-8",
    )
    before = path.read_text(encoding="utf-8").splitlines()
    session = Session(path)
    answer = _dragged(session, "C", 0.25, -0.125)
    assert answer["ok"], answer
    session.save({"doc": answer["doc"], "base": session.base})
    after = path.read_text(encoding="utf-8").splitlines()
    c = answer["doc"]["joints"]["C"]
    assert [a for a in after if a not in before] == [f"  C: [{c[0]!r}, {c[1]!r}]"]
    assert [b for b in before if b not in after] == ["  C: [1.86, 2.48]", "    lengths:", "      A-C: 3.1"]


@pytest.mark.parametrize("at", [0.0, 90.0])
def test_a_mode_switch_keeps_every_given_length(tmp_path, at):
    """Choosing another assembly mode changes no dimension: the answer's document keeps every given length
    exactly (seed000: the coupler's C-D, C-P, D-P = 5 and the rocker's B-D = 5, though D and P move; at 90 deg
    the crank's A-C = 2 too, though C moves), it is in the mode chosen (lk.analyze at that input gives the
    mode's positions back, 1e-9 of the size), and Save writes the file's own lines for those lengths."""
    path = copy_example(tmp_path)
    original = path.read_text(encoding="utf-8").splitlines()
    session = Session(path)
    mech = session.mech
    doc = mech.to_dict()
    listed = session.solve({"doc": doc, "modes_only": True, "at": {"crank": at}})
    other = next(m for m in listed["modes"] if not m["reference"])
    answer = session.solve({"doc": doc, "mode": other["signs"], "mode_groups": other["groups"], "at": {"crank": at}})
    assert answer["ok"], answer
    m2 = lk.Mechanism.from_dict(answer["doc"])
    moved = [j for j in mech.joint_names if m2.joints[j] != mech.joints[j]]
    assert set(moved) >= {"D", "P"} and ("C" in moved) == (at != 0.0), moved
    for ln in mech.links:
        assert dict(m2.link(ln.name).lengths) == dict(ln.lengths), (ln.name, m2.link(ln.name).lengths, ln.lengths)
    res = lk.analyze(m2, {"crank": [at]})
    for j, (x, y) in other["joints"].items():
        assert abs(res.point(j)[0] - complex(x, y)) < 1e-9 * mech.length_scale, (j, res.point(j)[0], (x, y))
    session.save({"doc": answer["doc"], "base": session.base})
    saved = path.read_text(encoding="utf-8").splitlines()
    lines = [ln for ln in original if "lengths:" in ln]
    assert len(lines) == 3 and all(ln in saved for ln in lines), (lines, saved)


def test_save_after_an_undone_drag_writes_the_files_integers(tmp_path):
    """Jansen's foot F dragged and saved (the foot's L-F: 49 and W-F go, read off the pose), then the
    original document (Undo) saved: the file is the original again, line for line, ``L-F: 49`` and not
    ``L-F: 49.0`` (the style of the file as opened is kept where the file saved in between lacks the number)."""
    path = copy_example(tmp_path, "jansen_leg.yaml")
    original = path.read_text(encoding="utf-8")
    session = Session(path)
    mech = session.mech
    f = mech.joints["F"]
    dragged = posed(mech, {"F": [f.real + 3.0, f.imag + 1.0]}, ["F"])
    session.save({"doc": dragged.to_dict(), "base": session.base})
    assert "L-F" not in path.read_text(encoding="utf-8")
    session.save({"doc": mech.to_dict(), "base": session.base})
    assert path.read_text(encoding="utf-8") == original


def test_a_class3_drag_computes_the_exact_range_once_per_release(tmp_path, monkeypatch):
    """Dragging a joint of the class-3 triad: the coarse moves never compute the exact assembly
    range (the continuation behind the curves' breaks, 72 % of a move's cost before), and after
    the first move they walk only the stretch of the coarse grid that assembled, with a margin
    (fewer samples, the same positions there); the release computes the range once (checks and
    breaks share it)."""
    import linkagekit.checks as checks_mod
    from linkagekit.web.editor import COARSE_SAMPLES, WINDOW_MARGIN

    calls = []
    real = checks_mod.continuation_intervals
    monkeypatch.setattr(checks_mod, "continuation_intervals", lambda *a, **k: calls.append(1) or real(*a, **k))
    session = Session(copy_example(tmp_path, "triad_six_modes.yaml"))
    doc = session.mech.to_dict()
    first = session.solve({"doc": doc, "coarse": True})
    at = joints_at(first["scene"], first["pose_index"])
    pose = {j: list(xy) for j, xy in at.items()}
    answers = []
    cpu0 = time.process_time()
    for k in range(4):
        pose["J1"] = [pose["J1"][0] + 0.01 * k, pose["J1"][1]]
        answers.append(session.solve({"doc": doc, "pose": pose, "moved": ["J1"], "coarse": True}))
    cpu = time.process_time() - cpu0
    assert calls == [], "a coarse move computed the exact assembly range"
    full_n = len(answers[0]["scene"]["columns"]["assembled"])
    assert full_n >= COARSE_SAMPLES
    later = [a["scene"]["columns"]["assembled"] for a in answers[1:]]
    # the window spans the assembled stretch (since issue 29 a crank's input is a direction: on a grid of a turn
    # the pose's range may show as two stretches, at both ends of the grid, and the window then spans the grid)
    span = [int(np.ptp(np.flatnonzero(a))) + 1 for a in later]
    assert all(sum(a) >= 10 and len(a) <= s + 2 * WINDOW_MARGIN + 1 for a, s in zip(later, span, strict=True)), [
        len(a) for a in later
    ]
    assert answers[-1]["scene"]["breaks"] == []
    # the windowed move gives the same positions as the whole coarse grid at its samples
    from linkagekit.web.editor import sweep_with_pose

    last = answers[-1]
    m = lk.Mechanism.from_dict(last["doc"])
    grid = sweep_with_pose(m, COARSE_SAMPLES)[0]["crank"]
    whole = lk.analyze(m, {"crank": grid})
    shown = np.array(last["scene"]["columns"]["input:crank"], float)
    k = np.searchsorted(grid, shown)
    assert np.array_equal(grid[k], shown)
    got = np.array([np.nan if v is None else v for v in last["scene"]["columns"]["J2.x"]], float)
    assert np.allclose(whole.xy("J2")[k, 0], got, rtol=0, atol=1e-9 * m.length_scale, equal_nan=True)
    assert cpu < 30.0, f"4 coarse moves took {cpu:.1f} CPU-s"  # generous: only catches the old cost times ten
    full = session.solve({"doc": doc, "pose": pose, "moved": ["J1"]})
    assert full["ok"] and len(calls) == 1, f"the release computed the exact range {len(calls)} times"


def test_kill_9_during_saves_loses_nothing_and_leaves_nothing(tmp_path):
    """`linkagekit edit` killed (SIGKILL) three times while a client saves back and forth: FILE and
    FILE.bak always load, every start removes what a kill left, and after a last start and a
    normal stop the directory holds FILE and FILE.bak only, with nothing on stderr.
    (benchmarks/attack_editor.py does this 50 times.)"""
    path = copy_example(tmp_path)
    doc = lk.load(path).to_dict()
    docs = [doc | {"name": "A"}, doc | {"name": "B"}]

    def start() -> tuple[subprocess.Popen, int, str]:
        proc = cli("edit", str(path), "--no-browser", "--port", "0")
        m = URL_RE.match(proc.stdout.readline().strip())
        assert m, proc
        return proc, int(m.group(1)), m.group(2)

    for k in range(3):
        proc, port, token = start()
        assert not [p for p in path.parent.iterdir() if p.name.endswith(".tmp")], "a temporary survived a start"
        done = threading.Event()

        def saves(port: int = port, token: str = token, done: threading.Event = done) -> None:
            i = 0
            while not done.is_set():
                base = hashlib.sha256(path.read_bytes()).hexdigest()
                try:
                    c = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
                    c.request(
                        "POST",
                        f"/{token}/api/save",
                        json.dumps({"doc": docs[i % 2], "base": base}),
                        {"Content-Type": "application/json"},
                    )
                    c.getresponse().read()
                except (OSError, http.client.HTTPException):
                    return
                i += 1

        t = threading.Thread(target=saves, daemon=True)
        t.start()
        time.sleep(0.1 + 0.05 * k)
        proc.kill()
        proc.communicate(timeout=30)
        done.set()
        t.join(15)
        assert lk.load(path).name in {"A", "B", doc.get("name")}
        backup = path.with_name(path.name + ".bak")
        assert not backup.exists() or lk.load(backup).joints == lk.load(path).joints
    proc, _, _ = start()
    proc.send_signal(signal.SIGINT)
    code, out, err = finish(proc)
    assert code == 0 and err.strip() == "linkagekit: editor stopped", err  # the normal goodbye, no traceback
    assert sorted(p.name for p in path.parent.iterdir()) == [SEED000, SEED000 + ".bak"]


def test_slow_connections_do_not_block_the_editor(server, monkeypatch):
    """20 connections that send their request line one byte at a time: a normal request is
    answered meanwhile, and the server drops each slow one after its request timeout (0.5 s
    here, TIMEOUT in use)."""
    from linkagekit.web import editor

    monkeypatch.setattr(editor, "TIMEOUT", 0.5)
    socks = [socket.create_connection(("127.0.0.1", server.port), timeout=10) for _ in range(20)]
    for s in socks:
        s.sendall(b"G")
    Client(server).still_serving()
    dropped = 0
    for s in socks:
        s.settimeout(10)
        try:
            dropped += s.recv(1) == b""
        except ConnectionResetError:
            dropped += 1
        s.close()
    assert dropped == 20


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "1e9", "abc"])
def test_cli_refuses_a_bad_solve_budget_in_one_line(tmp_path, value):
    path = copy_example(tmp_path)
    proc = cli("edit", str(path), "--no-browser", "--solve-seconds", value)
    code, out, err = finish(proc, 30)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and "--solve-seconds" in err, (code, err)


def test_cli_passes_its_solve_budget_to_the_server(tmp_path, monkeypatch):
    from linkagekit import cli as cli_module
    from linkagekit.web import editor as editor_module

    seen: dict[str, float] = {}

    def fake_serve(path, port=0, open_browser=True, solve_seconds=0.0):
        seen["budget"] = solve_seconds

    monkeypatch.setattr(editor_module, "serve", fake_serve)
    path = copy_example(tmp_path)
    assert cli_module.main(["edit", str(path), "--no-browser", "--solve-seconds", "2.5"]) == 0
    assert seen == {"budget": 2.5}
    assert cli_module.main(["edit", str(path), "--no-browser"]) == 0
    assert seen == {"budget": editor_module.SOLVE_SECONDS}


def test_a_drag_drops_the_given_length_of_a_joint_whose_name_has_a_dash():
    """``lengths: {A-C-1: 2}`` names joints A and C-1: dragging C-1 drops that length (the drag sets it)."""
    doc = {
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"A": [0, 0], "B": [4, 0], "C-1": [2, 0], "D": [3.5, 2]},
        "links": {
            "ground": ["A", "B"],
            "crank": {"joints": ["A", "C-1"], "lengths": {"A-C-1": 2}},
            "coupler": ["C-1", "D"],
            "rocker": ["B", "D"],
        },
        "drivers": [{"link": "crank", "pivot": "A", "toward": "C-1", "angles": {"start": 0, "stop": 360, "step": 10}}],
    }
    mech = lk.Mechanism.from_dict(doc)
    moved = posed(mech, {"C-1": [3, 0]}, ["C-1"])
    assert dict(moved.link("crank").lengths) == {}
    assert abs(moved.link("crank").length("A", "C-1") - 3.0) < 1e-12


# ============================================================================== review 8: the editor attacked
def _victim(tmp_path: Path) -> Path:
    victim = tmp_path / "elsewhere" / "precious.txt"
    victim.parent.mkdir(exist_ok=True)
    victim.write_text("precious user data\n")
    return victim


def test_save_replaces_a_planted_backup_link_and_never_writes_through_it(tmp_path):
    """FILE.bak planted as a link (to a file, or dangling): the save replaces the link itself by a regular file
    holding the old bytes; the file it pointed to stays as it was, and a dangling one is not created."""
    victim = _victim(tmp_path)
    for k, target in enumerate((victim, victim.with_name("created_by_editor.sh"))):
        path = copy_example(tmp_path, sub=f"shared{k}")
        original = path.read_bytes()
        backup = path.with_name(path.name + ".bak")
        backup.symlink_to(target)
        s = Session(path)
        assert s.save({"doc": s.mech.to_dict() | {"name": "saved"}, "base": s.base})["ok"] is True
        assert not backup.is_symlink() and backup.read_bytes() == original
        assert lk.load(path).name == "saved"
    assert victim.read_text() == "precious user data\n"
    assert sorted(p.name for p in victim.parent.iterdir()) == ["precious.txt"]


@pytest.fixture
def swap_temporaries(tmp_path, monkeypatch):
    """Every temporary file (``.NAME.<hex>.tmp``) is swapped for a link to a victim as soon as it is created, as
    another user who can write the directory would: returns the victim."""
    from linkagekit import files

    victim = _victim(tmp_path)
    real_open = os.open

    def racing_open(path, flags, mode=0o777, *args, **kw):
        fd = real_open(path, flags, mode, *args, **kw)
        name = os.fsdecode(path)
        if flags & os.O_CREAT and name.endswith(".tmp"):
            os.rename(name, name + ".moved")
            os.symlink(victim, name)
        return fd

    monkeypatch.setattr(files.os, "open", racing_open)
    return victim


def test_a_temporary_swapped_for_a_link_is_never_written_through_nor_renamed(tmp_path, swap_temporaries):
    """The temporary file is written through the descriptor that created it, and its name is checked to be still
    that file before the rename: a link swapped in is neither written through nor renamed over the file (the
    editor's save, lk.save, the report's write and atomic_output all refuse in one line naming the file)."""
    from linkagekit.files import atomic_output

    victim = swap_temporaries
    path = copy_example(tmp_path)
    original = path.read_bytes()
    s = Session(path)
    with pytest.raises(LinkageError, match=r"precious|replaced by another program") as err:
        s.save({"doc": s.mech.to_dict() | {"name": "saved"}, "base": s.base})
    assert "\n" not in str(err.value) and SEED000 in str(err.value)
    with pytest.raises(LinkageError, match="replaced by another program"):
        lk.save(s.mech, path)
    with pytest.raises(LinkageError, match="replaced by another program"), atomic_output(path) as tmp:
        tmp.write_text("written by name", encoding="utf-8")  # as matplotlib does: through the link
    assert not path.is_symlink() and path.read_bytes() == original
    assert victim.read_text() in ("precious user data\n", "written by name")  # a writer by name follows the link
    assert "format: linkagekit" not in victim.read_text()


def test_the_temporary_is_private_and_takes_the_files_mode_and_owner(tmp_path, monkeypatch):
    """The temporary file is created 0600 (not with the umask's 0644) before it takes the mode of the file it
    replaces; a 0600 file saved by the editor leaves a 0600 backup (the file's mode, not the umask's)."""
    from linkagekit import files

    path = copy_example(tmp_path)
    path.chmod(0o600)
    created: list[int] = []
    real_open = os.open

    def watching_open(p, flags, mode=0o777, *args, **kw):
        if flags & os.O_CREAT and os.fsdecode(p).endswith(".tmp"):
            created.append(mode)
        return real_open(p, flags, mode, *args, **kw)

    monkeypatch.setattr(files.os, "open", watching_open)
    old_umask = os.umask(0o022)
    try:
        s = Session(path)
        assert s.save({"doc": s.mech.to_dict() | {"name": "saved"}, "base": s.base})["ok"] is True
    finally:
        os.umask(old_umask)
    backup = path.with_name(path.name + ".bak")
    assert created == [0o600, 0o600]
    assert stat_mode(path) == 0o600 and stat_mode(backup) == 0o600
    if os.geteuid() == 0:  # only root may give a file another owner
        os.chown(path, 65534, 65534)
        s = Session(path)
        assert s.save({"doc": s.mech.to_dict() | {"name": "again"}, "base": s.base})["ok"] is True
        assert {(p.stat().st_uid, p.stat().st_gid) for p in (path, backup)} == {(65534, 65534)}


def stat_mode(p: Path) -> int:
    return p.stat().st_mode & 0o7777


def _in_thread(fn, seconds: float = 10.0):
    """``fn()`` in a thread: its result or exception, or a failure when it has not returned in ``seconds``."""
    out: dict[str, object] = {}

    def run() -> None:
        try:
            out["value"] = fn()
        except BaseException as exc:  # noqa: BLE001 - handed to the test
            out["error"] = exc

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(seconds)
    assert not t.is_alive(), f"still running after {seconds} s"
    return out


def test_save_reads_the_file_bounded_and_a_fifo_or_a_huge_file_is_refused(server, tmp_path):
    """The file swapped (after the page was served) for a FIFO, a link to /dev/zero or a file over the limit of a
    mechanism file: a save is answered at once, 409 in one line naming the file; nothing is written."""
    from linkagekit.files import MAX_FILE_BYTES

    c = Client(server)
    path = server.session.path
    original = path.read_bytes()
    doc, base = server.session.mech.to_dict(), server.session.base
    for what, swap, says in (
        ("FIFO", os.mkfifo, "FIFO"),
        ("/dev/zero", lambda p: os.symlink("/dev/zero", p), "character device"),
        ("huge", lambda p: os.truncate(os.open(p, os.O_CREAT | os.O_WRONLY), MAX_FILE_BYTES + 10), "more than"),
    ):
        path.unlink()
        swap(path)
        got = _in_thread(lambda: c.save({"doc": doc, "base": base}))
        status, headers, body = got["value"]
        err = json_error(status, headers, body, what)
        assert status == 409 and path.name in err["error"] and says in err["error"] and "not saved" in err["error"], err
        assert not path.with_name(path.name + ".bak").exists()
    path.unlink()
    path.write_bytes(original)
    c.still_serving()


def test_the_browser_is_opened_on_a_private_page_not_on_the_token_url(tmp_path, monkeypatch):
    """The browser's command line holds no token: it is given a file:// page (0600, in a fresh 0700 directory)
    that sends it to the editor's URL; the page is removed when the editor stops."""
    import webbrowser

    from linkagekit.web import editor as editor_module

    opened: list[str] = []
    ready = threading.Event()
    servers: list[EditorServer] = []
    monkeypatch.setattr(webbrowser, "open", lambda url, *a, **kw: opened.append(url) or True)

    def on_ready(srv: EditorServer) -> None:
        servers.append(srv)
        ready.set()

    path = copy_example(tmp_path)
    t = threading.Thread(target=editor_module.serve, args=(path,), kwargs={"ready": on_ready}, daemon=True)
    t.start()
    assert ready.wait(30)
    srv = servers[0]
    for _ in range(200):
        if opened:
            break
        time.sleep(0.02)
    assert len(opened) == 1 and opened[0].startswith("file://"), opened
    assert srv.token not in opened[0]
    page = Path(urllib.request.url2pathname(opened[0][len("file://") :]))
    assert stat_mode(page) == 0o600 and stat_mode(page.parent) == 0o700
    text = page.read_text(encoding="utf-8")
    assert srv.url in text and 'http-equiv="refresh"' in text
    srv.shutdown()
    t.join(10)
    assert not page.exists() and not page.parent.exists()


def _page_state(body: bytes) -> dict:
    m = re.search(rb'id="lk-editor">(.*?)</script>', body, re.S)
    assert m, body[:300]
    return json.loads(m.group(1))


def test_a_page_load_takes_the_file_as_another_program_changed_it(server):
    """After another program changed the file, a save is refused (409) and a reload of the page edits the file as
    it is now (its mechanism, text and hash), so the next save succeeds; a file that no longer loads, or is gone,
    makes the page say so in one line naming it."""
    c = Client(server)
    path = server.session.path
    first = _page_state(c.page()[2])
    text = path.read_text(encoding="utf-8")
    name = lk.load(path).name
    path.write_text(text.replace(name, "changed elsewhere"), encoding="utf-8")
    status, _, body = c.save({"doc": first["answer"]["doc"], "base": first["base"]})
    assert status == 409 and "reload the page" in json.loads(body)["error"]
    status, _, body = c.page()
    assert status == 200
    state = _page_state(body)
    assert state["base"] == hashlib.sha256(path.read_bytes()).hexdigest() != first["base"]
    assert state["answer"]["doc"]["name"] == "changed elsewhere"
    status, _, body = c.save({"doc": state["answer"]["doc"] | {"name": "saved after reload"}, "base": state["base"]})
    assert status == 200 and json.loads(body)["ok"] is True
    assert lk.load(path).name == "saved after reload"
    assert "# " in path.read_text(encoding="utf-8")  # the comments of the file as changed are kept
    for what, change, says in (
        ("broken", lambda: path.write_text("format: linkagekit/1\njoints: [\n"), "YAML syntax error"),
        ("deleted", path.unlink, "no such file any more"),
    ):
        change()
        status, headers, body = c.page()
        page = body.decode("utf-8")
        assert status == 409 and headers["Content-Type"].startswith("text/html"), (what, status, page[:300])
        message = re.search(r"<p>(.*)</p>", page).group(1)
        assert path.name in message and says in message and "\n" not in message, (what, message)


def test_a_file_name_that_is_not_utf8_is_shown_with_replacement_characters(tmp_path):
    """A file named with bytes that are not UTF-8 (legal on Linux): the page and the answers show its name with
    U+FFFD where those bytes are, and it saves."""
    d = tmp_path / "work"
    d.mkdir()
    raw = os.path.join(os.fsencode(d), b"m\xff.yaml")
    shutil.copyfile(EXAMPLES / SEED000, raw)
    srv = _serve(Session(os.fsdecode(raw)))
    try:
        c = Client(srv)
        status, _, body = c.page()
        assert status == 200 and _page_state(body)["file"] == "m\ufffd.yaml"
        status, _, body = c.save({"doc": srv.session.mech.to_dict(), "base": srv.session.base})
        got = json.loads(body)
        assert status == 200 and got["ok"] is True and got["saved"].endswith("m\ufffd.yaml"), got
        assert os.path.exists(raw + b".bak")
    finally:
        _stop(srv)


def test_a_read_only_file_is_not_saved(server):
    """A file without its owner's write bit is not overwritten (even by root, whom permissions do not stop): 409,
    one line, the file and its directory as they were."""
    c = Client(server)
    path = server.session.path
    path.chmod(0o444)
    before = tree(path.parent)
    status, headers, body = c.save({"doc": server.session.mech.to_dict(), "base": server.session.base})
    err = json_error(status, headers, body, "read-only")
    assert status == 409 and err["error"] == f"{path.name} is read-only: not saved"
    assert tree(path.parent) == before and stat_mode(path) == 0o444


@pytest.mark.parametrize("method", ["OPTIONS", "PUT", "DELETE", "HEAD", "PATCH"])
def test_other_methods_get_the_servers_json_error_with_its_headers(server, method):
    c = Client(server)
    status, headers, body = c.request(method, f"/{server.token}/api/save", body=None)
    h = {k.lower(): v for k, v in headers.items()}
    assert status == 501 and h["content-type"] == "application/json", (status, h, body[:200])
    assert "default-src 'none'" in h["content-security-policy"] and h["x-content-type-options"] == "nosniff"
    if method != "HEAD":
        assert method in json_error(status, headers, body, method)["error"]


def test_a_garbage_request_line_gets_a_json_error(server):
    with socket.create_connection(("127.0.0.1", server.port), timeout=10) as sock:
        sock.sendall(b"GARBAGE\r\n\r\n")
        data = b""
        while chunk := sock.recv(65536):
            data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.") and b" 400 " in head.split(b"\r\n")[0], head
    assert b"Content-Type: application/json" in head and b"X-Content-Type-Options: nosniff" in head
    assert json.loads(body)["ok"] is False


def test_bad_request_fields_are_named(server):
    """A pose that is not finite names pose.JOINT; a 'base' that is not a hash is 400 naming 'base' (not a
    conflict); a joint the document lacks, in 'pose' or 'moved', is 400 naming it."""
    c = Client(server)
    doc = server.session.mech.to_dict()
    for call, req, says in (
        ("solve", {"doc": doc, "pose": {"A": [float("inf"), 0]}}, "pose.A: expected [x, y], two finite numbers"),
        ("solve", {"doc": doc, "pose": {"A": [10**400, 0]}}, "pose.A: expected [x, y]"),
        ("solve", {"doc": doc, "pose": {"ZZ": [1, 2]}}, "pose: the mechanism has no joint 'ZZ'"),
        ("solve", {"doc": doc, "pose": {"D": [1.25, 4.6]}, "moved": ["nope"]}, "moved: the mechanism has no joint"),
        ("save", {"doc": doc, "base": None}, "'base'"),
        ("save", {"doc": doc, "base": 5}, "'base'"),
    ):
        body = json.dumps(req).replace("Infinity", "1e999")
        status, headers, data = c.request("POST", f"/{server.token}/api/{call}", body)
        err = json_error(status, headers, data, str(req)[-60:])
        assert status == 400 and says in err["error"], (status, err)
