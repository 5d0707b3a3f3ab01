// The animated line view of `divertsim line --out`: the belt seen from above, every
// diverter's arm swinging through its cycles, every parcel of the stretch at its pose.
// DATA: {belt_width, x0, x1, t0, t1, diverters: [{x, arm, dt, shape, cycles}],
//        parcels: [{i, a, b, k: [[t, x, y, phi], ...], gone, outcome, bad, link}]}
const LINE_ERRORS = [];
window.addEventListener("error", (e) => LINE_ERRORS.push(String(e.message)));
(function () {
  const D = JSON.parse(document.getElementById("line-data").textContent);
  const canvas = document.getElementById("line-canvas");
  const ctx = canvas.getContext("2d");
  const slider = document.getElementById("line-time");
  const label = document.getElementById("line-clock");
  const play = document.getElementById("line-play");
  const speed = document.getElementById("line-speed");
  const COLORS = {
    diverted: "#2ca02c", passed: "#9aa3ad", arm_busy: "#ff7f0e", not_diverted: "#d62728",
    struck_in_passing: "#9467bd", wrongly_diverted: "#e377c2", collision: "#8c564b", failed: "#000",
  };
  const yMax = D.belt_width + 0.6, yMin = -0.4;
  let scale = 1, t = D.t0, playing = true, last = null;

  function resize() {
    canvas.width = canvas.clientWidth * (window.devicePixelRatio || 1);
    scale = canvas.width / (D.x1 - D.x0);
    canvas.height = Math.round((yMax - yMin) * scale);
  }
  const X = (x) => (x - D.x0) * scale;
  const Y = (y) => canvas.height - (y - yMin) * scale;

  function armAngle(d, tt) {
    for (let k = d.cycles.length - 1; k >= 0; k--) {
      const s = d.cycles[k];
      if (s <= tt) {
        const u = (tt - s) / d.dt;
        if (u >= d.shape.length - 1) return 0;
        const i = Math.floor(u), f = u - i;
        return d.shape[i] + f * (d.shape[i + 1] - d.shape[i]);
      }
    }
    return 0;
  }

  function pose(p, tt) {
    const k = p.k;
    if (!k.length || tt < k[0][0] || (p.gone !== null && tt > p.gone)) return null;
    if (tt >= k[k.length - 1][0]) return p.gone === null ? k[k.length - 1] : null;
    let lo = 0, hi = k.length - 1;
    while (hi - lo > 1) { const m = (lo + hi) >> 1; if (k[m][0] <= tt) lo = m; else hi = m; }
    const a = k[lo], b = k[hi], w = b[0] > a[0] ? (tt - a[0]) / (b[0] - a[0]) : 0;
    return [tt, a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2]), a[3] + w * (b[3] - a[3])];
  }

  function draw() {
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    // Chutes beyond the far edge, the belt, its edges.
    ctx.fillStyle = "#eef6ee";
    ctx.fillRect(X(D.x0), Y(yMax), X(D.x1) - X(D.x0), Y(D.belt_width) - Y(yMax));
    ctx.fillStyle = "#e9ecef";
    ctx.fillRect(X(D.x0), Y(D.belt_width), X(D.x1) - X(D.x0), Y(0) - Y(D.belt_width));
    ctx.strokeStyle = "#6c757d";
    ctx.lineWidth = 1;
    for (const y of [0, D.belt_width]) {
      ctx.beginPath(); ctx.moveTo(X(D.x0), Y(y)); ctx.lineTo(X(D.x1), Y(y)); ctx.stroke();
    }
    D.diverters.forEach((d, n) => {
      const al = armAngle(d, t);
      ctx.strokeStyle = "#1f3b73"; ctx.lineWidth = Math.max(3, 0.03 * scale);
      ctx.beginPath(); ctx.moveTo(X(d.x), Y(0));
      ctx.lineTo(X(d.x + d.arm * Math.cos(al)), Y(d.arm * Math.sin(al))); ctx.stroke();
      ctx.fillStyle = "#1f3b73"; ctx.beginPath(); ctx.arc(X(d.x), Y(0), 5, 0, 7); ctx.fill();
      ctx.font = "12px system-ui"; ctx.fillText("chute " + (n + 1), X(d.x + 0.2), Y(yMax - 0.15));
    });
    for (const p of D.parcels) {
      const q = pose(p, t);
      if (!q) continue;
      const [, x, y, phi] = q, c = Math.cos(phi), s = Math.sin(phi), a = p.a / 2, b = p.b / 2;
      ctx.beginPath();
      [[a, -b], [a, b], [-a, b], [-a, -b]].forEach(([u, v], j) => {
        const px = X(x + u * c - v * s), py = Y(y + u * s + v * c);
        if (j) ctx.lineTo(px, py); else ctx.moveTo(px, py);
      });
      ctx.closePath();
      ctx.fillStyle = COLORS[p.outcome] || "#999"; ctx.globalAlpha = 0.8; ctx.fill();
      ctx.globalAlpha = 1; ctx.lineWidth = p.bad ? 3 : 1;
      ctx.strokeStyle = p.bad ? "#c00" : "#333"; ctx.stroke();
      ctx.fillStyle = "#111"; ctx.font = "11px system-ui";
      ctx.fillText(String(p.i), X(x) - 8, Y(y) + 4);
    }
    label.textContent = "t = " + t.toFixed(2) + " s";
    slider.value = String(t);
  }

  function frame(now) {
    if (playing && last !== null) {
      t += ((now - last) / 1000) * Number(speed.value);
      if (t > D.t1) t = D.t0;
    }
    last = now;
    draw();
    requestAnimationFrame(frame);
  }

  slider.min = String(D.t0); slider.max = String(D.t1); slider.step = "0.01";
  // #t=SECONDS opens the view paused at that time (a link to a moment of the stream).
  const at = /[#&]t=(-?[0-9.]+)/.exec(location.hash);
  if (at) { t = Math.min(D.t1, Math.max(D.t0, Number(at[1]))); playing = false; play.textContent = "play"; }
  slider.addEventListener("input", () => { t = Number(slider.value); draw(); });
  // A click on a failed parcel opens its own run (with every stroke near it).
  canvas.addEventListener("click", (e) => {
    const r = canvas.getBoundingClientRect(), k = canvas.width / r.width;
    const x = (e.clientX - r.left) * k / scale + D.x0;
    const y = yMin + (canvas.height - (e.clientY - r.top) * k) / scale;
    for (const p of D.parcels) {
      const q = pose(p, t);
      if (q && p.link && Math.hypot(q[1] - x, q[2] - y) < Math.max(p.a, p.b) / 2) {
        window.open(p.link, "_blank");
        return;
      }
    }
  });
  play.addEventListener("click", () => { playing = !playing; play.textContent = playing ? "pause" : "play"; });
  window.addEventListener("resize", () => { resize(); draw(); });
  resize();
  requestAnimationFrame(frame);

  // #selftest=T1,T2,…: after the animation has played a little, the poses drawn at those
  // times (every parcel on the belt, every arm's angle) as JSON in a pre element, id selftest.
  const st = /selftest=([-0-9.,]+)/.exec(location.hash);
  if (st) {
    const start = t;
    setTimeout(() => {
      const played = t !== start;
      const poses = st[1].split(",").map(Number).map((tt) => ({
        t: tt,
        parcels: D.parcels.map((p) => [p.i, pose(p, tt)]).filter(([, q]) => q)
          .map(([i, q]) => ({ i, x: q[1], y: q[2], phi: q[3] })),
        arms: D.diverters.map((d) => armAngle(d, tt)),
      }));
      const pre = document.createElement("pre");
      pre.id = "selftest";
      pre.textContent = JSON.stringify({ played, errors: LINE_ERRORS, poses });
      document.body.appendChild(pre);
    }, 500);
  }
})();
