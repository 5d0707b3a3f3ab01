// divertsim studio: the scenario editor (made from the scenario's JSON Schema), the live run
// (drawn by the report's viewer, window.divertsimRender), the capacity map and the
// reliability study (server-sent progress). Everything is served by `divertsim studio`;
// nothing comes from the network.
(function () {
  "use strict";
  var errors = [];
  window.addEventListener("error", function (e) { errors.push(String(e.message)); });

  var info = null;          // GET /api/scenario: name, schema, resolved values
  var base = {};            // dotted key -> the override text of its value at start
  var sets = new Map();     // dotted key -> override text (changed keys only)
  var fields = new Map();   // dotted key -> field {el, set(text), kind}
  var seq = 0, inflight = false, pending = false, drawn = 0;
  var firstInput = null;    // time of the first change not drawn yet
  var latencies = [];       // change -> redrawn path [ms]
  var lastRun = null;       // the last drawn run's response

  function $(id) { return document.getElementById(id); }
  function status(text, bad) { var s = $("status"); s.textContent = text; s.className = "status" + (bad ? " bad" : ""); }

  // ---- The scenario schema -> the editor ----------------------------------------------
  function resolve(p) {
    if (!p) return {};
    if (p.$ref) {
      var name = p.$ref.split("/").pop();
      var def = info.schema.$defs[name] || {};
      var merged = {}; Object.keys(def).forEach(function (k) { merged[k] = def[k]; });
      Object.keys(p).forEach(function (k) { if (k !== "$ref") merged[k] = p[k]; });
      return resolve(merged);
    }
    var alt = p.anyOf || (p.oneOf && !choices(p) ? p.oneOf : null);
    if (alt) {
      var branch = alt.filter(function (b) { return b.type !== "null"; })[0];
      if (branch) {
        var r = resolve(branch), out = {};
        Object.keys(r).forEach(function (k) { out[k] = r[k]; });
        if (p.description) out.description = p.description;
        out.nullable = true;
        return out;
      }
    }
    return p;
  }
  function choices(p) {
    if (p.enum) return p.enum.filter(function (v) { return v !== null; });
    var list = p.oneOf || p.anyOf;
    if (!list) return null;
    var out = [];
    for (var i = 0; i < list.length; i++) {
      var b = list[i];
      if (b.const !== undefined) out.push(b.const);
      else if (b.enum) out = out.concat(b.enum);
      else if (b.type === "null") continue;
      else return null;
    }
    return out.length ? out : null;
  }
  function types(p) { return [].concat(p.type || []); }
  function kindOf(p) {
    var t = types(p);
    if (choices(p)) return "enum";
    if (p.properties) return "object";
    if (t.indexOf("boolean") >= 0) return "bool";
    if (t.indexOf("number") >= 0 || t.indexOf("integer") >= 0) return "number";
    return "text";
  }
  function unitOf(desc) { var m = /\[([^\]]+)\]/.exec(desc || ""); return m ? m[1] : ""; }
  function allowedOf(desc) { var m = /Allowed: ([^\n]*)/.exec(desc || ""); return m ? m[1] : ""; }
  function get(obj, path) { return path.reduce(function (o, k) { return o == null ? undefined : o[k]; }, obj); }
  // The override text of a JSON value (TOML's grammar for numbers, booleans, strings, arrays).
  function textOf(v) {
    if (v === null || v === undefined) return "";
    if (typeof v === "string") return JSON.stringify(v);
    return JSON.stringify(v);
  }

  var SHOWN = ["machine", "parcel", "materials", "limits", "run"];
  function buildEditor() {
    var root = $("fields"); root.innerHTML = "";
    var props = info.schema.properties;
    var order = SHOWN.concat(Object.keys(props).filter(function (k) { return SHOWN.indexOf(k) < 0; }));
    order.forEach(function (sec) {
      if (!props[sec] || info.path_keys.indexOf(sec) >= 0) return;
      var p = resolve(props[sec]);
      if (!p.properties) return;
      var d = section(sec, p, [sec], 0);
      if (SHOWN.indexOf(sec) >= 0 && sec !== "run") d.open = true;
      root.appendChild(d);
    });
  }
  function section(name, p, path, depth) {
    var d = document.createElement("details");
    var s = document.createElement("summary"); s.textContent = name; s.title = p.description || ""; d.appendChild(s);
    Object.keys(p.properties).forEach(function (k) {
      var key = path.concat([k]).join(".");
      if (info.path_keys.indexOf(key) >= 0) return;
      var q = resolve(p.properties[k]);
      var kind = kindOf(q);
      if (kind === "object" && depth < 2) { d.appendChild(section(k, q, path.concat([k]), depth + 1)); return; }
      d.appendChild(field(key, q, kind === "object" ? "text" : kind, get(info.values, path.concat([k]))));
    });
    return d;
  }
  function field(key, p, kind, value) {
    var el = document.createElement("div"); el.className = "field"; el.dataset.key = key;
    var head = document.createElement("div");
    var name = document.createElement("span"); name.className = "name"; name.textContent = key.split(".").pop();
    head.appendChild(name);
    var unit = unitOf(p.description);
    if (unit) { var u = document.createElement("span"); u.className = "unit"; u.textContent = " [" + unit + "]"; head.appendChild(u); }
    el.title = key + ": " + (p.description || "");
    el.appendChild(head);
    var row = document.createElement("div"); row.className = "row"; el.appendChild(row);
    var f = { el: el, kind: kind };
    base[key] = textOf(value);
    if (kind === "number") {
      var lo = p.minimum !== undefined ? p.minimum : p.exclusiveMinimum;
      var hi = p.maximum !== undefined ? p.maximum : p.exclusiveMaximum;
      var v = typeof value === "number" ? value : null;
      var span = sliderSpan(lo, hi, v);
      var slider = document.createElement("input"); slider.type = "range";
      slider.min = span[0]; slider.max = span[1]; slider.step = types(p).indexOf("integer") >= 0 && types(p).indexOf("number") < 0 ? 1 : (span[1] - span[0]) / 400;
      slider.setAttribute("aria-label", key);
      var num = document.createElement("input"); num.type = "text"; num.inputMode = "decimal"; num.style.flex = "0 0 90px";
      num.setAttribute("aria-label", key + " value");
      if (v !== null) { slider.value = v; num.value = String(v); } else { num.placeholder = "default"; slider.disabled = true; }
      slider.oninput = function () { num.value = String(Number(slider.value)); change(key, num.value); };
      num.onchange = function () { var x = Number(num.value); if (num.value !== "" && isFinite(x)) { slider.disabled = false; slider.value = x; } change(key, num.value); };
      row.appendChild(slider); row.appendChild(num);
      f.slider = slider; f.input = num;
      f.set = function (text) { num.value = text; var x = Number(text); if (text !== "" && isFinite(x)) { slider.disabled = false; slider.value = x; } };
    } else if (kind === "enum") {
      var sel = document.createElement("select"); sel.setAttribute("aria-label", key);
      var list = choices(p);
      if (p.nullable || value === null || value === undefined) { var o0 = document.createElement("option"); o0.value = ""; o0.textContent = "(default)"; sel.appendChild(o0); }
      list.forEach(function (c) { var o = document.createElement("option"); o.value = JSON.stringify(c); o.textContent = String(c); sel.appendChild(o); });
      sel.value = value === null || value === undefined ? "" : JSON.stringify(value);
      sel.onchange = function () { change(key, sel.value); };
      row.appendChild(sel); f.input = sel;
      f.set = function (text) { sel.value = text; };
    } else if (kind === "bool") {
      var cb = document.createElement("input"); cb.type = "checkbox"; cb.checked = value === true; cb.setAttribute("aria-label", key);
      cb.onchange = function () { change(key, cb.checked ? "true" : "false"); };
      row.appendChild(cb); f.input = cb;
      f.set = function (text) { cb.checked = text === "true"; };
    } else {
      var t = document.createElement("input"); t.type = "text"; t.value = textOf(value); t.placeholder = "default"; t.setAttribute("aria-label", key);
      t.onchange = function () { change(key, t.value); };
      row.appendChild(t); f.input = t;
      f.set = function (text) { t.value = text; };
    }
    var allowed = allowedOf(p.description);
    if (allowed) { var r = document.createElement("div"); r.className = "range"; r.textContent = "allowed: " + allowed; el.appendChild(r); }
    var prob = document.createElement("div"); prob.className = "problem"; el.appendChild(prob); f.problem = prob;
    fields.set(key, f);
    return el;
  }
  // A slider's span: the allowed range, narrowed around the value when it is far wider.
  function sliderSpan(lo, hi, v) {
    var a = isFinite(lo) ? lo : null, b = isFinite(hi) ? hi : null;
    var scale = Math.max(Math.abs(v || 0), 0.1);
    if (v === null) return [a !== null ? a : 0, b !== null ? Math.min(b, (a || 0) + 10) : (a || 0) + 10];
    var l = a !== null ? a : v - 4 * scale, h = b !== null ? b : v + 4 * scale;
    if (h - l > 12 * scale) { l = Math.max(l, v - 4 * scale); h = Math.min(h, v + 4 * scale); if (a !== null && a >= 0) l = Math.max(a, Math.min(l, 0)); }
    return [l, h];
  }

  // ---- Changes -> runs (the latest wins) ---------------------------------------------
  function change(key, text) {
    if (text === "" || text === base[key]) sets.delete(key); else sets.set(key, text);
    var f = fields.get(key); if (f) f.el.classList.toggle("changed", sets.has(key));
    if (firstInput === null) firstInput = performance.now();
    share(); schedule();
  }
  function setList() { var out = []; sets.forEach(function (v, k) { out.push(k + "=" + v); }); return out; }
  function query() { var q = new URLSearchParams(); sets.forEach(function (v, k) { q.append(k, v); }); return q.toString(); }
  function share() {
    var q = query();
    history.replaceState(null, "", q ? "?" + q : location.pathname);
    $("dl-toml").href = "/api/scenario.toml" + (q ? "?" + q : "");
    $("dl-report").href = "/api/report.html" + (q ? "?" + q : "");
  }
  function schedule() { pending = true; if (!inflight) fire(); }
  function fire() {
    pending = false; inflight = true;
    var id = ++seq, sent = setList();
    status("running…");
    fetch("/api/run", { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify({ id: id, sets: sent }) })
      .then(function (r) {
        return r.text().then(function (text) {
          var j; try { j = JSON.parse(text); } catch (e) { j = { error: "the studio answered " + r.status + ": " + text.slice(0, 200) }; }
          if (j.id === undefined) j.id = id;
          return { ok: r.ok, j: j };
        });
      }, function (e) { return { ok: false, j: { id: id, error: "the studio did not answer: " + e } }; })
      .then(function (res) {
        inflight = false;
        // One request is in flight at a time, so replies come in order: each one drawn is
        // the newest run there is (a slider still moving keeps redrawing).
        try { if (res.j.id > drawn) show(res.ok, res.j); }
        catch (e) { errors.push(String(e && e.stack || e)); status("drawing failed: " + e, true); drawn = res.j.id; }
        if (pending) fire();
      });
  }
  function show(ok, j) {
    fields.forEach(function (f) { f.el.classList.remove("bad"); f.problem.textContent = ""; });
    if (!ok) {
      (j.problems || []).forEach(function (p) {
        var f = fields.get(p.key); if (f) { f.el.classList.add("bad"); f.problem.textContent = p.message; }
      });
      $("errors").hidden = false; $("errors").textContent = (j.problems ? "error: " : "") + (j.error || "the run failed");
      status("not run: invalid input", true);
      drawn = j.id || drawn; firstInput = null;
      return;
    }
    $("errors").hidden = true;
    lastRun = j;
    window.divertsimRender(j.data, false);
    var s = j.summary;
    $("title").textContent = s.outcome + " (" + s.stages.join(" → ") + ")";
    $("setting").textContent = j.setting;
    $("summary").innerHTML = j.summary_html;
    drawn = j.id;
    var ms = firstInput === null ? null : performance.now() - firstInput;
    if (ms !== null) latencies.push(ms);
    firstInput = null;
    status(s.outcome + (ms !== null ? " · redrawn " + ms.toFixed(0) + " ms after the change" : ""));
  }

  // The overrides that turn the base scenario into `file` (a resolved scenario): each leaf
  // that differs, as an override text.
  function diffSets(file) {
    var out = [];
    function walk(v, path) {
      var key = path.join(".");
      if (fields.has(key)) {
        var text = textOf(v);
        if (text !== base[key]) out.push([key, text]);
        return;
      }
      if (v && typeof v === "object" && !Array.isArray(v)) Object.keys(v).forEach(function (k) { walk(v[k], path.concat([k])); });
    }
    walk(file, []);
    return out;
  }
  function apply(pairs) {
    sets.clear();
    fields.forEach(function (f, k) { f.set(base[k]); f.el.classList.remove("changed"); });
    pairs.forEach(function (p) { var f = fields.get(p[0]); if (f) { f.set(p[1]); sets.set(p[0], p[1]); f.el.classList.add("changed"); } });
    if (firstInput === null) firstInput = performance.now();
    share(); schedule();
  }
  function setValue(key, text) { var f = fields.get(key); if (f) f.set(text); change(key, text); }

  // ---- Studies: start, progress (server-sent events), cancel --------------------------
  function study(kind, options, onProgress, onEnd) {
    return fetch("/api/studies", { method: "POST", headers: { "Content-Type": "application/json" },
      body: JSON.stringify({ analysis: kind, sets: setList(), options: options }) })
      .then(function (r) { return r.json().then(function (j) { return { ok: r.ok, j: j }; }); })
      .then(function (res) {
        if (!res.ok) { onEnd({ state: "failed", error: res.j.error || "refused" }); return null; }
        var id = res.j.id, es = new EventSource("/api/studies/" + id + "/events");
        es.addEventListener("progress", function (e) { onProgress(JSON.parse(e.data)); });
        es.addEventListener("end", function (e) { es.close(); onEnd(JSON.parse(e.data)); });
        es.onerror = function () { if (es.readyState === 2) onEnd({ state: "failed", error: "the connection to the studio closed" }); };
        return id;
      });
  }
  function cancel(id) { if (id) fetch("/api/studies/" + id, { method: "DELETE" }); }
  // A cancel pressed while the study is still starting takes effect once its id is known.
  function started(which, id) { if (cancelAsked[which]) cancel(id); cancelAsked[which] = false; return id; }
  var cancelAsked = { cap: false };
  function progressTo(el, span, p, unit) {
    el.max = Math.max(1, p.total); el.value = p.done;
    span.textContent = p.done + " of " + p.total + " " + unit;
  }

  // Capacity map.
  var capId = null, capMap = null, robustMap = null;
  $("cap-run").onclick = function () {
    var opts = { cycle_times: $("cap-tc").value, light_barriers: $("cap-sd").value, speeds: $("cap-v").value, worst: $("cap-worst").value };
    $("cap-run").disabled = true; $("cap-cancel").disabled = false; $("cap-zip").hidden = true; $("cap-status").textContent = "starting…";
    study("capacity", opts, function (p) { progressTo($("cap-progress"), $("cap-status"), p, "units"); }, function (end) {
      $("cap-run").disabled = false; $("cap-cancel").disabled = true; capId = null;
      if (end.state !== "done") { $("cap-status").textContent = end.state + (end.error ? ": " + end.error : ""); return; }
      $("cap-status").textContent = "done in " + end.elapsed_s.toFixed(1) + " s (" + end.summary.simulations + " simulations)";
      $("cap-zip").href = "/api/studies/" + end.id + "/outputs.zip"; $("cap-zip").download = "capacity-" + end.id + ".zip"; $("cap-zip").hidden = false;
      var m = { worst: opts.worst, cells: end.summary.cells, summary: end.summary.summary };
      if (opts.worst === "search") robustMap = m;
      capMap = m; drawMap();
    }).then(function (id) { capId = started("cap", id); });
  };
  $("cap-cancel").onclick = function () { if (capId) cancel(capId); else cancelAsked.cap = true; };
  var cv = $("cap-map"), geo = null;
  function drawMap() {
    if (!capMap) {
      var c0 = cv.getContext("2d"); cv.width = cv.clientWidth; cv.height = cv.clientHeight;
      c0.fillStyle = "#777"; c0.font = "14px sans-serif"; c0.textAlign = "center";
      c0.fillText("No map yet: choose the grid and press \u201ccompute map\u201d.", cv.width / 2, cv.height / 2);
      return;
    }
    var cells = capMap.cells, ctx = cv.getContext("2d");
    var dpr = window.devicePixelRatio || 1, w = cv.clientWidth, h = cv.clientHeight;
    cv.width = w * dpr; cv.height = h * dpr; ctx.setTransform(dpr, 0, 0, dpr, 0, 0); ctx.clearRect(0, 0, w, h);
    var xs = uniq(cells.map(function (c) { return c.cycle_time; })), ys = uniq(cells.map(function (c) { return c.light_barrier; }));
    var L = 60, B = 40, T = 10, R = 10, cw = (w - L - R) / xs.length, ch = (h - T - B) / ys.length;
    var ws = cells.filter(function (c) { return c.feasible; }).map(function (c) { return c.capacity; });
    var wmin = Math.min.apply(null, ws), wmax = Math.max.apply(null, ws);
    geo = { xs: xs, ys: ys, L: L, T: T, cw: cw, ch: ch, cells: cells };
    cells.forEach(function (c) {
      var i = xs.indexOf(c.cycle_time), j = ys.indexOf(c.light_barrier);
      var x = L + i * cw, y = T + (ys.length - 1 - j) * ch;
      if (c.feasible) { ctx.fillStyle = viridis(wmax > wmin ? (c.capacity - wmin) / (wmax - wmin) : 1); }
      else { ctx.fillStyle = "#e0e0e0"; }
      ctx.fillRect(x, y, cw - 1, ch - 1);
      if (!c.feasible) { ctx.strokeStyle = "#bdbdbd"; ctx.beginPath(); ctx.moveTo(x, y + ch - 1); ctx.lineTo(x + cw - 1, y); ctx.stroke(); }
    });
    // W contours (marching squares on the cell centres of feasible cells).
    if (ws.length > 3 && wmax > wmin) contours(ctx, xs, ys, cells, L, T, cw, ch, wmin, wmax);
    // The robust feasible region: its cells outlined.
    if (robustMap && robustMap !== capMap) outline(ctx, robustMap.cells, xs, ys, L, T, cw, ch);
    else if (capMap.worst === "search") outline(ctx, capMap.cells, xs, ys, L, T, cw, ch);
    ctx.fillStyle = "#222"; ctx.font = "11px sans-serif"; ctx.textAlign = "center";
    xs.forEach(function (x, i) { if (xs.length < 14 || i % 2 === 0) ctx.fillText(x.toFixed(2), L + (i + 0.5) * cw, h - B + 14); });
    ctx.fillText("cycle time t_c [s]", L + (w - L - R) / 2, h - 6);
    ctx.textAlign = "right";
    ys.forEach(function (y, j) { if (ys.length < 14 || j % 2 === 0) ctx.fillText(y.toFixed(2), L - 4, T + (ys.length - 1 - j + 0.5) * ch + 4); });
    ctx.save(); ctx.translate(12, T + (h - T - B) / 2); ctx.rotate(-Math.PI / 2); ctx.textAlign = "center"; ctx.fillText("light barrier S_d [m]", 0, 0); ctx.restore();
    $("cap-legend").textContent = ws.length
      ? "W from " + wmin.toFixed(0) + " (dark) to " + wmax.toFixed(0) + " parcels/h (yellow), contours in steps of " + step(wmin, wmax).toFixed(0) + "; grey: no setting feasible against " + (capMap.worst === "search" ? "the searched worst case (as the CLI's capacity)" : "the paper's tip strike alone (the searched worst case can still overload)") + (robustMap && robustMap !== capMap ? "; black outline: feasible against the searched worst case" : "")
      : "no feasible cell";
  }
  function step(a, b) { var s = (b - a) / 5, p = Math.pow(10, Math.floor(Math.log10(s))); return [1, 2, 5, 10].map(function (m) { return m * p; }).filter(function (v) { return v >= s; })[0]; }
  function contours(ctx, xs, ys, cells, L, T, cw, ch, wmin, wmax) {
    var grid = ys.map(function () { return xs.map(function () { return NaN; }); });
    cells.forEach(function (c) { if (c.feasible) grid[ys.indexOf(c.light_barrier)][xs.indexOf(c.cycle_time)] = c.capacity; });
    var st = step(wmin, wmax);
    ctx.strokeStyle = "rgba(255,255,255,0.9)"; ctx.lineWidth = 1.2; ctx.fillStyle = "#fff"; ctx.font = "10px sans-serif";
    function P(i, j) { return [L + (i + 0.5) * cw, T + (ys.length - 1 - j + 0.5) * ch]; }
    for (var level = Math.ceil(wmin / st) * st; level < wmax; level += st) {
      for (var j = 0; j + 1 < ys.length; j++) for (var i = 0; i + 1 < xs.length; i++) {
        var q = [[i, j], [i + 1, j], [i + 1, j + 1], [i, j + 1]], pts = [];
        for (var k = 0; k < 4; k++) {
          var a = q[k], b = q[(k + 1) % 4], va = grid[a[1]][a[0]], vb = grid[b[1]][b[0]];
          if (!isFinite(va) || !isFinite(vb)) continue;
          if ((va < level) !== (vb < level)) {
            var s = (level - va) / (vb - va), pa = P(a[0], a[1]), pb = P(b[0], b[1]);
            pts.push([pa[0] + s * (pb[0] - pa[0]), pa[1] + s * (pb[1] - pa[1])]);
          }
        }
        for (var m = 0; m + 1 < pts.length; m += 2) { ctx.beginPath(); ctx.moveTo(pts[m][0], pts[m][1]); ctx.lineTo(pts[m + 1][0], pts[m + 1][1]); ctx.stroke(); }
      }
    }
  }
  function outline(ctx, cells, xs, ys, L, T, cw, ch) {
    ctx.strokeStyle = "#000"; ctx.lineWidth = 2.5;
    var ok = {}; cells.forEach(function (c) { if (c.feasible) ok[c.cycle_time + "," + c.light_barrier] = true; });
    cells.forEach(function (c) {
      var i = xs.indexOf(c.cycle_time), j = ys.indexOf(c.light_barrier);
      if (i < 0 || j < 0 || !c.feasible) return;
      var x = L + i * cw, y = T + (ys.length - 1 - j) * ch;
      var nb = function (di, dj) { var a = xs[i + di], b = ys[j + dj]; return a !== undefined && b !== undefined && ok[a + "," + b]; };
      ctx.beginPath();
      if (!nb(0, 1)) { ctx.moveTo(x, y); ctx.lineTo(x + cw, y); }
      if (!nb(0, -1)) { ctx.moveTo(x, y + ch); ctx.lineTo(x + cw, y + ch); }
      if (!nb(-1, 0)) { ctx.moveTo(x, y); ctx.lineTo(x, y + ch); }
      if (!nb(1, 0)) { ctx.moveTo(x + cw, y); ctx.lineTo(x + cw, y + ch); }
      ctx.stroke();
    });
    ctx.lineWidth = 1;
  }
  function uniq(a) { return a.filter(function (v, i) { return a.indexOf(v) === i; }).sort(function (x, y) { return x - y; }); }
  function viridis(t) {
    var c = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
    var x = Math.max(0, Math.min(1, t)) * (c.length - 1), i = Math.min(c.length - 2, Math.floor(x)), s = x - i;
    return "rgb(" + [0, 1, 2].map(function (k) { return Math.round(c[i][k] + s * (c[i + 1][k] - c[i][k])); }).join(",") + ")";
  }
  function cellAt(ev) {
    if (!geo) return null;
    var r = cv.getBoundingClientRect(), x = ev.clientX - r.left, y = ev.clientY - r.top;
    var i = Math.floor((x - geo.L) / geo.cw), j = geo.ys.length - 1 - Math.floor((y - geo.T) / geo.ch);
    if (i < 0 || j < 0 || i >= geo.xs.length || j >= geo.ys.length) return null;
    return geo.cells.filter(function (c) { return c.cycle_time === geo.xs[i] && c.light_barrier === geo.ys[j]; })[0] || null;
  }
  function cellSets(c) {
    var out = [["machine.cycle_time", String(c.cycle_time)], ["machine.light_barrier", String(c.light_barrier)]];
    if (c.belt_speed !== null && c.belt_speed !== undefined) out.push(["machine.belt_speed", String(c.belt_speed)]);
    if (c.start_position !== null && c.start_position !== undefined) out.push(["machine.start_position", String(c.start_position)]);
    return out;
  }
  cv.onmousemove = function (ev) {
    var c = cellAt(ev), tip = $("cap-tip");
    if (!c) { tip.hidden = true; return; }
    tip.hidden = false;
    var r = cv.getBoundingClientRect();
    tip.style.left = (ev.clientX - r.left + 14) + "px"; tip.style.top = (ev.clientY - r.top + 10) + "px";
    tip.textContent = "t_c = " + c.cycle_time + " s, S_d = " + c.light_barrier + " m: " + (c.feasible
      ? "feasible, W = " + c.capacity.toFixed(0) + " /h at v = " + c.belt_speed + " m/s, R_s = " + c.start_position.toFixed(4) + " m"
      : "no feasible setting") + " (click to run)";
  };
  cv.onmouseleave = function () { $("cap-tip").hidden = true; };
  cv.onclick = function (ev) {
    var c = cellAt(ev); if (!c) return;
    var pairs = [];
    sets.forEach(function (v, k) { if (["machine.cycle_time", "machine.light_barrier", "machine.belt_speed", "machine.start_position"].indexOf(k) < 0) pairs.push([k, v]); });
    apply(pairs.concat(cellSets(c)));
  };

  // A study panel (ids prefixed `pre`): start, progress with partial results, cancel, the
  // outputs' zip, the result.
  var running = {};
  function panel(pre, analysis, options, unit, partial, done) {
    $(pre + "-run").onclick = function () {
      $(pre + "-run").disabled = true; $(pre + "-cancel").disabled = false; $(pre + "-zip").hidden = true;
      $(pre + "-status").textContent = "starting…"; $(pre + "-result").innerHTML = "";
      study(analysis, options(), function (p) {
        progressTo($(pre + "-progress"), $(pre + "-status"), p, unit);
        if (p.partial && partial) $(pre + "-result").innerHTML = partial(p.partial);
      }, function (end) {
        $(pre + "-run").disabled = false; $(pre + "-cancel").disabled = true; running[pre] = null;
        if (end.state !== "done") { $(pre + "-status").textContent = end.state + (end.error ? ": " + end.error : ""); return; }
        $(pre + "-status").textContent = "done in " + end.elapsed_s.toFixed(1) + " s";
        $(pre + "-zip").href = "/api/studies/" + end.id + "/outputs.zip"; $(pre + "-zip").download = analysis + "-" + end.id + ".zip"; $(pre + "-zip").hidden = false;
        done(end.summary);
      }).then(function (id) { running[pre] = started(pre, id); });
    };
    cancelAsked[pre] = false;
    $(pre + "-cancel").onclick = function () { if (running[pre]) cancel(running[pre]); else cancelAsked[pre] = true; };
  }

  // Reliability: the rates so far as the shards finish.
  panel("rel", "reliability", function () {
    var opts = { samples: Number($("rel-samples").value) };
    if ($("rel-seed").value !== "") opts.seed = Number($("rel-seed").value);
    return opts;
  }, "runs", function (p) {
    return "<p class=\"help\">so far (" + p.samples + " samples):</p>" + ratesHtml(p);
  }, reliabilityResult);

  // The sorter line ([line]): throughput and what happened to the stream.
  panel("line", "line", function () {
    var opts = { parcels: Number($("line-parcels").value) };
    if ($("line-seed").value !== "") opts.seed = Number($("line-seed").value);
    return opts;
  }, "segments", function (p) {
    return "<p class=\"help\">so far (" + p.parcels + " parcels):</p>" + lineRatesHtml(p);
  }, lineResult);
  function num(v) { return v === null || v === undefined ? "–" : v.toFixed(0); }
  // The throughput and the rates with their intervals (a final or a partial result).
  function lineRatesHtml(p) {
    var html = "<table><tr><th>parcels</th><th>arrivals [1/h]</th><th>throughput [1/h]</th><th>missorted [95 % CI]</th><th>struck in passing</th><th>overloaded</th><th>tipped</th></tr>";
    return html + "<tr><td>" + p.parcels + "</td><td>" + num(p.arrival_rate_per_h) + "</td><td>" + num(p.throughput_per_h) + "</td><td>" + pct(p.missort_rate) + "</td><td>" + pct(p.struck_rate) + "</td><td>" + pct(p.overload_rate) + "</td><td>" + pct(p.tipped_rate) + "</td></tr></table>";
  }
  function lineResult(s) {
    var p = s.points[0];
    var html = lineRatesHtml(p);
    html += "<h3>Outcomes</h3><table>" + Object.keys(p.outcomes).map(function (k) { return "<tr><td>" + esc(k) + "</td><td>" + pct(p.outcomes[k]) + "</td></tr>"; }).join("") + "</table>";
    $("line-result").innerHTML = html;
    lastLine = s;
  }
  var lastLine = null;
  function pct(p) { return p.estimate === null ? "–" : (100 * p.estimate).toFixed(2) + " % [" + (100 * p.lower).toFixed(2) + ", " + (100 * p.upper).toFixed(2) + "]"; }
  function esc(s) { var d = document.createElement("div"); d.textContent = String(s); return d.innerHTML; }
  // The rates with their intervals and the failures by reason (a final or a partial result).
  function ratesHtml(p) {
    var html = "<table><tr><th>samples</th><th>divert rate [95 % CI]</th><th>overload rate</th><th>tipping rate</th>" + (p.capacity_per_h !== undefined ? "<th>W [1/h]</th>" : "") + "</tr>";
    html += "<tr><td>" + p.samples + "</td><td>" + pct(p.divert_rate) + "</td><td>" + pct(p.overload_rate) + "</td><td>" + pct(p.tipping_rate) + "</td>" + (p.capacity_per_h !== undefined ? "<td>" + (p.capacity_per_h || 0).toFixed(0) + "</td>" : "") + "</tr></table>";
    var reasons = Object.keys(p.failures_by_reason);
    return html + "<h3>Failures by reason</h3>" + (reasons.length ? "<table>" + reasons.map(function (r) { return "<tr><td>" + esc(r) + "</td><td>" + p.failures_by_reason[r] + "</td></tr>"; }).join("") + "</table>" : "<p>none</p>");
  }
  function reliabilityResult(s) {
    var p = s.points[0], html = ratesHtml(p);
    html += "<h3>First failed samples</h3>";
    if (p.first_failures.length) {
      html += "<ul>" + p.first_failures.map(function (f, k) { return "<li><span class=\"failure\" data-k=\"" + k + "\">sample " + f.sample + "</span>: " + esc(f.reason) + " (final stage " + esc(f.final_stage) + ")</li>"; }).join("") + "</ul>";
    } else html += "<p>none</p>";
    $("rel-result").innerHTML = html;
    Array.prototype.forEach.call(document.querySelectorAll(".failure"), function (el) {
      el.onclick = function () { var f = p.first_failures[Number(el.dataset.k)]; apply(diffSets(f.scenario)); window.scrollTo(0, 0); };
    });
    lastReliability = s;
  }
  var lastReliability = null;

  // ---- Start ---------------------------------------------------------------------------
  $("reset").onclick = function () { apply([]); };
  $("share").onclick = function () {
    var url = location.href;
    if (navigator.clipboard) navigator.clipboard.writeText(url).then(function () { status("share link copied: " + url); }, function () { status(url); });
    else status(url);
  };
  $("filter").oninput = function () {
    var q = $("filter").value.toLowerCase();
    fields.forEach(function (f, k) { f.el.hidden = q !== "" && k.toLowerCase().indexOf(q) < 0; });
    if (q) Array.prototype.forEach.call(document.querySelectorAll("#fields details"), function (d) { d.open = true; });
  };
  window.addEventListener("resize", drawMap);
  drawMap();
  fetch("/api/scenario").then(function (r) { return r.json(); }).then(function (j) {
    info = j;
    $("scenario-name").textContent = "scenario: " + j.name + " · divertsim " + j.version;
    buildEditor();
    // The share URL's overrides.
    var pairs = [];
    new URLSearchParams(location.search).forEach(function (v, k) { pairs.push([k, v]); });
    pairs.forEach(function (p) { var f = fields.get(p[0]); if (f) { f.set(p[1]); f.el.classList.add("changed"); } sets.set(p[0], p[1]); });
    share(); schedule();
  }).catch(function (e) { status("cannot read the scenario: " + e, true); });

  // The test hook.
  window.studio = {
    errors: errors,
    latencies: latencies,
    seq: function () { return seq; },
    drawn: function () { return drawn; },
    idle: function () { return !inflight && !pending && drawn === seq; },
    sets: setList,
    setValue: setValue,
    apply: apply,
    lastRun: function () { return lastRun; },
    capacity: function () { return capMap; },
    reliability: function () { return lastReliability; },
    line: function () { return lastLine; },
    cellCentre: function (k) {
      if (!geo) return null;
      var c = geo.cells[k], r = cv.getBoundingClientRect();
      var i = geo.xs.indexOf(c.cycle_time), j = geo.ys.indexOf(c.light_barrier);
      return { x: r.left + geo.L + (i + 0.5) * geo.cw, y: r.top + geo.T + (geo.ys.length - 1 - j + 0.5) * geo.ch, cell: c };
    }
  };
})();
