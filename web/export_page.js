/* The exported replay's own page (web/_export.py writes it beside viser's client).
 *
 * viser's client plays the recorded 3-D scene; this script draws the rest of the
 * replay page over it, from the data web/_export.py embedded (gzipped JSON in
 * window.__GCS_EXPORT__): the status, vehicles table and events as the replay page
 * renders them at each frame, the plots of the whole flight, and a timeline with
 * the phases and events. It owns the time: viser's own playback bar is hidden
 * and viser's playback is moved to each frame shown, through that bar's time
 * field (viser 1.1's page offers no other handle). No network: everything is in
 * the file.
 *
 * window.gcsExport is the page's handle for scripts and tests: seek(t), play(),
 * pause(), time(), state() (what is drawn now), viserTime().
 */
(function () {
  "use strict";

  const css = `
#gcs-x-panel{position:fixed;top:8px;left:8px;width:470px;max-height:calc(100vh - 80px);
  overflow-y:auto;background:rgba(255,255,255,0.96);border-radius:6px;z-index:20;
  box-shadow:0 1px 6px rgba(0,0,0,0.18);font:13px system-ui,sans-serif;color:#263238}
#gcs-x-panel.collapsed{width:auto}
#gcs-x-panel.collapsed .gcs-x-body{display:none}
.gcs-x-head{display:flex;gap:4px;align-items:center;padding:4px 6px;border-bottom:1px solid #eceff1}
.gcs-x-head button{border:1px solid #cfd8dc;background:#fff;border-radius:4px;padding:2px 8px;
  cursor:pointer;font:inherit}
.gcs-x-head button.on{background:#eceff1;font-weight:600}
.gcs-x-title{flex:1;font-weight:600;padding-left:4px;white-space:nowrap;overflow:hidden;
  text-overflow:ellipsis}
.gcs-x-chart{padding:4px 8px}
.gcs-x-chart .t{font-weight:600;font-size:12px}
.gcs-x-legend{font-size:11px;color:#455a64}
.gcs-x-legend span{margin-right:8px;white-space:nowrap}
.gcs-x-legend i{display:inline-block;width:14px;height:3px;margin-right:3px;vertical-align:middle}
.gcs-x-chart canvas{width:100%;height:150px;display:block;cursor:crosshair}
#gcs-x-bar{position:fixed;left:0;right:0;bottom:0;height:52px;z-index:20;display:flex;
  align-items:center;gap:6px;padding:0 10px;background:rgba(255,255,255,0.97);
  border-top:1px solid #cfd8dc;font:13px system-ui,sans-serif;color:#263238}
#gcs-x-bar button,#gcs-x-bar select{border:1px solid #cfd8dc;background:#fff;border-radius:4px;
  padding:3px 8px;cursor:pointer;font:inherit;white-space:nowrap}
#gcs-x-time{font-family:ui-monospace,monospace;min-width:120px;text-align:center}
#gcs-x-scrub{flex:1;height:40px;cursor:pointer;touch-action:none}
`;

  function el(tag, attrs, html) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
    if (html !== undefined) e.innerHTML = html;
    return e;
  }

  async function load() {
    const bin = atob(window.__GCS_EXPORT__);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
    return JSON.parse(await new Response(stream).text());
  }

  function niceStep(span, count) {
    const raw = span / Math.max(count, 1);
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    for (const m of [1, 2, 5, 10]) if (m * mag >= raw) return m * mag;
    return 10 * mag;
  }

  function fmt(x, step) {
    const digits = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
    return x.toFixed(Math.min(digits, 4));
  }

  function start(D) {
    const N = D.frames, hz = D.hz, last = (N - 1) / hz, n = D.ids.length;
    let t = 0, playing = false, speed = 1, shown = -1, lastNow = null;
    const shownHtml = {summary: -1, vehicles: -1, events: -1};

    document.head.appendChild(el("style", {}, css));
    // -- the left panel: status and plots, as on the replay page -----------------------
    const panel = el("div", {id: "gcs-x-panel", "data-gcs": "export-panel"});
    const head = el("div", {class: "gcs-x-head"});
    const title = el("div", {class: "gcs-x-title"}, "");
    title.textContent = "REPLAY " + D.name;
    const statusTab = el("button", {class: "on"}, "Status");
    const plotsTab = el("button", {}, "Plots");
    const fold = el("button", {title: "fold the panel"}, "&#9664;");
    head.append(title, statusTab, plotsTab, fold);
    const body = el("div", {class: "gcs-x-body"});
    const status = el("div", {"data-gcs": "export-status"});
    const summary = el("div"), vehicles = el("div"), events = el("div");
    status.append(summary, vehicles, el("div", {}, D.html.filter), events);
    const plots = el("div", {"data-gcs": "export-plots", style: "display:none"});
    body.append(status, plots);
    panel.append(head, body);
    statusTab.onclick = () => { status.style.display = ""; plots.style.display = "none";
      statusTab.className = "on"; plotsTab.className = ""; };
    plotsTab.onclick = () => { status.style.display = "none"; plots.style.display = "";
      plotsTab.className = "on"; statusTab.className = ""; drawCharts(true); };
    fold.onclick = () => { panel.classList.toggle("collapsed");
      fold.innerHTML = panel.classList.contains("collapsed") ? "&#9654;" : "&#9664;"; };

    // -- the timeline bar ----------------------------------------------------------------
    const bar = el("div", {id: "gcs-x-bar", "data-gcs": "export-timeline"});
    const prev = el("button", {title: "previous event", "data-gcs": "export-prev"},
      "&#9664; event");
    const play = el("button", {title: "play / pause (space)", "data-gcs": "export-play"},
      "&#9654;");
    const next = el("button", {title: "next event", "data-gcs": "export-next"},
      "event &#9654;");
    const time = el("span", {id: "gcs-x-time", "data-gcs": "export-time"});
    const speedSel = el("select", {title: "speed", "data-gcs": "export-speed"});
    for (const s of D.speeds) {
      const o = el("option", {value: String(s)}, s + "x");
      if (s === 1) o.selected = true;
      speedSel.append(o);
    }
    const scrub = el("canvas", {id: "gcs-x-scrub", "data-gcs": "export-scrubber"});
    bar.append(prev, play, next, time, speedSel, scrub);

    const mount = () => { document.body.append(panel, bar); };
    if (document.body) mount(); else document.addEventListener("DOMContentLoaded", mount);

    // -- time ------------------------------------------------------------------------------
    const frameAt = (x) => Math.min(N - 1, Math.max(0, Math.floor(x * hz + 1e-6)));
    function seek(x) {
      t = Math.min(Math.max(Number(x) || 0, 0), last);
      render();
    }
    function setPlaying(on) {
      playing = on && t < last;
      if (on && t >= last) { t = 0; playing = true; }
      play.innerHTML = playing ? "&#10074;&#10074;" : "&#9654;";
      lastNow = null;
    }
    play.onclick = () => setPlaying(!playing);
    speedSel.onchange = () => { speed = Number(speedSel.value); };
    const eventTimes = D.events.map((e) => e[0]);
    prev.onclick = () => {
      const k = eventTimes.filter((e) => e < t - 1e-3);
      if (k.length) seek(k[k.length - 1]);
    };
    next.onclick = () => {
      const k = eventTimes.find((e) => e > t + 1e-3);
      if (k !== undefined) seek(k);
    };
    // viser's page toggles its own playback clock with the space bar: the key is taken
    // before it sees it (a focused button or field keeps its own use of the key)
    window.addEventListener("keydown", (e) => {
      if (e.code !== "Space") return;
      e.stopImmediatePropagation();
      const tag = (e.target && e.target.tagName) || "";
      if (/^(INPUT|SELECT|TEXTAREA|BUTTON)$/.test(tag)) return;
      e.preventDefault();
      setPlaying(!playing);
    }, true);

    // -- viser's playback, moved to the frame shown ----------------------------------------
    const setValue = Object.getOwnPropertyDescriptor(HTMLInputElement.prototype, "value").set;
    function viserBar() {
      const s = document.querySelector(".mantine-Slider-root");
      return s ? s.closest(".mantine-Paper-root") : null;
    }
    function viserTime() {
      const b = viserBar();
      const thumb = b && b.querySelector("[role=slider]");
      return thumb ? Number(thumb.getAttribute("aria-valuenow")) : null;
    }
    let hidden = false;
    function syncViser(k) {
      const b = viserBar();
      if (!b) return;
      if (!hidden) {
        b.style.display = "none";
        hidden = true;
        window.dispatchEvent(new Event("resize"));
      }
      const want = (k + 0.5) / hz;  // mid-frame: frame k's messages and none of k+1's
      const now = viserTime();
      if (now !== null && Math.abs(now - want) < 1e-3) return;
      const input = b.querySelector("input.mantine-NumberInput-input");
      if (!input) return;
      setValue.call(input, want.toFixed(4));
      input.dispatchEvent(new Event("input", {bubbles: true}));
    }

    // -- drawing ---------------------------------------------------------------------------
    function sized(canvas) {
      const dpr = window.devicePixelRatio || 1;
      const w = canvas.clientWidth, h = canvas.clientHeight;
      if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
        canvas.width = Math.round(w * dpr);
        canvas.height = Math.round(h * dpr);
      }
      const ctx = canvas.getContext("2d");
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      return [ctx, w, h];
    }

    function drawScrubber() {
      const [ctx, w, h] = sized(scrub);
      if (!w) return;
      const x = (s) => (s / Math.max(last, 1e-9)) * (w - 2) + 1;
      ctx.clearRect(0, 0, w, h);
      ctx.fillStyle = "#eceff1";
      ctx.fillRect(0, 12, w, 16);
      for (const [a, b, colour] of D.bands) {
        ctx.fillStyle = colour;
        ctx.fillRect(x(a), 12, Math.max(x(b) - x(a), 1), 16);
      }
      ctx.fillStyle = "rgba(38,50,56,0.18)";
      ctx.fillRect(0, 26, x(t), 2);
      for (const [s] of D.phases) {
        ctx.fillStyle = "#78909c";
        ctx.fillRect(x(s), 8, 1, 24);
      }
      for (const [s, level] of D.events) {
        ctx.fillStyle = level === "error" ? "#c0392b" : level === "warning" ? "#e67e22" : "#90a4ae";
        ctx.fillRect(x(s) - (level === "info" ? 0.5 : 1), 30, level === "info" ? 1 : 2, 8);
      }
      ctx.fillStyle = "#263238";
      ctx.fillRect(x(t) - 1, 2, 2, 36);
      ctx.fillStyle = "#37474f";
      ctx.font = "10px system-ui,sans-serif";
      ctx.fillText(phaseName(frameAt(t)), Math.min(x(t) + 4, w - 80), 10);
    }

    function phaseName(k) {
      const p = D.phase[k];
      return p >= 0 ? D.phaseNames[p] : "";
    }

    let dragging = false;
    function scrubTo(ev) {
      const r = scrub.getBoundingClientRect();
      seek(((ev.clientX - r.left - 1) / Math.max(r.width - 2, 1)) * last);
    }
    scrub.addEventListener("pointerdown", (ev) => {
      dragging = true;
      scrub.setPointerCapture(ev.pointerId);
      scrubTo(ev);
    });
    scrub.addEventListener("pointermove", (ev) => {
      if (dragging) scrubTo(ev);
      else {
        const r = scrub.getBoundingClientRect();
        const s = ((ev.clientX - r.left) / Math.max(r.width, 1)) * last;
        let best = null;
        for (const e of D.events) {
          if (Math.abs(e[0] - s) < last / 150 && (!best || Math.abs(e[0] - s) <
              Math.abs(best[0] - s))) best = e;
        }
        scrub.title = best ? best[0].toFixed(1) + " s " + best[3] : s.toFixed(1) + " s";
      }
    });
    scrub.addEventListener("pointerup", () => { dragging = false; });

    // charts: each drawn once (per size) into a back buffer; the cursor on top per frame
    const charts = D.charts.map((c) => {
      const box = el("div", {class: "gcs-x-chart", "data-gcs": "export-chart"});
      const legend = c.lines.map((l) => `<span><i style="background:${l.colour}${
        l.dash ? ";height:1px;border-top:2px dashed " + l.colour + ";background:none" : ""
      }"></i>${l.label}</span>`).join("");
      box.innerHTML = `<div class="t">${c.title}</div><div class="gcs-x-legend">${legend}</div>`;
      const canvas = el("canvas");
      box.append(canvas);
      plots.append(box);
      canvas.addEventListener("pointerdown", (ev) => {
        const r = canvas.getBoundingClientRect();
        const m = 44;
        seek(((ev.clientX - r.left - m) / Math.max(r.width - m - 8, 1)) * last);
      });
      return {c, canvas, back: document.createElement("canvas"), key: ""};
    });

    function drawStatic(chart, w, h) {
      const {c, back} = chart;
      const dpr = window.devicePixelRatio || 1;
      back.width = Math.round(w * dpr);
      back.height = Math.round(h * dpr);
      const ctx = back.getContext("2d");
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      const L = 44, R = 8, T = 6, B = 18;
      const ts = c.t.map((v) => v / 1000);
      let lo = Infinity, hi = -Infinity;
      for (const l of c.lines) for (const v of l.y) if (v !== null) {
        lo = Math.min(lo, v / c.scale); hi = Math.max(hi, v / c.scale);
      }
      if (!isFinite(lo)) { lo = 0; hi = 1; }
      if (c.zero) { lo = Math.min(lo, 0); hi = Math.max(hi, 0); }
      if (hi - lo < 1e-6) { hi += 0.5; lo -= 0.5; }
      const pad = (hi - lo) * 0.06;
      lo -= pad; hi += pad;
      const X = (s) => L + (s / Math.max(last, 1e-9)) * (w - L - R);
      const Y = (v) => T + (1 - (v - lo) / (hi - lo)) * (h - T - B);
      ctx.clearRect(0, 0, w, h);
      for (const [a, b, colour] of D.bands) {
        ctx.fillStyle = colour;
        ctx.fillRect(X(a), T, Math.max(X(b) - X(a), 1), h - T - B);
      }
      ctx.strokeStyle = "#eceff1";
      ctx.fillStyle = "#607d8b";
      ctx.font = "10px system-ui,sans-serif";
      ctx.lineWidth = 1;
      const ys = niceStep(hi - lo, 4);
      for (let v = Math.ceil(lo / ys) * ys; v <= hi; v += ys) {
        ctx.beginPath(); ctx.moveTo(L, Y(v)); ctx.lineTo(w - R, Y(v)); ctx.stroke();
        ctx.fillText(fmt(v, ys), 2, Y(v) + 3);
      }
      const xs = niceStep(last, 6);
      for (let s = 0; s <= last + 1e-9; s += xs) {
        ctx.beginPath(); ctx.moveTo(X(s), T); ctx.lineTo(X(s), h - B); ctx.stroke();
        ctx.fillText(fmt(s, xs) + " s", X(s) - 8, h - 5);
      }
      for (const l of c.lines) {
        ctx.strokeStyle = l.colour;
        ctx.lineWidth = l.dash ? 1.2 : 1.5;
        ctx.setLineDash(l.dash ? [6, 4] : []);
        ctx.beginPath();
        let pen = false;
        for (let i = 0; i < ts.length; i++) {
          const v = l.y[i];
          if (v === null) { pen = false; continue; }
          const px = X(ts[i]), py = Y(v / c.scale);
          if (pen) ctx.lineTo(px, py); else ctx.moveTo(px, py);
          pen = true;
        }
        ctx.stroke();
      }
      ctx.setLineDash([]);
      chart.X = X;
    }

    function drawCharts(force) {
      if (plots.style.display === "none") return;
      for (const chart of charts) {
        const [ctx, w, h] = sized(chart.canvas);
        if (!w) continue;
        const key = w + "x" + h + "@" + (window.devicePixelRatio || 1);
        if (force || chart.key !== key) { drawStatic(chart, w, h); chart.key = key; }
        ctx.clearRect(0, 0, w, h);
        ctx.drawImage(chart.back, 0, 0, w, h);
        ctx.fillStyle = "#263238";
        ctx.fillRect(chart.X(t) - 0.75, 6, 1.5, h - 24);
      }
    }

    function showHtml(which, target, k) {
      const i = D.html[which][k];
      if (i !== shownHtml[which]) {
        target.innerHTML = D.html.strings[i];
        shownHtml[which] = i;
      }
    }

    let drawnAt = null, drawnSize = "";
    function render() {
      const k = frameAt(t);
      time.textContent = t.toFixed(2) + " / " + last.toFixed(1) + " s";
      if (k !== shown) {
        showHtml("summary", summary, k);
        showHtml("vehicles", vehicles, k);
        showHtml("events", events, k);
        shown = k;
      }
      syncViser(k);
      // the canvases only when the play head moved or the page's layout changed
      const size = [window.innerWidth, window.innerHeight, window.devicePixelRatio,
        plots.style.display, panel.className].join();
      if (t !== drawnAt || size !== drawnSize) {
        drawScrubber();
        drawCharts(false);
        drawnAt = t;
        drawnSize = size;
      }
    }

    function loop(now) {
      if (playing) {
        if (lastNow !== null) {
          t += ((now - lastNow) / 1000) * speed;
          if (t >= last) { t = last; setPlaying(false); }
        }
        lastNow = now;
      }
      render();
      requestAnimationFrame(loop);
    }

    function state() {
      const k = frameAt(t);
      const positions = [];
      for (let i = 0; i < n; i++) {
        const o = (k * n + i) * 3;
        positions.push([0, 1, 2].map((j) => (D.p[o + j] === null ? null : D.p[o + j] / D.pScale)));
      }
      return {t, frame: k, frameTime: k / hz, ids: D.ids, positions, phase: phaseName(k)};
    }

    window.gcsExport = {
      duration: last, rate: hz,
      seek, play: () => setPlaying(true), pause: () => setPlaying(false),
      time: () => t, playing: () => playing, state, viserTime,
      synced: () => { const v = viserTime(); return v !== null &&
        Math.abs(v - (frameAt(t) + 0.5) / hz) < 1e-3; },
      ready: true,
    };
    requestAnimationFrame(loop);
  }

  load().then(start, (err) => { console.error("gcs export: cannot read the flight: " + err); });
})();
