/* linkagekit editor: editing on top of the report's viewer (viewer.js). It solves nothing.
 *
 * Every edit changes the mechanism document (the file's own structure) and sends it to the
 * local server, which solves it with the Python solver and answers with the new document and
 * its scene; only then is anything redrawn. While a joint is dragged, a coarse sweep is asked
 * for at every pointer move, with only the newest request in flight (moves that arrive
 * meanwhile are merged into the next one); on release the full sweep with checks, modes and
 * forces. A document that does not solve keeps the last good picture and shows the message.
 */
(function () {
  "use strict";
  var node = document.getElementById("lk-editor");
  if (!node) return;
  var cfg = JSON.parse(node.textContent);
  var base = "/" + cfg.token + "/";
  var lk = null, doc = cfg.answer.doc, baseHash = cfg.base;
  var undoStack = [], redoStack = [];
  var q = function (sel) { return document.querySelector(sel); };
  var message = q("[data-role=message]"), status = q("[data-role=status]");
  var svg = q("svg[data-role=mechanism]");
  var timing = window.linkagekitTiming = [];   // drag event -> redrawn frame, ms (the benchmark reads it)

  function setStatus(text) { if (status) status.textContent = text; }
  function setError(text) {
    if (!lk) return;
    lk.holdMessage = !!text;
    if (message) message.textContent = text || "";
    if (!text) lk.show(lk.current());
  }
  function clone(x) { return JSON.parse(JSON.stringify(x)); }

  function post(path, body) {
    return fetch(base + path, {method: "POST", headers: {"Content-Type": "application/json"}, body: JSON.stringify(body)})
      .then(function (r) { return r.json().then(function (j) { j.httpStatus = r.status; return j; }); });
  }

  /* ------------------------------------------------------------- solving, newest request only */
  var inflight = false, pending = null, view = null, generation = 0;
  function solve(body, done) {
    pending = {body: body, done: done, t0: body.t0};
    if (!inflight) pump();
  }
  function pump() {
    if (!pending) return;
    var job = pending; pending = null; inflight = true;
    var gen = generation;
    post("api/solve", job.body).then(function (r) {
      inflight = false;
      if (gen === generation) apply(r, job);
      if (pending) pump();
    }, function (err) {
      inflight = false;
      setError("The editor's server does not answer (" + err + "); nothing was changed.");
      if (pending) pump();
    });
  }
  function apply(r, job) {
    if (!r.ok) { setError(r.error || "could not solve"); if (job.done) job.done(false); return; }
    doc = r.doc;
    lk.load(r.scene, job.body.coarse ? view : null);
    lk.show(r.pose_index);
    setError("");
    if (!job.body.coarse) { render(r); }
    if (job.t0 !== undefined) {
      var t0 = job.t0;
      requestAnimationFrame(function () { timing.push(performance.now() - t0); });
    }
    if (job.done) job.done(true);
  }

  /* ------------------------------------------------------------- undo, redo */
  function commit(newDoc) {       // an edit that changed the document: remember the one before
    undoStack.push(lastGood); redoStack = []; lastGood = clone(newDoc); buttons();
  }
  var lastGood = clone(doc);
  function buttons() {
    q("[data-action=undo]").disabled = !undoStack.length;
    q("[data-action=redo]").disabled = !redoStack.length;
  }
  function restore(d) {
    solve({doc: d}, function (ok) { if (ok) { lastGood = clone(doc); buttons(); } });
  }
  q("[data-action=undo]").addEventListener("click", function () {
    if (!undoStack.length) return;
    redoStack.push(lastGood); restore(undoStack.pop());
  });
  q("[data-action=redo]").addEventListener("click", function () {
    if (!redoStack.length) return;
    undoStack.push(lastGood); restore(redoStack.pop());
  });
  document.addEventListener("keydown", function (e) {
    if (!(e.ctrlKey || e.metaKey) || e.target.tagName === "INPUT") return;
    if (e.key === "z" && !e.shiftKey) { e.preventDefault(); q("[data-action=undo]").click(); }
    if (e.key === "y" || (e.key === "z" && e.shiftKey)) { e.preventDefault(); q("[data-action=redo]").click(); }
  });

  /* ------------------------------------------------------------- dragging a joint */
  function svgPoint(evt) {
    var pt = svg.createSVGPoint(); pt.x = evt.clientX; pt.y = evt.clientY;
    var p = pt.matrixTransform(svg.getScreenCTM().inverse());
    return lk.viewer.toFile(p.x, p.y);
  }
  function displayedPose() {    // every joint where it is drawn now (the solver's numbers)
    var sc = lk.scene, i = lk.current(), pose = {};
    sc.joints.forEach(function (j) { pose[j] = [sc.columns[j + ".x"][i], sc.columns[j + ".y"][i]]; });
    return pose;
  }
  var drag = null;
  svg.addEventListener("pointerdown", function (e) {
    var t = e.target;
    if (mode !== null) return;
    if (!t.hasAttribute || !t.hasAttribute("data-joint") || t.getAttribute("data-x") === "") return;
    e.preventDefault();
    lk.stop();
    svg.setPointerCapture(e.pointerId);
    view = lk.viewer.view();
    drag = {joint: t.getAttribute("data-joint"), pose: displayedPose(), doc: clone(doc), moved: false};
    generation++;
  });
  svg.addEventListener("pointermove", function (e) {
    if (!drag) return;
    var t0 = performance.now();
    var p = svgPoint(e);
    drag.pose[drag.joint] = p;
    drag.moved = true;
    solve({doc: drag.doc, pose: drag.pose, coarse: true, t0: t0});
  });
  function release(e) {
    if (!drag) return;
    var d = drag; drag = null;
    try { svg.releasePointerCapture(e.pointerId); } catch (err) { /* already released */ }
    if (!d.moved) return;
    d.pose[d.joint] = svgPoint(e);
    generation++;           // coarse answers still on the way are not drawn over the full one
    pending = null;
    solve({doc: d.doc, pose: d.pose, at: atNow()}, function (ok) {
      if (ok) commit(doc);
      else { view = null; }
    });
  }
  svg.addEventListener("pointerup", release);
  svg.addEventListener("pointercancel", release);
  function atNow() {
    var out = {}, sc = lk.scene, i = lk.current();
    sc.drivers.forEach(function (d) { out[d] = sc.columns["input:" + d][i]; });
    return out;
  }

  /* ------------------------------------------------------------- adding links, the ground */
  var mode = null, building = [];
  var finish = q("[data-action=finish-link]");
  function newName(prefix, taken) {
    for (var k = 1; ; k++) if (!Object.prototype.hasOwnProperty.call(taken, prefix + k)) return prefix + k;
  }
  q("[data-action=add-link]").addEventListener("click", function () {
    mode = mode === "link" ? null : "link"; building = [];
    svg.classList.toggle("adding", mode === "link");
    finish.hidden = mode !== "link";
    setStatus(mode === "link" ? "Click joints, or empty places for new joints; then Finish link." : "");
  });
  q("[data-action=ground]").addEventListener("click", function () {
    mode = mode === "ground" ? null : "ground";
    svg.classList.toggle("adding", mode === "ground");
    setStatus(mode === "ground" ? "Click a joint to fix it to the ground (or to free it)." : "");
  });
  svg.addEventListener("click", function (e) {
    if (mode === null) return;
    var t = e.target, joint = t.hasAttribute && t.hasAttribute("data-joint") ? t.getAttribute("data-joint") : null;
    if (mode === "ground") {
      if (!joint) return;
      var d = clone(doc), g = d.links.ground;
      var list = Array.isArray(g) ? g : g.joints;
      var k = list.indexOf(joint);
      if (k >= 0) list.splice(k, 1); else list.push(joint);
      mode = null; svg.classList.remove("adding"); setStatus("");
      edit(d);
      return;
    }
    if (!joint) {
      var p = svgPoint(e), name = newName("J", Object.assign({}, doc.joints, pendingJoints()));
      building.push({name: name, at: p});
    } else if (building.every(function (b) { return b.name !== joint; })) {
      building.push({name: joint});
    }
    setStatus("New link: " + building.map(function (b) { return b.name; }).join(" - ") + " (Finish link when done)");
  });
  function pendingJoints() { var o = {}; building.forEach(function (b) { if (b.at) o[b.name] = b.at; }); return o; }
  finish.addEventListener("click", function () {
    var d = clone(doc);
    building.forEach(function (b) { if (b.at) d.joints[b.name] = b.at; });
    if (building.length >= 2) d.links[newName("link", d.links)] = building.map(function (b) { return b.name; });
    mode = null; building = []; finish.hidden = true; svg.classList.remove("adding"); setStatus("");
    edit(d);
  });

  /* an edit of the document (numbers, links, ground, driver): solved in full, undoable */
  function edit(d) {
    generation++;
    solve({doc: d, at: atNow()}, function (ok) { if (ok) commit(doc); });
  }

  /* ------------------------------------------------------------- side panels */
  function render(r) {
    var checks = q("[data-role=checks]");
    if (checks && r.checks) checks.textContent = r.checks;
    var modes = q("[data-role=modes]");
    if (modes) {
      modes.textContent = "";
      (r.modes || []).forEach(function (m, k) {
        var b = document.createElement("button");
        b.type = "button";
        b.setAttribute("data-action", "mode");
        b.setAttribute("data-mode", String(k));
        var signs = Object.keys(m.signs).map(function (j) { return j + (m.signs[j] > 0 ? "+" : "-"); }).join(" ");
        b.textContent = (k + 1) + ": " + (signs || "the only mode") + (m.reference ? " (this one)" : "");
        b.disabled = m.reference;
        b.addEventListener("click", function () {
          generation++;
          solve({doc: doc, pose: m.joints, at: atNow()}, function (ok) { if (ok) commit(doc); });
        });
        modes.appendChild(b);
      });
      if (r.modes_note) { var p = document.createElement("p"); p.textContent = r.modes_note; modes.appendChild(p); }
    }
    var table = q("[data-role=numbers]");
    if (table) {
      table.textContent = "";
      Object.keys(r.lengths || {}).forEach(function (ln) {
        Object.keys(r.lengths[ln]).forEach(function (pair) {
          row(table, ln + " " + pair, r.lengths[ln][pair], "length", function (v) {
            var d = clone(doc), entry = d.links[ln];
            if (Array.isArray(entry)) entry = d.links[ln] = {joints: entry};
            entry.lengths = Object.assign({}, entry.lengths || {});
            entry.lengths[pair] = v;
            edit(d);
          });
        });
      });
      Object.keys(doc.links).forEach(function (ln) {
        if (ln === "ground") return;
        var entry = doc.links[ln];
        var mass = Array.isArray(entry) ? 0 : (entry.mass || 0);
        row(table, ln + " mass [kg]", mass, "mass", function (v) {
          var d = clone(doc), e2 = d.links[ln];
          if (Array.isArray(e2)) e2 = d.links[ln] = {joints: e2};
          e2.mass = v;
          edit(d);
        });
      });
    }
    var drv = q("[data-role=driver]");
    if (drv) {
      drv.textContent = "";
      var sel = document.createElement("select");
      sel.setAttribute("data-role", "driver-choice");
      var ground = Array.isArray(doc.links.ground) ? doc.links.ground : doc.links.ground.joints;
      Object.keys(doc.links).forEach(function (ln) {
        if (ln === "ground") return;
        var js = Array.isArray(doc.links[ln]) ? doc.links[ln] : doc.links[ln].joints;
        var pivot = js.filter(function (j) { return ground.indexOf(j) >= 0; })[0];
        if (!pivot || js.length < 2) return;
        var toward = js.filter(function (j) { return j !== pivot; })[0];
        var o = document.createElement("option");
        o.value = JSON.stringify({link: ln, pivot: pivot, toward: toward});
        o.textContent = ln + " (turning about " + pivot + ")";
        var cur = doc.drivers && doc.drivers[0];
        if (cur && cur.link === ln) o.selected = true;
        sel.appendChild(o);
      });
      sel.addEventListener("change", function () {
        var d = clone(doc), choice = JSON.parse(sel.value);
        var old = d.drivers && d.drivers[0] || {};
        d.drivers = [Object.assign({angles: old.angles || {start: 0, stop: 360, step: 1}}, choice)];
        edit(d);
      });
      var label = document.createElement("label");
      label.textContent = "Driven link: ";
      label.appendChild(sel);
      drv.appendChild(label);
    }
  }
  function row(table, label, value, kind, set) {
    var tr = document.createElement("tr"), a = document.createElement("td"), b = document.createElement("td");
    a.textContent = label;
    var inp = document.createElement("input");
    inp.type = "number"; inp.step = "any"; inp.value = String(lk.pyRepr(value));
    inp.setAttribute("data-number", label);
    inp.addEventListener("change", function () {
      var v = parseFloat(inp.value);
      if (!isFinite(v) || (kind === "length" && v <= 0) || v < 0) { setError(label + ": expected a positive number"); return; }
      set(v);
    });
    b.appendChild(inp); tr.appendChild(a); tr.appendChild(b); table.appendChild(tr);
  }

  /* ------------------------------------------------------------- saving */
  q("[data-action=save]").addEventListener("click", function () {
    setStatus("Saving...");
    post("api/save", {doc: doc, base: baseHash}).then(function (r) {
      if (r.ok) { baseHash = r.base; setStatus("Saved " + cfg.file + " (previous version: " + cfg.file + ".bak)."); }
      else { setStatus(""); setError(r.error || "not saved"); }
    }, function (err) { setStatus(""); setError("Not saved: the editor's server does not answer (" + err + ")."); });
  });

  function ready() {
    lk = window.linkagekit;
    lk.editor = {doc: function () { return doc; }, timing: timing, busy: function () { return inflight || !!pending; }};
    render(cfg.answer);
    lk.show(cfg.pose_index);
    buttons();
  }
  if (window.linkagekit && window.linkagekit.load) ready();
  else document.addEventListener("linkagekit:ready", ready);
})();
