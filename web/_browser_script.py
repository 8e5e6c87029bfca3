"""The page's script: hotkeys, virtual sticks and a freshness badge that viser lacks.

viser 1.1.1 offers command hotkeys (key-down only, letters/digits/a few
specials: no ``+``/``-``, no key-up, so no "hold W to fly forward") and
buttons with ``on_hold``, but no joystick. This script adds both:

* hotkeys (:data:`web._browser_input.HOTKEYS`) tracked down *and* up, ignored
  while typing in a text field (not after clicking a checkbox or a button) or
  with Ctrl/Alt/Cmd held; released on window blur;
* two virtual sticks drawn by :func:`pads_html` (a round pad for translation,
  a bar for rotation) that follow the pointer and spring back to the centre
  on release.

It also draws the **always-visible abort**: a fixed button over the page,
above every panel, that no panel's collapse or scroll can hide. It aborts
through viser's command hotkey (``ABORT_HOTKEY`` with ``ABORT_MODIFIER``,
Ctrl+Shift+X), registered for every viewer by :class:`web.WebUi`: the
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
viewer, carries :func:`answer_abort` and :func:`beat`). It is kept in the server's
persistent messages, so viewers connecting later get it too.

The script shows **how old the page's data is**: a small badge above the abort, "data
0.3 s old", that turns red, "STALE — no update for N s", once
:data:`STALE_AFTER_S` passed without news from the GCS. The news is the server's
*beat* (:func:`beat`, about four a second to every viewer, with each loop tick
and at least every :data:`BEAT_PERIOD_S`): the GCS time of the latest tick and
how old that tick was when the beat left. The page adds the time since the beat
arrived (its own clock), so the badge measures what the operator sees, whether
the GCS's loop stalled (the beats say their data is old) or the viewer's
connection did (no beat comes). A beat is applied with the page's other
messages, in its render loop, so a page that stopped applying what it receives
reads as stale too. After :data:`RECONNECT_AFTER_S` without a beat, and with nothing
at all arriving over the socket, the script forces a reconnect (a page the machine held
up, whose render loop has not applied what came meanwhile, keeps its socket: the
display's own late tick is not counted as the server's silence), then again with a
doubling back-off (at most every :data:`RECONNECT_MAX_S`): viser's page keeps its
websocket in a Worker and
retries only once its socket closed, and only while the window has the focus,
so a half-open socket (nothing arrives, nothing closes) or a window in the
background would stay frozen. The script learns the Worker from its messages
(it hooks ``MessageEvent``'s ``data`` getter: viser keeps no other handle) and
posts it viser's own ``retry``, which opens a fresh socket (the server then
replays the page, as for any reconnect); without the Worker it reloads the page,
once the server answers at all.
"""

from __future__ import annotations

import json
import math
from importlib import resources
from typing import Literal

import viser
from viser import _messages as viser_messages

from web._browser_input import HOTKEYS, INPUT_TIMEOUT, STEP_ACTIONS

__all__ = [
    "ABORT_ANSWERS",
    "ABORT_ANSWER_WAIT_MS",
    "ABORT_HOTKEY",
    "ABORT_LABEL",
    "ABORT_MODIFIER",
    "BEAT_PERIOD_S",
    "CHANNEL_LABEL",
    "RECONNECT_AFTER_S",
    "RECONNECT_MAX_S",
    "SEND_PERIOD_MS",
    "STALE_AFTER_S",
    "abort_keys",
    "answer_abort",
    "beat",
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

STALE_AFTER_S = 1.0
"""The badge turns red, "STALE", once the page's data is older than this, s."""

BEAT_PERIOD_S = 0.25
"""The server beats to every viewer with each loop tick (4 Hz) and at least this often, s."""

RECONNECT_AFTER_S = 3.0
"""Without a beat, and with nothing arriving over the socket, for this long the page forces
a reconnect, s (then with a doubling back-off, at most every :data:`RECONNECT_MAX_S`)."""

RECONNECT_MAX_S = 15.0
"""The longest wait between two forced reconnects, s."""

_SCRIPT_FILE = "browser_input.js"
"""The script itself, shipped beside this module as package data."""

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


_BADGE_STYLE = (
    "position:fixed;left:50%;bottom:72px;transform:translateX(-50%);z-index:2147483000;"
    "pointer-events:none;white-space:nowrap;padding:2px 10px;border-radius:10px;"
    "font:12px/1.4 sans-serif;box-shadow:0 1px 4px rgba(0,0,0,0.3);")
"""Centred above the abort (whose top is about 60 px up), over everything like it, never
taking a click; the script sets its colours."""


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
        "fresh": {"stale": STALE_AFTER_S, "reconnect": RECONNECT_AFTER_S,
                  "reconnectMax": RECONNECT_MAX_S, "every": 100, "style": _BADGE_STYLE,
                  "ok": "background:rgba(255,255,255,0.85);color:#37474f;font-weight:400",
                  "bad": "background:#c92a2a;color:#fff;font-weight:700"},
    }
    source = resources.files("web").joinpath(_SCRIPT_FILE).read_text(encoding="utf-8")
    return source.replace("__CONFIG__", json.dumps(config))


def answer_abort(client: viser.ClientHandle, *, accepted: bool) -> None:
    """Tell ``client``'s page the server got its abort (``accepted``, or the phase refused
    it): its overlay button says "ABORT sent" on this answer alone."""
    outcome = json.dumps("sent" if accepted else "refused")
    client._websock_connection.queue_message(  # no public API in viser 1.1.1
        viser_messages.RunJavascriptMessage(
            source=f"window.__gcsInput && window.__gcsInput.abortAnswer({outcome});"))


def beat(client: viser.ClientHandle, *, gcs_time: float | None, age: float) -> None:
    """Tell ``client``'s page the GCS is there: the GCS time of the data the page shows
    (None before the first tick) and how old that data is now, s."""
    t = "null" if gcs_time is None or not math.isfinite(gcs_time) else f"{gcs_time:.3f}"
    client._websock_connection.queue_message(  # no public API in viser 1.1.1
        viser_messages.RunJavascriptMessage(
            source=f"window.__gcsInput && window.__gcsInput.beat({t}, {max(0.0, age):.3f});"))


def install_script(server: viser.ViserServer) -> None:
    """Run the input script in every present and future viewer of ``server``."""
    server.gui._websock_interface.queue_message(  # no public API in viser 1.1.1
        viser_messages.RunJavascriptMessage(source=script_source()))
