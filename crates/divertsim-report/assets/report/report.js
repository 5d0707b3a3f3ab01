// divertsim report: the animated top view and the linked plots of one or more runs.
// Data: the JSON in <script id="divertsim-data">. No network access; uPlot is inlined.
// The same viewer draws the studio's live runs: `window.divertsimRender(D)` redraws the page
// for new data (the previous animation and plots are dropped).
(function () {
  "use strict";
  var errors = [];
  window.addEventListener("error", function (e) { errors.push(String(e.message)); });
  var current = null;
  window.addEventListener("resize", function () { if (current) current.resize(); });

  function render(D, selftest) {
  if (current) current.stop();
  var runs = D.runs;
  var T = Math.max.apply(null, runs.map(function (r) { return r.t[r.t.length - 1]; }));
  var now = 0, playing = false, speed = parseFloat(document.getElementById("speed").value) || 1, last = null;
  var visible = runs.map(function () { return true; });

  // The sample interval of run r that holds time t: linear interpolation between samples.
  function at(r, t) {
    var ts = r.t, n = ts.length;
    if (t <= ts[0]) return sample(r, 0, 0, 0);
    if (t >= ts[n - 1]) return sample(r, n - 1, n - 1, 0);
    var lo = 0, hi = n - 1;
    while (hi - lo > 1) { var mid = (lo + hi) >> 1; if (ts[mid] <= t) lo = mid; else hi = mid; }
    var h = ts[hi] - ts[lo];
    return sample(r, lo, hi, h > 0 ? (t - ts[lo]) / h : 0);
  }
  function sample(r, i, j, s) {
    function L(a) { return a[i] + (a[j] - a[i]) * s; }
    var k = s < 1 ? i : j;
    return { t: L(r.t), x: L(r.x), y: L(r.y), phi: L(r.phi), alpha: L(r.alpha),
             stage: D.stages[r.stage[k]], contacts: r.contacts[k] || [] };
  }

  // Canvas view: the machine frame fitted to the canvas, y up.
  var cv = document.getElementById("view"), ctx = cv.getContext("2d");
  var xs = [], ys = [];
  runs.forEach(function (r) { xs = xs.concat(r.x); ys = ys.concat(r.y); });
  var xmin = Math.min(-0.2, Math.min.apply(null, xs) - 0.5), xmax = Math.max(D.machine.arm_length + 0.2, Math.max.apply(null, xs) + 0.5);
  var ymin = Math.min(-0.3, Math.min.apply(null, ys) - 0.3), ymax = Math.max(D.machine.belt_width + 0.3, Math.max.apply(null, ys) + 0.3, D.machine.arm_length * 0.8);
  var view = { s: 1, ox: 0, oy: 0 };
  function fit() {
    var w = cv.clientWidth, h = cv.clientHeight, dpr = window.devicePixelRatio || 1;
    cv.width = Math.round(w * dpr); cv.height = Math.round(h * dpr);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    view.s = Math.min(w / (xmax - xmin), h / (ymax - ymin));
    view.ox = (w - view.s * (xmax - xmin)) / 2 - view.s * xmin;
    view.oy = (h + view.s * (ymax - ymin)) / 2 + view.s * ymin;
  }
  function P(x, y) { return [view.ox + view.s * x, view.oy - view.s * y]; }

  function draw() {
    var w = cv.clientWidth, h = cv.clientHeight;
    ctx.clearRect(0, 0, w, h);
    var m = D.machine;
    // Belt, guide, pivot, far edge.
    var a = P(xmin, m.belt_width), b = P(xmax, 0);
    ctx.fillStyle = "#eef2f5"; ctx.fillRect(a[0], a[1], b[0] - a[0], b[1] - a[1]);
    ctx.strokeStyle = "#9aa5ad"; ctx.lineWidth = 1;
    ctx.beginPath(); var e = P(xmin, m.belt_width), f = P(xmax, m.belt_width); ctx.moveTo(e[0], e[1]); ctx.lineTo(f[0], f[1]); ctx.stroke();
    ctx.strokeStyle = "#212121"; ctx.lineWidth = 3; ctx.beginPath();
    var g0 = P(xmin, 0), g1 = P(m.guide_everywhere ? xmax : 0, 0); ctx.moveTo(g0[0], g0[1]); ctx.lineTo(g1[0], g1[1]); ctx.stroke();
    var o = P(0, 0); ctx.fillStyle = "#212121"; ctx.beginPath(); ctx.arc(o[0], o[1], 5, 0, 2 * Math.PI); ctx.fill();
    scaleBar(w, h);
    runs.forEach(function (r, k) {
      if (!visible[k]) return;
      var q = at(r, now);
      // Path: all of it faint, the part travelled bold.
      ctx.strokeStyle = r.color; ctx.globalAlpha = 0.25; ctx.lineWidth = 1.5; ctx.beginPath();
      for (var i = 0; i < r.t.length; i++) { var p = P(r.x[i], r.y[i]); if (i) ctx.lineTo(p[0], p[1]); else ctx.moveTo(p[0], p[1]); }
      ctx.stroke(); ctx.globalAlpha = 1; ctx.lineWidth = 2; ctx.beginPath();
      for (i = 0; i < r.t.length && r.t[i] <= now; i++) { p = P(r.x[i], r.y[i]); if (i) ctx.lineTo(p[0], p[1]); else ctx.moveTo(p[0], p[1]); }
      p = P(q.x, q.y); ctx.lineTo(p[0], p[1]); ctx.stroke();
      // The arm at its angle.
      var tip = P(r.arm_length * Math.cos(q.alpha), r.arm_length * Math.sin(q.alpha));
      ctx.strokeStyle = runs.length > 1 ? r.color : "#8c564b"; ctx.lineWidth = 5; ctx.beginPath();
      ctx.moveTo(o[0], o[1]); ctx.lineTo(tip[0], tip[1]); ctx.stroke();
      // The parcel outline.
      var c = Math.cos(q.phi), s = Math.sin(q.phi), ha = r.length / 2, hb = r.width / 2;
      ctx.fillStyle = r.color; ctx.globalAlpha = 0.18; ctx.beginPath();
      [[ha, hb], [-ha, hb], [-ha, -hb], [ha, -hb]].forEach(function (v, j) {
        var pt = P(q.x + c * v[0] - s * v[1], q.y + s * v[0] + c * v[1]);
        if (j) ctx.lineTo(pt[0], pt[1]); else ctx.moveTo(pt[0], pt[1]);
      });
      ctx.closePath(); ctx.fill(); ctx.globalAlpha = 1; ctx.strokeStyle = r.color; ctx.lineWidth = 2; ctx.stroke();
      ctx.fillStyle = r.color; ctx.beginPath(); ctx.arc(p[0], p[1], 3, 0, 2 * Math.PI); ctx.fill();
      // A measured track: its points, those already passed solid.
      (r.measured || []).forEach(function (mp) {
        var pp = P(mp[1], mp[2]);
        ctx.fillStyle = "#111"; ctx.globalAlpha = mp[0] <= now ? 0.9 : 0.25;
        ctx.beginPath(); ctx.arc(pp[0], pp[1], 3.5, 0, 2 * Math.PI); ctx.fill();
      });
      ctx.globalAlpha = 1;
      // Active contacts.
      ctx.fillStyle = "#1b5e20";
      q.contacts.forEach(function (pt) { var cp = P(pt[0], pt[1]); ctx.beginPath(); ctx.arc(cp[0], cp[1], 4, 0, 2 * Math.PI); ctx.fill(); });
      // Every strike marked on the path (a small cross), flashed for 60 ms with its impulse.
      ctx.strokeStyle = "#c62828"; ctx.lineWidth = 1.5;
      r.impacts.forEach(function (im) {
        var xp = P(im.point[0], im.point[1]);
        ctx.beginPath(); ctx.moveTo(xp[0] - 4, xp[1] - 4); ctx.lineTo(xp[0] + 4, xp[1] + 4);
        ctx.moveTo(xp[0] - 4, xp[1] + 4); ctx.lineTo(xp[0] + 4, xp[1] - 4); ctx.stroke();
      });
      r.impacts.forEach(function (im) {
        var age = now - im.t;
        if (age >= 0 && age < 0.06) {
          var ip = P(im.point[0], im.point[1]);
          ctx.strokeStyle = "#c62828"; ctx.lineWidth = 2; ctx.beginPath(); ctx.arc(ip[0], ip[1], 8 + 120 * age, 0, 2 * Math.PI); ctx.stroke();
          ctx.fillStyle = "#c62828"; ctx.font = "13px sans-serif";
          ctx.fillText(im.stage + " S = " + im.impulse.toFixed(2) + " N·s", ip[0] + 12, ip[1] - 12);
        }
      });
    });
    var first = at(runs[0], now);
    document.getElementById("clock").textContent = "t = " + now.toFixed(3) + " s · " + (runs.length > 1 ? runs.map(function (r) { return at(r, now).stage; }).join(" / ") : first.stage);
    document.getElementById("scrub").value = now;
    cursors();
  }

  // A scale bar in the lower left corner: a round length of about a fifth of the view, and
  // the axes' directions (x along the belt, y across it).
  var scaleShown = null;
  function scaleBar(w, h) {
    var want = (w / 5) / view.s, p10 = Math.pow(10, Math.floor(Math.log10(want)));
    var len = [1, 2, 5, 10].map(function (k) { return k * p10; }).filter(function (v) { return v <= want; }).pop() || p10;
    var px = len * view.s, x0 = 14, y0 = h - 14;
    ctx.strokeStyle = "#333"; ctx.fillStyle = "#333"; ctx.lineWidth = 2; ctx.beginPath();
    ctx.moveTo(x0, y0 - 5); ctx.lineTo(x0, y0); ctx.lineTo(x0 + px, y0); ctx.lineTo(x0 + px, y0 - 5); ctx.stroke();
    ctx.font = "12px sans-serif"; ctx.textAlign = "center";
    scaleShown = (len >= 1 ? len.toFixed(0) : len.toPrecision(1)) + " m";
    ctx.fillText(scaleShown, x0 + px / 2, y0 - 6);
    ctx.textAlign = "left"; ctx.fillText("x → along the belt, y ↑ across it", x0 + px + 12, y0);
  }

  function seek(t) { now = Math.max(0, Math.min(T, t)); draw(); }
  function frame(ts) {
    if (!playing) { last = null; return; }
    if (last !== null) now += speed * (ts - last) / 1000;
    last = ts;
    if (now >= T) { now = T; playing = false; label(); }
    draw();
    if (playing) requestAnimationFrame(frame);
  }
  function play() { if (now >= T) now = 0; playing = true; label(); requestAnimationFrame(frame); }
  function pause() { playing = false; label(); }
  function label() { document.getElementById("play").textContent = playing ? "❚❚ pause" : "▶ play"; }

  document.getElementById("play").onclick = function () { playing ? pause() : play(); };
  document.getElementById("speed").onchange = function (e) { speed = parseFloat(e.target.value); };
  var scrub = document.getElementById("scrub"); scrub.max = T; scrub.step = 0.001;
  scrub.oninput = function (e) { pause(); seek(parseFloat(e.target.value)); };
  document.getElementById("back").onclick = function () { pause(); seek(now - 0.005); };
  document.getElementById("fwd").onclick = function () { pause(); seek(now + 0.005); };
  var toggles = document.getElementById("toggles");
  toggles.innerHTML = "";
  if (runs.length > 1) runs.forEach(function (r, k) {
    var l = document.createElement("label"), c = document.createElement("input");
    c.type = "checkbox"; c.checked = true; c.onchange = function () { visible[k] = c.checked; draw(); };
    l.appendChild(c); var sw = document.createElement("span"); sw.className = "swatch"; sw.style.background = r.color;
    l.appendChild(sw); l.appendChild(document.createTextNode(r.label)); toggles.appendChild(l);
  });

  // Linked plots: hovering moves the animation's time; the time shows as the cursor.
  var plots = [];
  function cursors() {
    plots.forEach(function (u) { var left = u.valToPos(now, "x"); if (isFinite(left)) u.setCursor({ left: left, top: -10 }, false); });
  }
  function plot(el, title, series, data, opts) {
    var o = {
      title: title, width: el.clientWidth || 600, height: 220, series: [{ label: "t [s]" }].concat(series),
      // Every plot spans the runs' own time, 0 to T, whatever its points.
      scales: { x: { time: false, range: [0, T] } }, axes: [{ label: "t [s]" }, { label: (opts && opts.y) || "" }],
      cursor: { sync: { key: "t" } },
      hooks: { setCursor: [function (u) { if (u.cursor.event && u.cursor.idx != null) { pause(); now = u.data[0][u.cursor.idx]; draw(); } }] }
    };
    el.textContent = "";
    var u = new uPlot(o, data, el); plots.push(u); return u;
  }
  if (window.uPlot) {
    var r0 = runs[0];
    var deg = function (a) { return a.map(function (v) { return v * 180 / Math.PI; }); };
    // A series is named by its run only where there are several runs.
    var tag = function (r, s) { return runs.length > 1 ? r.label + ": " + s : s; };
    plot(document.getElementById("p-alpha"), "arm angle α(t)", runs.map(function (r) { return { label: tag(r, "α [deg]"), stroke: r.color, spanGaps: true }; }),
      aligned(runs.map(function (r) { return [r.t, deg(r.alpha)]; })), { y: "α [deg]" });
    // The drive's torque on the arm beside α (docs/model.md §12b).
    var armed = runs.filter(function (r) { return r.drive_torque; });
    // Zero throughout (a massless arm that holds no contact: its strikes are impulses, not
    // part of the curve) is said, not drawn as a flat line on an arbitrary axis.
    var loaded = armed.filter(function (r) { return r.drive_torque.some(function (v) { return v !== null && Math.abs(v) > 0; }); });
    if (armed.length && !loaded.length) {
      document.getElementById("p-torque").textContent = "drive torque on the arm: 0 throughout (" +
        (D.machine.arm_inertia > 0 ? "no contact held the arm" : "a massless arm (machine.arm_mass or arm_inertia 0) and no contact held") +
        "); a strike is an impulse: its angular impulse on the arm is in the strikes table";
    } else if (armed.length) {
      plot(document.getElementById("p-torque"), "drive torque on the arm M_d(t) = I α̈ − M_c", armed.map(function (r) { return { label: tag(r, "M_d [N·m]"), stroke: r.color, spanGaps: true }; }),
        aligned(armed.map(function (r) { return [r.t, r.drive_torque]; })), { y: "M_d [N·m]" });
    } else {
      document.getElementById("p-torque").textContent = "no arm: no drive torque";
    }
    plot(document.getElementById("p-vel"), "parcel velocity and spin (" + r0.label + ")",
      [{ label: "vx [m/s]", stroke: "#1f77b4" }, { label: "vy [m/s]", stroke: "#ff7f0e" }, { label: "ω [rad/s]", stroke: "#2ca02c" }],
      [r0.t, r0.vx, r0.vy, r0.omega], { y: "m/s, rad/s" });
    var imp = [], seriesI = [];
    // Strikes as points only (no line between them).
    runs.forEach(function (r) { seriesI.push({ label: tag(r, "S [N·s]"), stroke: r.color, fill: r.color, paths: function () { return null; }, points: { show: true, size: 9 } }); });
    var tI = [];
    runs.forEach(function (r) { r.impacts.forEach(function (im) { tI.push(im.t); }); });
    tI = tI.filter(function (v, i, a) { return a.indexOf(v) === i; }).sort(function (a, b) { return a - b; });
    if (tI.length) {
      // The free fall is a limit line across the whole run: the axis gets 0 and T too.
      var tA = [0, T].concat(tI).sort(function (a, b) { return a - b; }).filter(function (v, i, a) { return i === 0 || v !== a[i - 1]; });
      var cols = [tA];
      runs.forEach(function (r) { cols.push(tA.map(function (t) { var m = r.impacts.filter(function (im) { return im.t === t; }); return m.length ? m[0].impulse : null; })); });
      cols.push(tA.map(function () { return r0.fall_impulse; }));
      seriesI.push({ label: "free fall from " + D.drop_height + " m (the limit)", stroke: "#c62828", width: 1.5, dash: [6, 4], points: { show: false } });
      plot(document.getElementById("p-imp"), "strikes: impulse S against the free fall", seriesI, cols, { y: "S [N·s]" });
    } else {
      document.getElementById("p-imp").textContent = "no strikes";
    }
    stageBar();
  } else {
    errors.push("uPlot missing");
  }
  // Columns of several runs on one time axis (nulls where a run has no sample).
  function aligned(pairs) {
    var t = [];
    pairs.forEach(function (p) { t = t.concat(p[0]); });
    t = t.sort(function (a, b) { return a - b; }).filter(function (v, i, a) { return i === 0 || v !== a[i - 1]; });
    var cols = [t];
    pairs.forEach(function (p) {
      var map = new Map(); p[0].forEach(function (v, i) { map.set(v, p[1][i]); });
      cols.push(t.map(function (v) { return map.has(v) ? map.get(v) : null; }));
    });
    return cols;
  }
  // The stage timeline: one coloured band per stage, labelled where there is room.
  function stageBar() {
    var el = document.getElementById("p-stage"); el.innerHTML = "";
    runs.forEach(function (r) {
      var row = document.createElement("div"); row.className = "stagerow";
      var name = document.createElement("span"); name.className = "stagename"; name.textContent = r.label; row.appendChild(name);
      var bar = document.createElement("div"); bar.className = "stagebar";
      var tEnd = r.t[r.t.length - 1], i = 0;
      while (i < r.t.length) {
        var j = i; while (j + 1 < r.t.length && r.stage[j + 1] === r.stage[i]) j++;
        var t0 = r.t[i], t1 = j + 1 < r.t.length ? r.t[j + 1] : tEnd;
        var seg = document.createElement("div"); seg.className = "seg";
        seg.style.left = (100 * t0 / T) + "%"; seg.style.width = Math.max(0.15, 100 * (t1 - t0) / T) + "%";
        seg.style.background = D.stage_colors[r.stage[i]]; seg.title = D.stages[r.stage[i]] + ": " + t0.toFixed(3) + "–" + t1.toFixed(3) + " s";
        if ((t1 - t0) / T > 0.04) seg.textContent = D.stages[r.stage[i]];
        (function (t) { seg.onclick = function () { pause(); seek(t); }; })(t0);
        bar.appendChild(seg); i = j + 1;
      }
      row.appendChild(bar); el.appendChild(row);
    });
  }

  current = {
    resize: function () { fit(); draw(); },
    stop: function () { playing = false; label(); plots.forEach(function (u) { u.destroy(); }); plots = []; }
  };
  fit(); draw();

  // The test hook: seek, the drawn pose, play/pause, errors.
  window.divertsim = {
    duration: T,
    seek: seek, play: play, pause: pause,
    time: function () { return now; },
    pose: function (k) { var q = at(runs[k || 0], now); return { t: now, x: q.x, y: q.y, phi: q.phi, alpha: q.alpha, stage: q.stage }; },
    errors: errors
  };
  // #selftest=t1,t2,...: play a moment, then seek to each time and print the drawn poses.
  // Time from navigation to the first drawn frame [ms] (for the load-time figure).
  var loadedMs = window.performance ? performance.now() : null;
  document.body.setAttribute("data-loaded-ms", String(loadedMs));
  var m = selftest && /selftest=([0-9.,]+)/.exec(location.hash);
  if (m) {
    var times = m[1].split(",").map(parseFloat);
    play();
    setTimeout(function () {
      var played = now > 0; pause();
      var poses = times.map(function (t) { seek(t); return runs.map(function (r, k) { return window.divertsim.pose(k); }); });
      var out = document.createElement("pre"); out.id = "selftest";
      // What the plots show: each one's title, x range and series (with their drawn points).
      var shown = plots.map(function (u) {
        return { title: u.root.querySelector(".u-title") ? u.root.querySelector(".u-title").textContent : "",
                 x: [u.scales.x.min, u.scales.x.max],
                 series: u.series.slice(1).map(function (se, i) {
                   return { label: se.label, points: u.data[i + 1].filter(function (v) { return v !== null; }).length };
                 }) };
      });
      out.textContent = JSON.stringify({ played: played, errors: errors, poses: poses, loaded_ms: loadedMs, T: T,
        plots: shown, torque_text: document.getElementById("p-torque").textContent, scale_bar: scaleShown });
      document.body.appendChild(out);
      seek(times[times.length - 1]);
    }, 400);
  }
  }

  window.divertsimRender = render;
  var data = document.getElementById("divertsim-data");
  if (data && data.textContent.trim()) render(JSON.parse(data.textContent), true);
})();
