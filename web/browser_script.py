"""The page's input script: hotkeys and virtual sticks that viser lacks.

viser 1.1.1 offers command hotkeys (key-down only, letters/digits/a few
specials: no ``+``/``-``, no key-up, so no "hold W to fly forward") and
buttons with ``on_hold``, but no joystick. This script adds both:

* hotkeys (:data:`web.browser_input.HOTKEYS`) tracked down *and* up, ignored
  while typing in a text field (not after clicking a checkbox or a button) or
  with Ctrl/Alt/Cmd held; released on window blur;
* two virtual sticks drawn by :data:`PADS_HTML` (a round pad for translation,
  a bar for rotation) that follow the pointer and spring back to the centre
  on release.

It also draws the **always-visible abort**: a fixed button over the page,
above every panel, that no panel's collapse or scroll can hide. It aborts
through viser's command hotkey (``ABORT_HOTKEY`` with ``ABORT_MODIFIER``,
Ctrl+Shift+X), registered for every viewer by :class:`web.ui.WebUi`: the
button dispatches that key press, viser's page sends the command over its
websocket, and the server runs the same abort as the panel's ABORT button
for the viewer it came from (any viewer may abort). A key press rather than
a GUI message because viser's page keeps no handle to send one through once
the control panel is collapsed (its content leaves the page); the hotkey
listener is the page's own, whatever its layout. Pressed on a keyboard, the
same keys abort too: the script takes them (the physical key, so any layout;
auto-repeat ignored) and sends them on as the button does, because viser's
listener (Mantine's ``useHotkeys``) skips key presses in form fields, a
checkbox just clicked included.

The button says "ABORT sent" only when the server answers (:func:`answer_abort`,
for the viewer the abort came from, however it was pressed): while the
websocket is down viser's page drops what it would send, and the button,
above viser's "disconnected" layer, then says "NOT CONNECTED".

It reports through the holder's read-only "browser input" text field, whose
input it sets the way a user's typing would (native value setter plus an
``input`` event), so the line travels over viser's own websocket as an
ordinary GUI update that the server attributes to that client. The script hides
that field's row (``display: none``: React still takes the event), so the
operator never sees it; a viser visibility flag would take it out of the page. A viewer
without control has no such field: the script then leaves the keys alone (W/A/S/D/Q/E
move viser's camera as usual) and the pads do nothing.

The script is shipped with viser's ``RunJavascriptMessage``, the mechanism
``GuiApi.add_plotly`` uses to load plotly.js; viser 1.1.1 has no public call
for it, hence the one private import below (and the same message, sent to one
viewer, carries :func:`answer_abort`). It is kept in the server's persistent
messages, so viewers connecting later get it too.
"""

from __future__ import annotations

import json
from typing import Literal

import viser
from viser import _messages as viser_messages

from web.browser_input import HOTKEYS, INPUT_TIMEOUT, STEP_ACTIONS

__all__ = [
    "ABORT_ANSWERS",
    "ABORT_ANSWER_WAIT_MS",
    "ABORT_HOTKEY",
    "ABORT_LABEL",
    "ABORT_MODIFIER",
    "CHANNEL_LABEL",
    "SEND_PERIOD_MS",
    "abort_keys",
    "answer_abort",
    "install_script",
    "pads_html",
    "script_source",
]

CHANNEL_LABEL = "browser input"
"""Label of the text field the script writes to (matched exactly by the script)."""

SEND_PERIOD_MS = 100
"""At most one line per this period; repeated at this period while anything is held."""

ABORT_LABEL = "ABORT: hold, then land"
"""The abort's name, on the panel's button and in viser's command palette."""

ABORT_HOTKEY: Literal["X"] = "X"
"""The abort command's key (viser command hotkey), pressed with :data:`ABORT_MODIFIER`;
the overlay button presses it, and the script reads it as the physical key ``KeyX``."""

ABORT_MODIFIER: Literal["cmd/ctrl+shift"] = "cmd/ctrl+shift"
"""The abort's modifiers: Ctrl+Shift+X (Cmd+Shift+X on a Mac). Two of them, so that no
stray key aborts a flight."""

ABORT_ANSWERS = {"sent": "ABORT sent", "refused": "ABORT refused", "offline": "NOT CONNECTED"}
"""What the overlay button says after an abort: the server took it, the phase refused it
(the viewer is told why in a notification), or no answer came (nothing was sent)."""

ABORT_ANSWER_WAIT_MS = 2000
"""How long the button waits for the server's answer before it says "NOT CONNECTED"."""

_SCRIPT = r"""
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
})();
"""

_PAD = ("position:relative;flex:none;touch-action:none;user-select:none;cursor:grab;"
        "background:#eef2f5;border:2px solid #90a4ae;box-sizing:border-box;")
