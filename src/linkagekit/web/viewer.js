/* linkagekit viewer: draws a scene computed by the Python solver as inline SVG.
 *
 * It solves nothing: every position, curve and plotted value comes from the scene JSON
 * embedded in the page (built by linkagekit.viz.scene). It only maps file units to pixels
 * through one similarity transform (uniform scale, y up) and moves elements between
 * samples. Hooks (the report page's, tested by tests/test_report_browser.py): [data-joint] with data-x/data-y (Python repr of the
 * float, empty when not assembled), <input type=range data-role=input data-driver> whose
 * value is the sample index, [data-role=input-value], [data-role=plot] with a
 * [data-role=cursor], [data-action=play], [data-action=csv], [data-role=message]; for a
 * simulated motion (scene.x_axis.time) [data-role=time-value]: the plots run along time and
 * Play steps through the samples at the pace of their times; [data-role=sample-count]: the
 * number of samples of the scene drawn. A ground joint is drawn at every sample.
 */
(function () {
  "use strict";
  var SVGNS = "http://www.w3.org/2000/svg";
  var PALETTE = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf", "#bcbd22"];
  var CURVE = "#e6007e", PATH = "#9a9a9a";

  /* Python's repr of a float: shortest round-trip digits, exponent form below 1e-4 and from 1e16. */
  function pyRepr(x) {
    if (x === null || x === undefined || !isFinite(x)) return "";
    if (x === 0) return Object.is(x, -0) ? "-0.0" : "0.0";
    var parts = x.toExponential().split("e");
    var mant = parts[0], exp = parseInt(parts[1], 10);
    var neg = mant.charAt(0) === "-";
    if (neg) mant = mant.slice(1);
    var digits = mant.replace(".", "");
    var s;
    if (exp < -4 || exp >= 16) {
      s = digits.charAt(0) + (digits.length > 1 ? "." + digits.slice(1) : "") + "e" + (exp < 0 ? "-" : "+") +
        (Math.abs(exp) < 10 ? "0" : "") + Math.abs(exp);
    } else if (exp < 0) {
      s = "0." + "0".repeat(-exp - 1) + digits;
    } else if (digits.length <= exp + 1) {
      s = digits + "0".repeat(exp + 1 - digits.length) + ".0";
    } else {
      s = digits.slice(0, exp + 1) + "." + digits.slice(exp + 1);
    }
    return (neg ? "-" : "") + s;
  }

  function fmt(x, unit) {
    if (x === null || x === undefined || !isFinite(x)) return "—";
    var a = Math.abs(x);
    var s = (a !== 0 && (a < 1e-3 || a >= 1e6)) ? x.toExponential(4) : String(parseFloat(x.toPrecision(6)));
    return unit ? s + " " + unit : s;
  }

  function el(name, attrs, parent) {
    var e = document.createElementNS(SVGNS, name);
    for (var k in attrs) if (Object.prototype.hasOwnProperty.call(attrs, k)) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  }

  function finite(v) { return v !== null && v !== undefined && isFinite(v); }

  /* The values of one quantity of the scene's catalogue (its `quantities`: owner, component,
   * unit, group...), found by what it is, never by parsing a column name. */
  function column(scene, owner, ownerName, component) {
    var qs = scene.quantities;
    for (var k = 0; k < qs.length; k++) {
      var q = qs[k];
      if (q.owner === owner && q.owner_name === ownerName && q.component === component) return scene.columns[q.name];
    }
    throw new Error("linkagekit: the scene has no " + component + " of " + owner + " " + ownerName);
  }
  function inputOf(scene, driver) { return column(scene, "driver", driver, "input"); }
  /* what the plots run along: {values, name, unit, time} (a simulation's time, or the first moving driver's input) */
  function xAxisOf(scene) {
    var ax = scene.x_axis;
    if (ax && ax.column && scene.columns[ax.column]) return {values: scene.columns[ax.column], name: ax.name, unit: ax.unit, time: ax.time};
    var d = scene.x_driver || scene.drivers[0];
    return {values: inputOf(scene, d), name: d, unit: scene.input_units[d], time: false};
  }
  function assembledOf(scene) { return column(scene, "mechanism", "", "assembled"); }

  /* [min, max] of the finite values of several arrays (a loop: spreading a long array into
   * Math.min overflows the call stack) */
  function extent(arrays) {
    var lo = Infinity, hi = -Infinity;
    for (var a = 0; a < arrays.length; a++) {
      var v = arrays[a];
      for (var i = 0; i < v.length; i++) {
        if (finite(v[i])) { if (v[i] < lo) lo = v[i]; if (v[i] > hi) hi = v[i]; }
      }
    }
    return [lo, hi];
  }

  /* ------------------------------------------------------------------ the mechanism */
  /* view: {W, H, s, tx, ty} to keep the transform of an earlier drawing (the editor keeps it
   * while a joint is dragged, so the drawing does not slide under the pointer) */
  function Viewer(scene, svg, view) {
    this.scene = scene;
    this.svg = svg;
    var b = scene.bounds, W = 640;
    if (view) {
      this.W = view.W; this.H = view.H; this.s = view.s; this.tx = view.tx; this.ty = view.ty;
    } else {
      var s = W / (b[2] - b[0]);
      this.W = W; this.H = Math.max(120, Math.round((b[3] - b[1]) * s)); this.s = s;
      this.tx = -b[0] * s; this.ty = b[3] * s;   // X = tx + s x ; Y = ty - s y
    }
    W = this.W;
    var H = this.H;
    svg.setAttribute("viewBox", "0 0 " + W + " " + H);
    svg.setAttribute("data-scale", String(this.s));
    this.X = {}; this.Y = {};
    for (var i = 0; i < scene.joints.length; i++) {
      var j = scene.joints[i];
      this.X[j] = column(scene, "joint", j, "x"); this.Y[j] = column(scene, "joint", j, "y");
    }
    this.size = Math.max(b[2] - b[0], b[3] - b[1]);
    this.pin = 0.012 * this.size * this.s;  // pixels
    this.build();
  }
  Viewer.prototype.view = function () { return {W: this.W, H: this.H, s: this.s, tx: this.tx, ty: this.ty}; };
  /* file units of an SVG point (the inverse of the transform) */
  Viewer.prototype.toFile = function (X, Y) { return [(X - this.tx) / this.s, (this.ty - Y) / this.s]; };
  Viewer.prototype.px = function (x) { return this.tx + this.s * x; };
  Viewer.prototype.py = function (y) { return this.ty - this.s * y; };

  /* an SVG path through the samples, lifted where a sample is missing and after each of
   * the scene's breaks (a gap between two samples where the mechanism does not assemble) */
  Viewer.prototype.pathOf = function (xs, ys, cuts) {
    var d = "", pen = false, breaks = {};
    (cuts || this.scene.breaks).forEach(function (b) { breaks[b] = true; });
    for (var i = 0; i < xs.length; i++) {
      if (finite(xs[i]) && finite(ys[i])) {
        d += (pen ? "L" : "M") + this.px(xs[i]).toFixed(2) + " " + this.py(ys[i]).toFixed(2);
        pen = !breaks[i];
      } else pen = false;
    }
    return d;
  };

  Viewer.prototype.build = function () {
    var sc = this.scene, svg = this.svg, self = this;
    var gStatic = el("g", {"class": "static"}, svg);
    /* a joint's path: on to the dead points where the scene has them (sc.paths), else through the samples */
    function drawn(j) {
      return sc.paths ? self.pathOf(sc.paths[j].x, sc.paths[j].y, sc.path_breaks) : self.pathOf(self.X[j], self.Y[j]);
    }
    sc.other_paths.forEach(function (j) {
      el("path", {d: drawn(j), fill: "none", stroke: PATH, "stroke-width": 1, "stroke-dasharray": "4 3",
        "data-path": j}, gStatic);
    });
    sc.coupler_curves.forEach(function (j) {
      el("path", {d: drawn(j), fill: "none", stroke: CURVE, "stroke-width": 1.8, "data-curve": j}, gStatic);
    });
    var h = 3.2 * this.pin;
    sc.sliders.forEach(function (sl) {
      if (sl.on !== "ground") return;
      var o = sl.origin[0], d = sl.direction[0];
      var a = [o[0] + sl.span[0] * d[0], o[1] + sl.span[0] * d[1]], b = [o[0] + sl.span[1] * d[0], o[1] + sl.span[1] * d[1]];
      el("line", {x1: self.px(a[0]), y1: self.py(a[1]), x2: self.px(b[0]), y2: self.py(b[1]), stroke: "#000",
        "stroke-width": 1.5}, gStatic);
      var n = [d[1], -d[0]], len = Math.hypot(b[0] - a[0], b[1] - a[1]) * self.s, k = Math.floor(len / 8);
      for (var i = 0; i <= k; i++) {
        var t = i / Math.max(k, 1), x = a[0] + t * (b[0] - a[0]), y = a[1] + t * (b[1] - a[1]);
        var X = self.px(x), Y = self.py(y);
        el("line", {x1: X, y1: Y, x2: X + 0.6 * h * n[0] - 0.4 * h * d[0], y2: Y - 0.6 * h * n[1] + 0.4 * h * d[1],
          stroke: "#000", "stroke-width": 0.8}, gStatic);
      }
    });
    sc.ground_joints.forEach(function (j) {
      var g = sc.ground_xy[j];  // fixed: drawn even when no sample assembles
      var X = self.px(g[0]), Y = self.py(g[1]);
      el("polygon", {points: [X, Y, X - 0.8 * h, Y + h, X + 0.8 * h, Y + h].join(" "), fill: "#ddd", stroke: "#000",
        "stroke-width": 1}, gStatic);
      for (var i = 0; i < 6; i++) {
        var hx = X - 1.2 * h + i * 0.48 * h;
        el("line", {x1: hx, y1: Y + h + 0.45 * h, x2: hx + 0.45 * h, y2: Y + h, stroke: "#000", "stroke-width": 0.8}, gStatic);
      }
      el("line", {x1: X - 1.3 * h, y1: Y + h, x2: X + 1.3 * h, y2: Y + h, stroke: "#000", "stroke-width": 1}, gStatic);
    });
    var gMove = el("g", {"class": "moving"}, svg);
    this.links = [];
    var k = 0;
    sc.links.forEach(function (ln) {
      if (ln.kind === "ground") return;
      if (ln.kind === "cylinder") { /* a cylinder driver: its rod, then its barrel over the first part */
        self.links.push({link: ln, e: el("line", {stroke: "#9a9a9a", "stroke-width": 3, "data-cylinder": ln.name}, gMove)});
        self.links.push({link: ln, barrel: true, e: el("line", {stroke: "#505050", "stroke-width": 8, "data-cylinder": ln.name}, gMove)});
        return;
      }
      var color = PALETTE[k++ % PALETTE.length], e;
      if (ln.kind === "plate") e = el("polygon", {fill: color, "fill-opacity": 0.35, stroke: color, "stroke-width": 3,
        "stroke-linejoin": "round", "data-link": ln.name}, gMove);
      else if (ln.kind === "block") e = el("polygon", {fill: color, "fill-opacity": 0.8, stroke: "#000",
        "stroke-width": 1, "data-link": ln.name}, gMove);
      else e = el("line", {stroke: color, "stroke-width": 6, "stroke-linecap": "round", "data-link": ln.name}, gMove);
      self.links.push({link: ln, e: e, slider: sc.sliders.filter(function (s) { return s.block === ln.name; })[0]});
    });
    this.guides = [];
    sc.sliders.forEach(function (sl) {
      if (sl.on === "ground") return;
      self.guides.push({sl: sl, e: el("line", {stroke: "#444", "stroke-width": 1.5}, gMove)});
    });
    this.joints = {};
    sc.joints.forEach(function (j) {
      var c = el("circle", {r: 4.5, fill: "#fff", stroke: "#000", "stroke-width": 1.5, "data-joint": j}, gMove);
      var t = el("text", {"font-size": 11, "class": "label"}, gMove);
      t.textContent = j;
      self.joints[j] = {c: c, t: t};
    });
  };

  Viewer.prototype.show = function (i) {
    var self = this, sc = this.scene;
    var ok = assembledOf(sc)[i];
    sc.joints.forEach(function (j) {
      var x = self.X[j][i], y = self.Y[j][i], je = self.joints[j];
      var good = finite(x) && finite(y);
      // a ground joint never moves: drawn where the file puts it also where nothing assembles (its
      // data-x/data-y stay empty there, as the hooks say)
      var at = good ? [x, y] : sc.ground_xy[j];
      je.c.setAttribute("data-x", good ? pyRepr(x) : "");
      je.c.setAttribute("data-y", good ? pyRepr(y) : "");
      je.c.style.visibility = at ? "visible" : "hidden";
      je.t.style.visibility = at ? "visible" : "hidden";
      if (at) {
        je.c.setAttribute("cx", self.px(at[0])); je.c.setAttribute("cy", self.py(at[1]));
        je.t.setAttribute("x", self.px(at[0]) + 6); je.t.setAttribute("y", self.py(at[1]) - 6);
      }
    });
    this.links.forEach(function (L) {
      var ln = L.link, e = L.e;
      // a link with a joint not known here (null, which arithmetic reads as 0: a link drawn to the origin) is left out
      var drawn = ok && (ln.kind === "block" ? [L.slider.through] : ln.joints).every(function (j) {
        return finite(self.X[j][i]) && finite(self.Y[j][i]);
      });
      e.style.visibility = drawn ? "visible" : "hidden";
      if (!drawn) return;
      if (ln.kind === "plate") {
        e.setAttribute("points", ln.joints.map(function (j) { return self.px(self.X[j][i]) + "," + self.py(self.Y[j][i]); }).join(" "));
      } else if (ln.kind === "block") {
        var sl = L.slider, j = sl.through, d = sl.direction[i];
        var cx = self.px(self.X[j][i]), cy = self.py(self.Y[j][i]);
        var dx = d[0], dy = -d[1], nx = -dy, ny = dx, w = 2.6 * self.pin, h = 1.6 * self.pin;
        e.setAttribute("points", [cx - w * dx - h * nx, cy - w * dy - h * ny, cx + w * dx - h * nx, cy + w * dy - h * ny,
          cx + w * dx + h * nx, cy + w * dy + h * ny, cx - w * dx + h * nx, cy - w * dy + h * ny].join(" "));
      } else if (ln.joints.length >= 2) {
        var a = ln.joints[0], b = ln.joints[1], ax = self.X[a][i], ay = self.Y[a][i];
        // a cylinder's barrel is rigid (its length in the scene), cut at the rod's end
        var f = L.barrel ? Math.min(ln.barrel / Math.hypot(self.X[b][i] - ax, self.Y[b][i] - ay), 1) : 1;
        e.setAttribute("x1", self.px(ax)); e.setAttribute("y1", self.py(ay));
        e.setAttribute("x2", self.px(ax + f * (self.X[b][i] - ax))); e.setAttribute("y2", self.py(ay + f * (self.Y[b][i] - ay)));
      }
    });
    this.guides.forEach(function (G) {
      var sl = G.sl, o = sl.origin[i], d = sl.direction[i];
      G.e.style.visibility = ok && o[0] !== null ? "visible" : "hidden";
      if (!ok || o[0] === null) return;
      G.e.setAttribute("x1", self.px(o[0] + sl.span[0] * d[0])); G.e.setAttribute("y1", self.py(o[1] + sl.span[0] * d[1]));
      G.e.setAttribute("x2", self.px(o[0] + sl.span[1] * d[0])); G.e.setAttribute("y2", self.py(o[1] + sl.span[1] * d[1]));
    });
  };

  /* ------------------------------------------------------------------ plots */
  function niceTicks(lo, hi, n) {
    // a range too narrow for its magnitude (a constant up to round-off) is widened first:
    // a tick step below the spacing of the floats would never advance
    var mid = isFinite(lo) && isFinite(hi) ? (lo + hi) / 2 : 0;
    var least = 1e-9 * Math.max(Math.abs(lo), Math.abs(hi), 1e-300);
    if (!(hi - lo > least)) { var w = Math.max(Math.abs(mid) * 0.05, 1e-12); lo = mid - w; hi = mid + w; }
    var step = Math.pow(10, Math.floor(Math.log10((hi - lo) / n)));
    var err = (hi - lo) / n / step;
    if (err >= 7.5) step *= 10; else if (err >= 3.5) step *= 5; else if (err >= 1.5) step *= 2;
    var t = [], first = Math.ceil(lo / step);
    for (var k = 0; k <= 4 * n; k++) {
      var v = (first + k) * step;
      if (v > hi + 1e-9 * step) break;
      t.push(Math.abs(v) < 1e-12 * step ? 0 : v);
    }
    return {lo: lo, hi: hi, ticks: t};
  }

  function Plot(scene, spec, svg) {
    // drawn in the width it is shown in (640 units at most, 320 at least): on a phone a fixed 640 was shrunk to
    // half, its text to 6-8 px
    var shown = svg.parentNode ? svg.parentNode.clientWidth : 0;
    var W = Math.round(Math.min(640, Math.max(320, shown || 640))), L = 62, R = 12, B = 34, PH = 154;
    // the legend: entries flow left to right under the title, wrapping to more rows
    var rows = [[]], used = 0, avail = W - L - R;
    spec.series.forEach(function (k, n) {
      var w = 22 + 6.2 * k.length;
      if (used + w > avail && rows[rows.length - 1].length) { rows.push([]); used = 0; }
      rows[rows.length - 1].push({k: k, n: n, x: L + used});
      used += w;
    });
    var T = 24 + 14 * rows.length, H = T + PH + B;
    svg.setAttribute("viewBox", "0 0 " + W + " " + H);
    var axis = xAxisOf(scene), xs = axis.values;
    var xe = extent([xs]), x0 = xe[0], x1 = xe[1];
    if (!(x1 > x0)) { x1 = x0 + 1; }
    var ye = extent(spec.series.map(function (k) { return scene.columns[k]; }));
    var ylo = isFinite(ye[0]) ? ye[0] : -1, yhi = isFinite(ye[1]) ? ye[1] : 1;
    var pad = 0.05 * (yhi - ylo || Math.abs(yhi) || 1);
    var yt = niceTicks(ylo - pad, yhi + pad, 5), xt = niceTicks(x0, x1, 8);
    function X(x) { return L + (x - x0) / (x1 - x0) * (W - L - R); }
    function Y(y) { return T + (yt.hi - y) / (yt.hi - yt.lo) * (H - T - B); }
    this.X = X; this.xs = xs; this.scene = scene; this.spec = spec; this.Y = Y;
    var title = el("text", {x: L, y: 15, "font-size": 12, "font-weight": "bold"}, svg);
    title.textContent = spec.title + (spec.unit ? " [" + spec.unit + "]" : "");
    scene.shaded.forEach(function (g) {
      el("rect", {x: Math.min(X(g[0]), X(g[1])), y: T, width: Math.abs(X(g[1]) - X(g[0])), height: H - T - B,
        fill: "#ececec", "data-role": "gap"}, svg);
    });
    yt.ticks.forEach(function (v) {
      if (v < yt.lo || v > yt.hi) return;
      el("line", {x1: L, x2: W - R, y1: Y(v), y2: Y(v), stroke: "#ddd", "stroke-width": 0.7}, svg);
      var t = el("text", {x: L - 5, y: Y(v) + 4, "font-size": 10, "text-anchor": "end"}, svg);
      t.textContent = fmt(v);
    });
    xt.ticks.forEach(function (v) {
      if (v < x0 - 1e-9 || v > x1 + 1e-9) return;
      el("line", {x1: X(v), x2: X(v), y1: T, y2: H - B, stroke: "#eee", "stroke-width": 0.7}, svg);
      var t = el("text", {x: X(v), y: H - B + 14, "font-size": 10, "text-anchor": "middle"}, svg);
      t.textContent = fmt(v);
    });
    var xl = el("text", {x: (L + W - R) / 2, y: H - 4, "font-size": 11, "text-anchor": "middle"}, svg);
    xl.textContent = axis.name + " [" + axis.unit + "]";
    el("rect", {x: L, y: T, width: W - L - R, height: H - T - B, fill: "none", stroke: "#888", "stroke-width": 0.8}, svg);
    rows.forEach(function (row, r) {
      row.forEach(function (it) {
        var lg = el("text", {x: it.x, y: 30 + 14 * r, "font-size": 10, fill: PALETTE[it.n % PALETTE.length],
          "data-legend": it.k}, svg);
        lg.textContent = "\u25AC " + it.k;
      });
    });
    var breaks = {};
    scene.breaks.forEach(function (b) { breaks[b] = true; });
    this.marks = [];
    var self = this;
    spec.series.forEach(function (k, n) {
      var v = scene.columns[k], d = "", pen = false, color = PALETTE[n % PALETTE.length], period = spec.period;
      for (var i = 0; i < xs.length; i++) {
        if (finite(v[i])) {
          // an angle that wraps (+180 to -180) is not joined across the jump
          if (pen && period && Math.abs(v[i] - v[i - 1]) > period / 2) pen = false;
          d += (pen ? "L" : "M") + X(xs[i]).toFixed(2) + " " + Y(v[i]).toFixed(2);
          pen = !breaks[i];
        } else pen = false;
      }
      el("path", {d: d, fill: "none", stroke: color, "stroke-width": 1.4, "data-series": k}, svg);
      self.marks.push({k: k, e: el("circle", {r: 3, fill: color, "data-series": k}, svg)});
    });
    this.cursor = el("line", {y1: T, y2: H - B, stroke: "#000", "stroke-width": 1, "stroke-dasharray": "3 2",
      "data-role": "cursor"}, svg);
  }
  Plot.prototype.show = function (i) {
    var X = this.X(this.xs[i]), self = this;
    this.cursor.setAttribute("x1", X); this.cursor.setAttribute("x2", X);
    this.cursor.setAttribute("data-index", String(i));
    this.marks.forEach(function (m) {
      var v = self.scene.columns[m.k][i];
      m.e.style.visibility = finite(v) ? "visible" : "hidden";
      if (finite(v)) { m.e.setAttribute("cx", X); m.e.setAttribute("cy", self.Y(v)); }
    });
  };

  /* ------------------------------------------------------------------ CSV */
  /* a header cell quoted as Python's csv module does (a name may hold a comma or a quote) */
  function csvCell(s) { return /[",\r\n]/.test(s) ? '"' + s.replace(/"/g, '""') + '"' : s; }
  /* the table of `analyze --format csv`: the catalogue's table quantities, in its order */
  function csvText(scene) {
    var names = scene.quantities.filter(function (q) { return q.table; }).map(function (q) { return q.name; });
    var n = scene.n, lines = [names.map(csvCell).join(",")];
    for (var i = 0; i < n; i++) {
      lines.push(names.map(function (k) {
        var v = scene.columns[k][i];
        if (v === true) return "true";  // as analyze --format csv writes them
        if (v === false) return "false";
        return finite(v) ? pyRepr(v) : "";
      }).join(","));
    }
    return lines.join("\n") + "\n";
  }

  /* ------------------------------------------------------------------ the page */
  function gapText(scene) {
    var axis = xAxisOf(scene), x = axis.values;
    if (scene.shaded_exact) {
      if (!scene.shaded.length) return "";
      return "Does not assemble for " + axis.name + " in " + scene.shaded.map(function (g) {
        return "(" + fmt(g[0]) + ", " + fmt(g[1]) + ")";
      }).join(", ") + " " + axis.unit + " (shaded).";
    }
    if (!scene.gaps.length) return "";
    return "Does not assemble at the samples " + axis.name + " in " + scene.gaps.map(function (g) {
      return g[0] === g[1] ? fmt(x[g[0]]) : "[" + fmt(x[g[0]]) + ", " + fmt(x[g[1]]) + "]";
    }).join(", ") + " " + axis.unit + " (the gaps in the curves).";
  }

  function start() {
    var node = document.getElementById("lk-scene");
    if (!node) return;
    var svgMech = document.querySelector("svg[data-role=mechanism]");
    var box = document.getElementById("lk-plots");
    var sliders = Array.prototype.slice.call(document.querySelectorAll("input[data-role=input]"));
    var values = Array.prototype.slice.call(document.querySelectorAll("[data-role=input-value]"));
    var controls = document.querySelector(".controls");
    var message = document.querySelector("[data-role=message]");
    var gaps = document.querySelector("[data-role=gaps]");
    var timeValue = document.querySelector("[data-role=time-value]");
    var count = document.querySelector("[data-role=sample-count]");
    var scene, viewer, plots, current = 0;

    /* draw a scene: everything is rebuilt from it (the editor calls this with each new solve) */
    function load(newScene, view) {
      scene = newScene;
      while (svgMech.firstChild) svgMech.removeChild(svgMech.firstChild);
      viewer = new Viewer(scene, svgMech, view);
      drawPlots();
      var named = sliders.map(function (s) { return s.getAttribute("data-driver"); });
      if (controls && named.join("\n") !== scene.drivers.join("\n")) rebuildControls();
      sliders.forEach(function (s) { s.max = String(scene.n - 1); });
      if (count) count.textContent = String(scene.n);   // an edit's sweep may hold one more sample (its pose's input)
      if (gaps) gaps.textContent = gapText(scene);
      api.scene = scene;
      api.viewer = viewer;
    }
    /* the plots, drawn in the width they are shown in (again when it changes: a phone turned, a window resized) */
    var plotWidth = 0;
    function drawPlots() {
      while (box.firstChild) box.removeChild(box.firstChild);
      plots = [];
      scene.plots.forEach(function (spec) {
        var fig = document.createElement("figure");
        var svg = el("svg", {"data-role": "plot", "data-title": spec.title, width: "100%"});
        fig.appendChild(svg);
        box.appendChild(fig);
        plots.push(new Plot(scene, spec, svg));
      });
      plotWidth = box.clientWidth;
    }
    var resizing = null;
    window.addEventListener("resize", function () {
      clearTimeout(resizing);
      resizing = setTimeout(function () {
        if (scene && Math.abs(box.clientWidth - plotWidth) > 0.05 * plotWidth) { drawPlots(); show(current); }
      }, 150);
    });
    function show(i) {
      i = Math.max(0, Math.min(scene.n - 1, i | 0));
      current = i;
      sliders.forEach(function (s) { if (String(s.value) !== String(i)) s.value = String(i); });
      viewer.show(i);
      plots.forEach(function (p) { p.show(i); });
      values.forEach(function (v) {
        var d = v.getAttribute("data-driver"), x = inputOf(scene, d)[i];
        v.setAttribute("data-value", pyRepr(x));
        v.textContent = d + " = " + fmt(x, scene.input_units[d]);
      });
      if (timeValue) {
        var axis = xAxisOf(scene), t = axis.time ? axis.values[i] : null;
        timeValue.setAttribute("data-value", pyRepr(t));
        timeValue.textContent = axis.time ? "t = " + fmt(t, axis.unit) : "";
      }
      var ok = assembledOf(scene)[i];
      if (message && !api.holdMessage) {
        message.textContent = ok ? "" : "Does not assemble at " + scene.drivers.map(function (d) {
          return d + " = " + fmt(inputOf(scene, d)[i], scene.input_units[d]);
        }).join(", ") + ".";
      }
    }
    /* one range per driver (the editor may change the drivers: the ranges follow the scene) */
    function listen(s) { s.addEventListener("input", function () { stop(); show(parseInt(s.value, 10)); }); }
    function rebuildControls() {
      while (controls.firstChild) controls.removeChild(controls.firstChild);
      sliders = []; values = [];
      scene.drivers.forEach(function (d) {
        var label = document.createElement("label"), s = document.createElement("input");
        var out = document.createElement("output");
        label.htmlFor = "lk-in-" + d; label.textContent = d;
        s.type = "range"; s.id = "lk-in-" + d; s.min = "0"; s.step = "1"; s.value = "0";
        s.setAttribute("data-role", "input"); s.setAttribute("data-driver", d);
        out.setAttribute("data-role", "input-value"); out.setAttribute("data-driver", d);
        controls.appendChild(label); controls.appendChild(s); controls.appendChild(out);
        sliders.push(s); values.push(out); listen(s);
        document.dispatchEvent(new CustomEvent("linkagekit:input-added", {detail: s}));
      });
    }
    sliders.forEach(listen);
    var timer = null, play = document.querySelector("[data-action=play]");
    /* ms between samples: a simulated motion plays at the pace of its times (within 16 ms to 1 s a
     * sample), a sweep in about six seconds */
    function playStep() {
      var axis = xAxisOf(scene), x = axis.values, n = scene.n;
      if (!axis.time || n < 2 || !finite(x[0]) || !finite(x[n - 1])) return Math.max(16, Math.round(6000 / n));
      return Math.min(1000, Math.max(16, Math.round(1000 * (x[n - 1] - x[0]) / (n - 1))));
    }
    function stop() { if (timer !== null) { clearInterval(timer); timer = null; if (play) play.textContent = "Play"; } }
    if (play) play.addEventListener("click", function () {
      if (timer !== null) { stop(); return; }
      play.textContent = "Pause";
      timer = setInterval(function () {
        show((current + 1) % scene.n);
        document.dispatchEvent(new CustomEvent("linkagekit:played", {detail: current}));  // the editor's modes follow
      }, playStep());
    });
    var csv = document.querySelector("[data-action=csv]");
    if (csv) csv.addEventListener("click", function () {
      var blob = new Blob([csvText(scene)], {type: "text/csv"});
      var a = document.createElement("a");
      a.href = URL.createObjectURL(blob);
      a.download = (document.body.getAttribute("data-name") || "linkage") + ".csv";
      document.body.appendChild(a); a.click(); a.remove();
      setTimeout(function () { URL.revokeObjectURL(a.href); }, 1000);
    });
    var api = window.linkagekit = {show: show, load: load, stop: stop, pyRepr: pyRepr, fmt: fmt, el: el,
      current: function () { return current; }, niceTicks: niceTicks, extent: extent, holdMessage: false,
      column: column, inputOf: inputOf, xAxisOf: xAxisOf, playStep: function () { return playStep(); }};
    load(JSON.parse(node.textContent));
    var first = assembledOf(scene).indexOf(true);
    show(parseInt(sliders.length ? sliders[0].value : "0", 10) || (first > 0 ? first : 0));
    document.dispatchEvent(new CustomEvent("linkagekit:ready"));
  }

  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
  else start();
})();
