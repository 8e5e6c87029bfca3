// The page's script: hotkeys, virtual sticks, the always-visible abort and the
// badge saying how old the page's data is.
// Shipped as package data and run in every viewer by web/_browser_script.py, which
// fills in the configuration placeholder (keys, actions, timing, the abort) as JSON.
(() => {
  const CFG = __CONFIG__;
  if (window.__gcsInput) return;
  const st = {held: new Set(), steps: {}, pad: [0, 0], rot: 0, seq: 0, sentAt: 0,
              changedAt: 0, timer: null, drag: null};
  window.__gcsInput = st;
  const setValue = Object.getOwnPropertyDescriptor(HTMLInputElement.prototype, "value").set;

  function channel() {
    for (const label of document.querySelectorAll("label")) {
      if (label.textContent !== CFG.channel) continue;
      let box = label.parentElement;
      while (box && !box.querySelector("input")) box = box.parentElement;
      if (!box) return null;
      box.style.display = "none";  // a channel, not a control: the operator never sees it
      return box.querySelector("input");
    }
    return null;
  }
  const num = (x) => (Math.round(x * 100) / 100).toFixed(2);
  function line() {
    const steps = Object.keys(st.steps).sort().map((k) => k + ":" + st.steps[k]).join(",");
    return "#" + st.seq + " keys=" + [...st.held].sort().join(",") + " steps=" + steps +
      " pad=" + num(st.pad[0]) + "," + num(st.pad[1]) + " rot=" + num(st.rot);
  }
  function flush() {
    st.timer = null;
    const input = channel();
    if (!input) return;
    st.seq += 1;
    st.sentAt = Date.now();
    setValue.call(input, line());
    input.dispatchEvent(new Event("input", {bubbles: true}));
  }
  function schedule() {
    if (st.timer !== null) return;
    st.timer = setTimeout(flush, Math.max(0, st.sentAt + CFG.period - Date.now()));
  }
  function changed() {
    st.changedAt = Date.now();
    schedule();
  }
  setInterval(() => {
    channel();  // hides the field as soon as viser draws it
    const active = st.held.size > 0 || st.pad[0] !== 0 || st.pad[1] !== 0 || st.rot !== 0;
    if (active || Date.now() - st.changedAt < CFG.linger) schedule();
  }, CFG.period);

  // typing fields keep their keys; a focused checkbox or button (just clicked) does not
  const editable = (t) => t && (t.isContentEditable || /^(TEXTAREA|SELECT)$/.test(t.tagName) ||
    (t.tagName === "INPUT" && /^(text|search|number|email|password|tel|url)$/.test(t.type)));
  const keyName = (e) => (e.key.length === 1 ? e.key.toLowerCase() : e.key);
  // the abort's keys: viser's hotkey skips a press in a form field (a clicked checkbox
  // too), so the script sends every real one the way the button does (the physical key:
  // any layout); the button's own synthetic press goes on to viser
  const abortKeys = (e) => e.code === CFG.abort.code && e.shiftKey && (e.ctrlKey || e.metaKey) &&
    !e.altKey;
  window.addEventListener("keydown", (e) => {
    if (!e.isTrusted || !abortKeys(e)) return;
    e.preventDefault();
    e.stopPropagation();
    if (!e.repeat) sendAbort();
  }, true);
  window.addEventListener("keydown", (e) => {
    if (editable(e.target) || e.ctrlKey || e.metaKey || e.altKey) return;
    const action = CFG.keys[keyName(e)];
    if (!action || !channel()) return;
    e.preventDefault();
    e.stopPropagation();
    if (e.repeat) return;
    if (CFG.steps.includes(action)) {
      st.steps[action] = (st.steps[action] || 0) + 1;
      changed();
    } else if (!st.held.has(action)) {
      st.held.add(action);
      changed();
    }
  }, true);
  window.addEventListener("keyup", (e) => {
    const action = CFG.keys[keyName(e)];
    if (action && st.held.delete(action)) {
      e.stopPropagation();
      changed();
    }
  }, true);

  function knob(pad, x, y) {
    const k = pad.querySelector("[data-gcs-knob]");
    const r = pad.getBoundingClientRect();
    const kr = k.getBoundingClientRect();
    k.style.transform = "translate(" + x * (r.width - kr.width) / 2 + "px," +
      y * (r.height - kr.height) / 2 + "px)";
  }
  function centre(pad) {
    knob(pad, 0, 0);
    if (pad.dataset.gcsPad === "move") st.pad = [0, 0]; else st.rot = 0;
    changed();
  }
  function follow(e) {
    const pad = st.drag.pad;
    const r = pad.getBoundingClientRect();
    let x = (e.clientX - r.left - r.width / 2) / (r.width / 2);
    let y = (e.clientY - r.top - r.height / 2) / (r.height / 2);
    if (pad.dataset.gcsPad === "move") {
      const n = Math.hypot(x, y);
      if (n > 1) { x /= n; y /= n; }
      st.pad = [-y, x];
      knob(pad, x, y);
    } else {
      x = Math.max(-1, Math.min(1, x));
      st.rot = x;
      knob(pad, x, 0);
    }
    changed();
  }
  document.addEventListener("pointerdown", (e) => {
    const pad = e.target.closest ? e.target.closest("[data-gcs-pad]") : null;
    if (!pad || pad.closest("[data-gcs-off]") || !channel()) return;
    e.preventDefault();
    try { pad.setPointerCapture(e.pointerId); } catch (err) { /* pointer already gone */ }
    st.drag = {pad: pad, id: e.pointerId};
    follow(e);
  }, true);
  document.addEventListener("pointermove", (e) => {
    if (st.drag && e.pointerId === st.drag.id) follow(e);
  }, true);
  function release(e) {
    if (!st.drag || e.pointerId !== st.drag.id) return;
    const pad = st.drag.pad;
    st.drag = null;
    centre(pad);
  }
  for (const type of ["pointerup", "pointercancel", "lostpointercapture"]) {
    document.addEventListener(type, release, true);
  }
  function letGo() {
    st.held.clear();
    if (st.drag) { const pad = st.drag.pad; st.drag = null; centre(pad); }
    st.pad = [0, 0];
    st.rot = 0;
    changed();
  }
  window.addEventListener("blur", letGo);
  document.addEventListener("visibilitychange", () => { if (document.hidden) letGo(); });

  // the always-visible abort: presses the abort command's hotkey (viser's listener)
  const abort = document.createElement("button");
  abort.type = "button";
  abort.dataset.gcs = "abort";
  abort.textContent = CFG.abort.text;
  abort.title = CFG.abort.title;
  abort.setAttribute("aria-label", CFG.abort.aria);
  abort.style.cssText = CFG.abort.style;
  function show(text, ms) {
    abort.textContent = text;
    clearTimeout(abort.gcsTimer);
    abort.gcsTimer = setTimeout(() => { abort.textContent = CFG.abort.text; }, ms);
  }
  // "sent" only on the server's word (answer_abort): a press while the websocket is
  // down is dropped by viser's page with a line in the console, nothing more
  function answered(outcome) {
    clearTimeout(st.abortWait);
    st.abortWait = null;
    abort.dataset.gcsAnswer = outcome;
    abort.dataset.gcsAnswers = String(Number(abort.dataset.gcsAnswers || 0) + 1);
    show(CFG.abort.answers[outcome], CFG.abort.shown);
  }
  st.abortAnswer = answered;
  function sendAbort() {
    const key = {key: CFG.abort.key, code: CFG.abort.code, ctrlKey: CFG.abort.ctrl,
                 shiftKey: CFG.abort.shift, altKey: CFG.abort.alt, bubbles: true,
                 cancelable: true};
    document.body.dispatchEvent(new KeyboardEvent("keydown", key));
    document.body.dispatchEvent(new KeyboardEvent("keyup", key));
    show(CFG.abort.sending, CFG.abort.wait + CFG.abort.shown);
    clearTimeout(st.abortWait);
    st.abortWait = setTimeout(() => answered("offline"), CFG.abort.wait);
  }
  abort.addEventListener("click", () => {
    abort.blur();  // Space or Enter later must not press it again
    sendAbort();
  });
  document.body.appendChild(abort);

  // how old the page's data is: the server's beat (web._browser_script.beat) brings the
  // GCS time of its latest tick and that tick's age when the beat left; the page adds the
  // time since the beat was applied (by viser's message queue, in the render loop)
  // heard: when the socket last brought anything (the Worker's messages, before the render
  // loop applies them); tick: when the display last ran (a late one: the page itself was
  // held up, by a busy machine, and the socket's news may still be queued behind it)
  const fresh = {at: performance.now(), age: 0, t: null, beats: 0, stale: null,
                 forcedAt: -Infinity, backoff: CFG.fresh.reconnect, reconnects: 0,
                 worker: null, asking: false, due: null, heard: performance.now(),
                 tick: performance.now()};
  st.fresh = fresh;
  const badge = document.createElement("div");
  badge.dataset.gcs = "freshness";
  badge.setAttribute("role", "status");
  document.body.appendChild(badge);
  st.beat = (t, age) => {
    fresh.at = performance.now();
    fresh.age = age;
    fresh.t = t;
    fresh.beats += 1;
    fresh.backoff = CFG.fresh.reconnect;
    badge.dataset.gcsTime = t === null ? "" : String(t);
    freshness();
    clearTimeout(fresh.due);  // turns stale on time, between the display's ticks
    fresh.due = setTimeout(freshness, Math.max(0, 1000 * (CFG.fresh.stale - age)) + 1);
  };
  // viser's page keeps its websocket in a Worker and holds the only handle; the Worker's
  // messages pass through MessageEvent's data getter, where the script meets it
  const getData = Object.getOwnPropertyDescriptor(MessageEvent.prototype, "data");
  if (getData && getData.get && getData.configurable && typeof Worker !== "undefined") {
    Object.defineProperty(MessageEvent.prototype, "data", {
      configurable: true, enumerable: getData.enumerable,
      get() {
        const data = getData.get.call(this);
        if (data && this.target instanceof Worker &&
            /^(message_batch|connected|closed)$/.test(data.type)) {
          fresh.worker = this.target;
          if (data.type === "message_batch") fresh.heard = performance.now();
        }
        return data;
      }});
  }
  // no beat for a while: the socket may be half-open (nothing arrives, nothing closes),
  // or closed in a window without the focus (viser then does not retry): reconnect
  function reconnect() {
    fresh.reconnects += 1;
    badge.dataset.gcsReconnects = String(fresh.reconnects);
    if (fresh.worker) {  // viser's own retry: a fresh socket; the server replays the page
      fresh.worker.postMessage({type: "retry"});
      return;
    }
    if (fresh.asking) return;
    fresh.asking = true;  // no Worker known: reload, but only a page the server serves
    fetch("/__gcs_alive", {cache: "no-store"}).then(() => location.reload(), () => {})
      .finally(() => { fresh.asking = false; });
  }
  const secs = (x) => (x < 10 ? x.toFixed(1) : String(Math.round(x)));
  function freshness() {
    const now = performance.now();
    const held = now - fresh.tick > 1000 * CFG.fresh.stale;  // the page could not run
    fresh.tick = now;
    const silent = (now - fresh.at) / 1000;
    // the socket is given up only when nothing came over it: news the render loop has not
    // applied yet (a busy machine) is no dead socket; nor is the page's own hold-up
    const quiet = Math.min(silent, (now - fresh.heard) / 1000);
    const age = silent + fresh.age;
    const stale = age > CFG.fresh.stale;
    if (stale !== fresh.stale) {
      fresh.stale = stale;
      badge.dataset.gcsState = stale ? "stale" : "fresh";
      badge.dataset[stale ? "gcsStaleAt" : "gcsFreshAt"] = String(Date.now());
      badge.style.cssText = CFG.fresh.style + (stale ? CFG.fresh.bad : CFG.fresh.ok);
    }
    if (!held && quiet > CFG.fresh.reconnect && now - fresh.forcedAt > 1000 * fresh.backoff) {
      fresh.forcedAt = now;
      fresh.backoff = Math.min(2 * fresh.backoff, CFG.fresh.reconnectMax);
      reconnect();
    }
    badge.textContent = !stale ? "data " + age.toFixed(1) + " s old"
      : "STALE — no update for " + secs(age) + " s" +
        (quiet > CFG.fresh.reconnect ? " (reconnecting)" : "");
  }
  freshness();
  setInterval(freshness, CFG.fresh.every);
})();