_KNOB = ("position:absolute;left:50%;top:50%;width:34px;height:34px;margin:-17px 0 0 -17px;"
         "border-radius:50%;background:#37474f;pointer-events:none;")
_MARK = "position:absolute;font:11px sans-serif;color:#607d8b;pointer-events:none;"


def pads_html(*, enabled: bool) -> str:
    """The two virtual sticks; greyed out and inert when ``enabled`` is False."""
    off = "" if enabled else ' data-gcs-off="1" style="opacity:0.35;filter:grayscale(1)"'
    return (
        f'<div{off}><div style="display:flex;gap:14px;align-items:center;'
        f'justify-content:center;padding:2px 0 8px 0">'
        f'<div data-gcs-pad="move" title="translate: drag (forward up)" '
        f'style="{_PAD}width:124px;height:124px;border-radius:50%">'
        f'<span style="{_MARK}left:50%;top:2px;transform:translateX(-50%)">fwd</span>'
        f'<span style="{_MARK}left:50%;bottom:2px;transform:translateX(-50%)">back</span>'
        f'<span style="{_MARK}left:4px;top:50%;transform:translateY(-50%)">L</span>'
        f'<span style="{_MARK}right:4px;top:50%;transform:translateY(-50%)">R</span>'
        f'<div data-gcs-knob style="{_KNOB}"></div></div>'
        f'<div style="display:flex;flex-direction:column;align-items:center;gap:4px">'
        f'<div data-gcs-pad="turn" title="rotate: drag (right is clockwise)" '
        f'style="{_PAD}width:124px;height:40px;border-radius:20px">'
        f'<span style="{_MARK}left:6px;top:50%;transform:translateY(-50%)">&#8634;</span>'
        f'<span style="{_MARK}right:6px;top:50%;transform:translateY(-50%)">&#8635;</span>'
        f'<div data-gcs-knob style="{_KNOB}"></div></div>'
        f'<span style="font:11px sans-serif;color:#607d8b">rotate</span></div>'
        f'</div></div>'
    )


_ABORT_STYLE = (
    "position:fixed;left:50%;bottom:16px;transform:translateX(-50%);z-index:2147483000;"
    "min-width:132px;padding:10px 22px;border:3px solid #fff;border-radius:10px;"
    "background:#e03131;color:#fff;font:700 18px/1 sans-serif;letter-spacing:1px;"
    "box-shadow:0 2px 10px rgba(0,0,0,0.45);cursor:pointer;touch-action:manipulation;")


def abort_keys() -> str:
    """The abort's keys as a person reads them, e.g. ``Ctrl+Shift+X``."""
    names = {"cmd/ctrl": "Ctrl", "shift": "Shift", "alt": "Alt"}
    return "+".join([*(names[m] for m in ABORT_MODIFIER.split("+")), ABORT_HOTKEY])


def script_source() -> str:
    """The script with its configuration (keys, actions, timing, the abort) filled in."""
    modifiers = ABORT_MODIFIER.split("+")
    config = {
        "channel": CHANNEL_LABEL,
        "keys": dict(HOTKEYS),
        "steps": list(STEP_ACTIONS),
        "period": SEND_PERIOD_MS,
        "linger": int(INPUT_TIMEOUT * 1000),
        "abort": {"key": ABORT_HOTKEY, "code": f"Key{ABORT_HOTKEY}",
                  "ctrl": "cmd/ctrl" in modifiers, "shift": "shift" in modifiers,
                  "alt": "alt" in modifiers, "text": "ABORT", "sending": "ABORT …",
                  "answers": ABORT_ANSWERS, "wait": ABORT_ANSWER_WAIT_MS, "shown": 2500,
                  "aria": "ABORT (always shown): hold, then land",
                  "title": "Abort: the team stops, holds, then lands. Any viewer may; "
                           f"{abort_keys()} does the same.",
                  "style": _ABORT_STYLE},
    }
    return _SCRIPT.replace("__CONFIG__", json.dumps(config))


def answer_abort(client: viser.ClientHandle, *, accepted: bool) -> None:
    """Tell ``client``'s page the server got its abort (``accepted``, or the phase refused
    it): its overlay button says "ABORT sent" on this answer alone."""
    outcome = json.dumps("sent" if accepted else "refused")
    client._websock_connection.queue_message(  # no public API in viser 1.1.1
        viser_messages.RunJavascriptMessage(
            source=f"window.__gcsInput && window.__gcsInput.abortAnswer({outcome});"))


def install_script(server: viser.ViserServer) -> None:
    """Run the input script in every present and future viewer of ``server``."""
    server.gui._websock_interface.queue_message(  # no public API in viser 1.1.1
        viser_messages.RunJavascriptMessage(source=script_source()))
