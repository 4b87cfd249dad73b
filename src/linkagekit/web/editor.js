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
  /* the document as last saved (or opened): the status says when the page shows something else */
  var savedJSON = JSON.stringify(doc), savedNote = "", saving = false;
  function restStatus() {
    if (draft) return draftStatus();
    if (JSON.stringify(doc) !== savedJSON) return "Unsaved changes (Save writes them to " + cfg.file + ").";
    return savedNote;
  }
  function refreshStatus() { if (mode === null && !saving) setStatus(restStatus()); }
  function setError(text) {
    if (!lk) return;
    lk.holdMessage = !!text;
    if (message) message.textContent = text || "";
    if (!text) lk.show(lk.current());
  }
  function clone(x) { return JSON.parse(JSON.stringify(x)); }
  function centroid(pts) {
    var x = 0, y = 0;
    pts.forEach(function (p) { x += p[0]; y += p[1]; });
    return [x / pts.length, y / pts.length];
  }

  function post(path, body) {
    return fetch(base + path, {method: "POST", headers: {"Content-Type": "application/json"}, body: JSON.stringify(body)})
      .then(function (r) { return r.json().then(function (j) { j.httpStatus = r.status; return j; }); });
  }

  /* ------------------------------------------------------------- solving, newest request only */
  /* edits (full solves) are queued and answered in order, none dropped; of the coarse
   * requests of a drag only the newest waits (a newer move replaces it) */
  var inflight = false, pending = null, finals = [], view = null, generation = 0, outstanding = null;
  function solve(body, done) {
    var job = {body: body, done: done, t0: body.t0};
    if (body.coarse) pending = job; else finals.push(job);
    if (!inflight) pump();
    return job;
  }
  function pump() {
    var job = finals.length ? finals.shift() : pending;
    if (!job) return;
    if (job === pending) pending = null;
    inflight = true;
    var gen = generation;
    post("api/solve", job.body).then(function (r) {
      inflight = false;
      // a coarse answer overtaken by a newer edit is dropped; a full one (an edit) never is
      if (gen === generation || !job.body.coarse) apply(r, job);
      if (outstanding === job) outstanding = null;
      if (pending || finals.length) pump();
      else afterIdle();
    }, function (err) {
      inflight = false;
      if (outstanding === job) outstanding = null;
      setError("The editor's server does not answer (" + err + "); nothing was changed.");
      if (pending || finals.length) pump();
      else afterIdle();
    });
  }
  function apply(r, job) {
    if (!r.ok) { setError(r.error || "could not solve"); if (job.done) job.done(false); return; }
    doc = r.doc;
    if (!(drag && !job.body.coarse)) {   // a drag under way draws its own coarse answers
      lk.load(r.scene, job.body.coarse ? view : keptView(r.scene));
      lk.show(r.pose_index);
    }
    setError("");
    if (!job.body.coarse) { render(r); refreshStatus(); }
    if (job.t0 !== undefined) {
      var t0 = job.t0;
      requestAnimationFrame(function () { timing.push(performance.now() - t0); });
    }
    if (job.done) job.done(true);
  }

  /* the view stays as it is across edits (a released joint stays under the pointer); it is
   * fitted again only when asked (Fit view) or when the mechanism no longer lies in it */
  function keptView(scene) {
    if (!lk.viewer) return null;
    var v = lk.viewer.view(), xs = [], ys = [];
    scene.joints.forEach(function (j) {
      xs.push(lk.column(scene, "joint", j, "x")); ys.push(lk.column(scene, "joint", j, "y"));
    });
    var ex = lk.extent(xs), ey = lk.extent(ys);
    if (!(ex[0] <= ex[1] && ey[0] <= ey[1])) return v;   // nothing assembles: nothing to fit
    var x0 = -v.tx / v.s, x1 = (v.W - v.tx) / v.s, y0 = (v.ty - v.H) / v.s, y1 = v.ty / v.s;
    return ex[0] >= x0 && ex[1] <= x1 && ey[0] >= y0 && ey[1] <= y1 ? v : null;
  }

  /* things to do once no solve is in flight or waiting (a save clicked during a solve) */
  var idle = [];
  function whenIdle(f) { if (inflight || pending || finals.length) idle.push(f); else f(); }
  function afterIdle() { var fs = idle; idle = []; fs.forEach(function (f) { f(); }); }

  /* the modes listed are those at the shown input: asked again when the slider moves */
  var modesTimer = null, modesBusy = false, modesAsked = 0;
  function refreshModes() {
    clearTimeout(modesTimer);
    modesBusy = true;
    var ask = ++modesAsked;
    modesTimer = setTimeout(function () {
      var shownAt = lk.current();
      post("api/solve", {doc: doc, at: atNow(), modes_only: true}).then(function (r) {
        if (r.ok && lk.current() === shownAt) renderModes(r);
        // the newest question's answer ends the wait, whatever the page shows now (a drag shows its pose: the
        // answer was dropped and the page stayed busy for ever; the drag's own solve lists the modes again)
        if (ask === modesAsked) modesBusy = false;
      }, function () { if (ask === modesAsked) modesBusy = false; /* the drawing is unchanged; the list stays */ });
    }, 120);
  }

  /* ------------------------------------------------------------- undo, redo */
  function commit(newDoc) {       // an edit that changed the document: remember the one before
    undoStack.push(lastGood); redoStack = []; lastGood = clone(newDoc); buttons();
  }
  var lastGood = clone(doc);
  function buttons() {
    q("[data-action=undo]").disabled = !undoStack.length && !draft;
    q("[data-action=redo]").disabled = !redoStack.length;
  }
  function restore(d) {
    solve({doc: d}, function (ok) { if (ok) { lastGood = clone(doc); buttons(); } });
  }
  q("[data-action=undo]").addEventListener("click", function () {
    if (draft) { setDraft(null); setError(""); return; }
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
    sc.joints.forEach(function (j) { pose[j] = [lk.column(sc, "joint", j, "x")[i], lk.column(sc, "joint", j, "y")[i]]; });
    return pose;
  }
  var drag = null;
  svg.addEventListener("pointerdown", function (e) {
    var t = e.target;
    if (mode !== null) return;
    if (!t.hasAttribute || !t.hasAttribute("data-joint") || t.getAttribute("data-x") === "") return;
    e.preventDefault();
    lk.stop();
    if (draft) { setDraft(null); setError(""); }
    svg.setPointerCapture(e.pointerId);
    view = lk.viewer.view();
    // a drag pressed before the previous edit is answered builds on that edit's pose
    var start = outstanding ? clone(outstanding.body.pose) : displayedPose();
    // the joints moved by the user since drag.doc: the server keeps every other number of the document
    var joints = outstanding ? outstanding.body.moved.slice() : [];
    if (joints.indexOf(t.getAttribute("data-joint")) < 0) joints.push(t.getAttribute("data-joint"));
    drag = {joint: t.getAttribute("data-joint"), pose: start, doc: clone(doc), moved: false, joints: joints};
    generation++;
  });
  svg.addEventListener("pointermove", function (e) {
    if (!drag) return;
    var t0 = performance.now();
    var p = svgPoint(e);
    drag.pose[drag.joint] = p;
    drag.moved = true;
    solve({doc: drag.doc, pose: drag.pose, moved: drag.joints, coarse: true, t0: t0});
  });
  function release(e) {
    if (!drag) return;
    var d = drag; drag = null;
    try { svg.releasePointerCapture(e.pointerId); } catch (err) { /* already released */ }
    if (!d.moved) return;
    d.pose[d.joint] = svgPoint(e);
    generation++;           // coarse answers still on the way are not drawn over the full one
    pending = null;
    outstanding = solve({doc: d.doc, pose: d.pose, moved: d.joints, at: atNow()}, function (ok) {
      if (ok) commit(doc);
      else { view = null; }
    });
  }
  svg.addEventListener("pointerup", release);
  svg.addEventListener("pointercancel", release);
  function atNow() {
    var out = {}, sc = lk.scene, i = lk.current();
    sc.drivers.forEach(function (d) { out[d] = lk.inputOf(sc, d)[i]; });
    return out;
  }

  /* ------------------------------------------------------------- adding links, the ground */
  /* A mechanism is built up one link at a time, and the steps in between do not solve (a new
   * link hangs free until it is connected or grounded). Such a document is kept as a draft:
   * the solver's message says what is missing, the last good drawing stays, and the draft's
   * new joints and links are marked on top of it (dashed: the user's own clicks, nothing
   * computed) so they can be clicked to go on. The draft is committed the moment it solves;
   * Undo, a drag or any other edit drops it. */
  var mode = null, building = [], draft = null;
  var finish = q("[data-action=finish-link]");
  function newName(prefix, taken) {
    for (var k = 1; ; k++) if (!Object.prototype.hasOwnProperty.call(taken, prefix + k)) return prefix + k;
  }
  function groundOf(d) { return Array.isArray(d.links.ground) ? d.links.ground : d.links.ground.joints; }
  function jointsOf(entry) { return Array.isArray(entry) ? entry : entry.joints; }
  function setMode(m) {
    mode = m; building = [];
    svg.classList.toggle("adding", mode !== null);
    finish.hidden = mode !== "link";
    setStatus(mode === "link" ? "Click joints, or empty places for new joints; then Finish link." :
              mode === "ground" ? "Click a joint to fix it to the ground (or to free it)." : restStatus());
    drawDraft();
  }
  function draftStatus() {
    return draft ? "Draft, not solved yet: add links or ground until it solves (Undo drops it)." : "";
  }
  function setDraft(d) {
    draft = d;
    refreshStatus();
    drawDraft(); buttons();
  }
  var SVGNS = "http://www.w3.org/2000/svg";
  function drawDraft() {
    var old = svg.querySelector("g[data-role=draft]");
    if (old) old.parentNode.removeChild(old);
    if (!draft && !building.length) return;
    var g = document.createElementNS(SVGNS, "g"), v = lk.viewer, shown = displayedPose();
    g.setAttribute("data-role", "draft");
    var d = draft || doc, pend = pendingJoints();
    function at(j) { return shown[j] && isFinite(shown[j][0]) ? shown[j] : (pend[j] || d.joints[j]); }
    function mk(tag, attrs) {
      var e = document.createElementNS(SVGNS, tag);
      Object.keys(attrs).forEach(function (k) { e.setAttribute(k, attrs[k]); });
      g.appendChild(e); return e;
    }
    var links = Object.keys(d.links).filter(function (ln) { return ln !== "ground" && !doc.links[ln]; })
      .map(function (ln) { return jointsOf(d.links[ln]); });
    if (building.length) links.push(building.map(function (b) { return b.name; }));
    links.forEach(function (js) {
      for (var k = 1; k < js.length; k++) {
        var a = at(js[k - 1]), b = at(js[k]);
        mk("line", {x1: v.px(a[0]), y1: v.py(a[1]), x2: v.px(b[0]), y2: v.py(b[1]), stroke: "#777",
          "stroke-width": 2, "stroke-dasharray": "5 4", "pointer-events": "none"});
      }
    });
    var fresh = Object.keys(d.joints).filter(function (j) { return !shown[j]; }).concat(Object.keys(pend));
    fresh.forEach(function (j) {
      var p = at(j), grounded = groundOf(d).indexOf(j) >= 0;
      var c = mk("circle", {cx: v.px(p[0]), cy: v.py(p[1]), r: Math.max(5, v.pin * 1.3), fill: grounded ? "#bbb" : "#fff",
        stroke: "#555", "stroke-width": 1.5, "stroke-dasharray": "3 2", "data-draft-joint": j});
      c.style.cursor = "pointer";
      var t = mk("text", {x: v.px(p[0]) + 7, y: v.py(p[1]) - 7, "font-size": 11, fill: "#555", "pointer-events": "none"});
      t.textContent = j + (grounded ? " (ground)" : "");
    });
    svg.appendChild(g);
  }
  var fitButton = document.createElement("button");
  fitButton.type = "button"; fitButton.textContent = "Fit view"; fitButton.setAttribute("data-action", "fit");
  fitButton.title = "fit the drawing to the mechanism (the view is otherwise kept across edits)";
  q("[data-action=ground]").insertAdjacentElement("afterend", fitButton);
  fitButton.addEventListener("click", function () {
    var i = lk.current();
    lk.load(lk.scene, null); lk.show(i); drawDraft();
  });
  q("[data-action=add-link]").addEventListener("click", function () { setMode(mode === "link" ? null : "link"); });
  q("[data-action=ground]").addEventListener("click", function () { setMode(mode === "ground" ? null : "ground"); });
  function clickedJoint(t) {
    if (!t.hasAttribute) return null;
    if (t.hasAttribute("data-draft-joint")) return t.getAttribute("data-draft-joint");
    return t.hasAttribute("data-joint") && t.getAttribute("data-x") !== "" ? t.getAttribute("data-joint") : null;
  }
  // a click's clientX/Y are whole pixels in Chromium; the pointerdown before it has fractions
  var lastDown = null;
  svg.addEventListener("pointerdown", function (e) { lastDown = {clientX: e.clientX, clientY: e.clientY}; }, true);
  svg.addEventListener("click", function (e) {
    if (mode === null) return;
    var joint = clickedJoint(e.target), d;
    if (mode === "ground") {
      if (!joint) return;
      d = clone(draft || doc);
      if (pendingJoints()[joint]) return;
      var list = groundOf(d), k = list.indexOf(joint);
      if (k >= 0) list.splice(k, 1); else list.push(joint);
      setMode(null);
      edit(d, true);
      return;
    }
    if (!joint) {
      var near = lastDown && Math.abs(lastDown.clientX - e.clientX) < 1 && Math.abs(lastDown.clientY - e.clientY) < 1;
      var p = svgPoint(near ? lastDown : e), name = newName("J", Object.assign({}, (draft || doc).joints, pendingJoints()));
      building.push({name: name, at: p});
    } else if (building.every(function (b) { return b.name !== joint; })) {
      building.push({name: joint});
    }
    setStatus("New link: " + building.map(function (b) { return b.name; }).join(" - ") + " (Finish link when done)");
    drawDraft();
  });
  function pendingJoints() { var o = {}; building.forEach(function (b) { if (b.at) o[b.name] = b.at; }); return o; }
  finish.addEventListener("click", function () {
    var d = clone(draft || doc), add = building.slice();
    add.forEach(function (b) { if (b.at) d.joints[b.name] = b.at; });
    setMode(null);
    if (add.length < 2) { setError("A link needs at least two joints."); return; }
    d.links[newName("link", d.links)] = add.map(function (b) { return b.name; });
    edit(d, true);
  });

  /* an edit of the document (numbers, links, ground, driver): solved in full, undoable; a
   * structural edit that does not solve yet is kept as the draft */
  function edit(d, structural) {
    generation++;
    solve({doc: d, at: atNow()}, function (ok) {
      if (ok) { setDraft(null); commit(doc); }
      else if (structural) setDraft(d);
      else renderPanel(panelAnswer);   // a rejected number or driver: the fields show what is in force again
    });
  }

  /* ------------------------------------------------------------- side panels */
  function render(r) {
    var checks = q("[data-role=checks]");
    if (checks && r.checks) checks.textContent = r.checks;
    renderModes(r);
    renderPanel(r);
  }
  /* the numbers and the driver of the document in force (r: its full solve's answer) */
  var panelAnswer = null;
  function renderPanel(r) {
    panelAnswer = r;
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
          // a mass needs its centre of gravity: the centroid of the link's joints in the pose
          // until the file says otherwise (the file format has no default)
          if (!e2.cg) e2.cg = centroid(e2.joints.map(function (j) { return d.joints[j]; }));
          edit(d);
        });
      });
      var g = doc.gravity ? doc.gravity[1] : 0;
      row(table, "gravity y [m/s\u00b2]", g, "signed", function (v) {
        var d = clone(doc);
        if (v === 0) delete d.gravity; else d.gravity = [d.gravity ? d.gravity[0] : 0, v];
        edit(d);
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
  function renderModes(r) {
    var modes = q("[data-role=modes]");
    if (!modes) return;
    modes.textContent = "";
    (r.modes || []).forEach(function (m, k) {
      var b = document.createElement("button");
      b.type = "button";
      b.setAttribute("data-action", "mode");
      b.setAttribute("data-mode", String(k));
      var signs = Object.keys(m.signs).map(function (j) { return j + (m.signs[j] > 0 ? "+" : "-"); }).join(" ");
      var groups = Object.keys(m.groups || {}).map(function (g) {
        var gi = m.groups[g];
        return g + " " + (gi.of > 0 ? (gi.index + 1) + "/" + gi.of : "(continued)");
      }).join(" ");
      b.textContent = (k + 1) + ": " + ([signs, groups].filter(Boolean).join(" ") || "the only mode") +
        (m.reference ? " (this one)" : "");
      b.disabled = m.reference;
      b.addEventListener("click", function () {
        generation++;
        // the mode by its signs, at the input shown when clicked (the list may be a moment old)
        solve({doc: doc, mode: m.signs, mode_groups: m.groups || null, at: atNow()}, function (ok) {
          if (ok) { setDraft(null); commit(doc); }
        });
      });
      modes.appendChild(b);
    });
    if (r.modes_note) { var p = document.createElement("p"); p.textContent = r.modes_note; modes.appendChild(p); }
  }
  function row(table, label, value, kind, set) {
    var tr = document.createElement("tr"), a = document.createElement("td"), b = document.createElement("td");
    a.textContent = label;
    var inp = document.createElement("input");
    // shown to 10 significant digits (a length computed from two joints reads 50, not
    // 50.00000000000001); the document keeps the exact value until this field is edited
    inp.type = "number"; inp.step = "any"; inp.value = String(Number(Number(value).toPrecision(10)));
    inp.title = String(lk.pyRepr(value));
    inp.setAttribute("data-number", label);
    var inForce = inp.value;
    inp.addEventListener("change", function () {
      var v = parseFloat(inp.value);
      if (!isFinite(v) || (kind === "length" && v <= 0) || (kind === "mass" && v < 0)) {
        setError(label + (kind === "signed" ? ": expected a number" : ": expected a positive number") +
          (inp.value === "" ? " (not a number: not taken)" : " (" + inp.value + " not taken)"));
        inp.value = inForce;
        return;
      }
      set(v);
    });
    b.appendChild(inp); tr.appendChild(a); tr.appendChild(b); table.appendChild(tr);
  }

  /* ------------------------------------------------------------- saving */
  q("[data-action=save]").addEventListener("click", function () {
    saving = true;
    setStatus("Saving...");
    whenIdle(save);   // after the solve under way: save what the page then shows
  });
  function save() {
    var sent = doc;
    post("api/save", {doc: sent, base: baseHash}).then(function (r) {
      saving = false;
      if (r.ok) {
        baseHash = r.base; savedJSON = JSON.stringify(sent);
        savedNote = "Saved " + cfg.file + " (previous version: " + cfg.file + ".bak).";
        var source = q("[data-role=source]");
        if (source && typeof r.text === "string") source.textContent = r.text;   // the file as now on disk
      } else setError(r.error || "not saved");
      setStatus(restStatus());   // "Saving..." goes, whatever the page is doing
    }, function (err) {
      saving = false; setStatus(restStatus());
      setError("Not saved: the editor's server does not answer (" + err + ").");
    });
  }

  function ready() {
    lk = window.linkagekit;
    function follow(sl) { sl.addEventListener("input", refreshModes); sl.addEventListener("input", drawDraft); }
    Array.prototype.forEach.call(document.querySelectorAll("input[data-role=input]"), follow);
    // a new driver gets a new range (viewer.js rebuilds them from the scene)
    document.addEventListener("linkagekit:input-added", function (e) { follow(e.detail); });
    // Play moves the input too: the draft follows it, the modes are asked for once it rests (120 ms: where paused)
    document.addEventListener("linkagekit:played", function () { refreshModes(); drawDraft(); });
    lk.editor = {doc: function () { return doc; }, timing: timing,
      busy: function () { return inflight || !!pending || finals.length > 0 || modesBusy; }};
    render(cfg.answer);
    lk.show(cfg.pose_index);
    buttons();
  }
  if (window.linkagekit && window.linkagekit.load) ready();
  else document.addEventListener("linkagekit:ready", ready);
})();
