"""One viewer's control panel: abort, take control, sticks, scale, altitude, phases.

Built per browser (viser's ``client.gui``), so each viewer's controls can be
enabled or greyed out on their own. Every callback checks on the server that
its viewer holds control (the abort excepted): a page that bypasses the
greyed-out controls still cannot steer.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import viser

from gcs.loop import Action, OperatorSnapshot
from web._actions import OperatorActions
from web._browser_input import InputTracker, parse_input
from web._browser_script import ABORT_LABEL, CHANNEL_LABEL, answer_abort, pads_html
from web._camera import ViewControls
from web._control_lock import ControlLock

__all__ = ["HOTKEY_HELP", "PHASE_BUTTONS", "ControlPanel", "abort_for"]

PHASE_BUTTONS: dict[str, Action] = {
    "arm": Action.ARM, "take off": Action.TAKEOFF, "lift": Action.LIFT,
    "set down": Action.SET_DOWN, "land": Action.LAND, "resume": Action.RESUME,
}
_SCALE = ("shrink −", "grow +")
_ALTITUDE = ("down ▼", "up ▲")
_GROUPS = {"scale": (_SCALE, 2.0), "altitude": (_ALTITUDE, 3.0),
           "phase": (tuple(PHASE_BUTTONS), 5.0)}  # label: (buttons, order in the folder)
_GUIDANCE, _HELP = 4.0, 6.0

HOTKEY_HELP = (
    "<small>Keys (while you hold control): **W/S** forward/back, **A/D** left/right, "
    "**Q/E** rotate, **+/−** scale, **PgUp/PgDn** altitude. Drag the pad and the bar; "
    "they spring back when released. **C** centres the view on the team (anyone).</small>")


def _notify(client: viser.ClientHandle, title: str, body: str) -> None:
    """Tell one viewer why its action did nothing."""
    client.add_notification(title, body, color="red", auto_close_seconds=6.0)


def abort_for(client: viser.ClientHandle, actions: OperatorActions) -> None:
    """``client`` asked to abort (any viewer may, control or not): abort, answer its page
    (the overlay says "sent" only then), and tell it why if the phase refuses."""
    why = actions.request(Action.ABORT)
    answer_abort(client, accepted=why is None)
    if why is not None:
        _notify(client, "Abort refused", why)


class ControlPanel:
    """The controls of one connected browser.

    Args:
        client: the viewer.
        actions: what the controls act on.
        lock: who holds control.
        on_control_change: called after this viewer took or released control
            (the UI then refreshes every panel).
    """

    def __init__(self, client: viser.ClientHandle, actions: OperatorActions, lock: ControlLock,
                 *, on_control_change: Callable[[], None]) -> None:
        self.client = client
        self.id = client.client_id
        self.source = f"browser#{self.id}"
        self._actions = actions
        self._lock = lock
        self._changed = on_control_change
        self._tracker = InputTracker()
        self._refreshing = threading.Lock()  # viewers come and go on viser's threads
        gui = client.gui
        self._banner = gui.add_markdown("", order=0)
        self._abort = gui.add_button(ABORT_LABEL, color="red", icon=viser.Icon.ALERT_OCTAGON,
                                     order=1, hint="Any viewer may abort: the team stops, "
                                                   "holds, lands.")
        self._take = gui.add_button("Take control", icon=viser.Icon.STEERING_WHEEL, order=2)
        with gui.add_folder("Fly", order=3) as fly:
            self._pads = gui.add_html(pads_html(enabled=False), order=0)
            self._channel = gui.add_text(CHANNEL_LABEL, "", disabled=True, visible=False, order=1,
                                         hint="What this page sends: held keys, step "
                                              "presses, stick positions.")
            self.guidance = gui.add_checkbox("guidance on", True, disabled=True, order=_GUIDANCE,
                                             hint="Off: the team holds its shape and place.")
            self._guidance_shown: bool | None = None  # the operator's, as last synced
            gui.add_markdown(HOTKEY_HELP, order=_HELP)
        self._fly = fly
        self._groups: dict[str, viser.GuiButtonGroupHandle] = {}
        self._add_groups(enabled=False)
        self.view = ViewControls(client, order=4)
        """This viewer's camera: follows the team, centres on it."""
        self._abort.on_click(self._on_abort)
        self._take.on_click(self._on_take)
        self._channel.on_update(self._on_channel)
        self.guidance.on_update(self._on_guidance)

    # -- state ---------------------------------------------------------------------------

    @property
    def holds(self) -> bool:
        return self._lock.holds(self.id)

    def refresh(self) -> None:
        """Show who holds control; enable or grey out the controls accordingly."""
        holder = self._lock.holder
        mine = holder == self.id
        if mine:
            text = "**You hold control.**"
        elif holder is None:
            text = "**View only.** Nobody holds control: *Take control* to fly."
        else:
            text = f"**View only.** Viewer #{holder} holds control."
        with self._refreshing, self.client.atomic():
            self._banner.content = text
            self._take.label = "Release control" if mine else "Take control"
            self._pads.content = pads_html(enabled=mine)
            self._channel.visible = mine
            self.guidance.disabled = not mine
            self._add_groups(enabled=mine)
        if not mine:
            self._tracker.reset()

    def _add_groups(self, *, enabled: bool) -> None:
        """(Re)build the button groups: viser 1.1.1 cannot grey out a group once built."""
        callbacks = {"scale": self._on_scale, "altitude": self._on_altitude,
                     "phase": self._on_phase}
        with self._fly:
            for label, (options, order) in _GROUPS.items():
                old = self._groups.get(label)
                if old is not None:
                    old.remove()
                group = self.client.gui.add_button_group(label, options, disabled=not enabled,
                                                         order=order)
                group.on_click(callbacks[label])
                self._groups[label] = group

    def sticks(self) -> tuple[float, float, float]:
        """(forward, right, rotate) this viewer commands now; zero unless it holds control."""
        if not self.holds:
            return 0.0, 0.0, 0.0
        return self._tracker.sticks(wall=time.monotonic())

    def sync(self, operator: OperatorSnapshot) -> None:
        """Show state another source may have changed (the gamepad switches guidance).

        Written only when the operator's value changed since the last tick, so a tick
        never undoes a click: viser stores a click's value first and runs its callback
        later, on its thread pool, and a tick in between that rewrites the checkbox from
        its older snapshot would make the callback read that value back (guidance stuck
        off).
        """
        if operator.guidance_on != self._guidance_shown:
            self._guidance_shown = operator.guidance_on
            # viser 1.1 defines a method between the getter and setter of ``value``, so
            # mypy sees the property as read-only; the setter exists and is what runs.
            self.guidance.value = operator.guidance_on  # type: ignore[misc]

    def close(self) -> bool:
        """The viewer left: drop control if held (sticks centred); True if it held it."""
        if self._lock.release(self.id):
            self._actions.release(source=f"{self.source} left")
            return True
        return False

    # -- callbacks (viser's thread pool) ------------------------------------------------

    def _mine(self, event: viser.GuiEvent) -> bool:
        return event.client_id == self.id and self.holds

    def abort(self) -> None:
        """This viewer asked to abort (its panel's button, the overlay, the hotkey)."""
        abort_for(self.client, self._actions)

    def _on_abort(self, event: viser.GuiEvent) -> None:
        if event.client_id == self.id:
            self.abort()

    def _on_take(self, event: viser.GuiEvent) -> None:
        if event.client_id != self.id:
            return
        if self.holds:
            self._lock.release(self.id)
            self._actions.release(source=f"{self.source} released control")
        else:
            previous = self._lock.take(self.id)
            if previous is not None:
                self._actions.release(source=f"{self.source} took control")
        self._changed()

    def _on_channel(self, event: viser.GuiEvent) -> None:
        if not self._mine(event):
            return
        inp = parse_input(self._channel.value)
        if inp is None:
            return
        steps = self._tracker.update(inp, wall=time.monotonic())
        if steps.get("grow") or steps.get("shrink"):
            self._actions.step_scale(steps.get("grow", 0) - steps.get("shrink", 0))
        if steps.get("up") or steps.get("down"):
            self._actions.step_altitude(steps.get("up", 0) - steps.get("down", 0))

    def _on_scale(self, event: viser.GuiEvent) -> None:
        if self._mine(event):
            self._actions.step_scale(1 if event.target.value == _SCALE[1] else -1)

    def _on_altitude(self, event: viser.GuiEvent) -> None:
        if self._mine(event):
            self._actions.step_altitude(1 if event.target.value == _ALTITUDE[1] else -1)

    def _on_guidance(self, event: viser.GuiEvent) -> None:
        if self._mine(event):
            self._actions.set_guidance(bool(self.guidance.value))

    def _on_phase(self, event: viser.GuiEvent) -> None:
        if not self._mine(event):
            return
        why = self._actions.request(PHASE_BUTTONS[event.target.value])
        if why is not None:
            _notify(self.client, "Not now", why)
