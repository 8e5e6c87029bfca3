"""A gamepad on the GCS side: sticks, altitude, scale, guidance switch, abort and resume.

The paper's operator flew the team with a gamepad; here it is read through
pygame/SDL on the GCS machine and written to the same
:class:`~gcs.loop.OperatorCommand` as the browser (source ``"gamepad"``).
The mapping from SDL axis and button numbers is a YAML file
(``configs/gamepad.yaml``), so any pad works without code changes.

* Harmless when no pad is present: SDL runs with the dummy video driver (no
  window) and the thread just waits for one to be plugged in.
* Hot-plug tolerant: a pad can come and go at any time; when the pad in use
  goes away while steering, the sticks are centred at once.
* A pad at rest does not fight other sources: sticks inside the deadzone are
  not written (one zero is written when they come back to the centre).
* One pilot at a time: the pad is the pilot's control at the GCS machine and
  steers (sticks, altitude, scale, guidance, resume) only while ``may_steer()``
  says so; ``gcs demo``/``gcs run`` allow it while no browser holds control
  (web/README.md). Taking control in a browser silences the pad and centres
  sticks it held deflected; the abort button works always, as in every browser.
* Fault tolerant: an exception from pygame or from a callback (the abort's
  included) is reported once per distinct fault (``on_fault``, e.g. the page's
  events, and the log) and the thread reads on. A pad whose axes cannot be
  read has its sticks centred but is kept, buttons and all: its axes are
  tried again every :data:`AXES_RETRY_S` (dropping the pad instead would throw
  away every button press, the abort's included, while it is being reopened).
  One bad event must not leave the pilot without the abort button for the
  rest of the flight.
"""

from __future__ import annotations

import logging
import os
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from gcs.common import field, from_mapping, join_thread, load_yaml
from gcs.loop._clock import Clock
from gcs.loop._operator import OperatorCommand

__all__ = [
    "AXES_RETRY_S",
    "MAX_FAULTS_REPORTED",
    "AxisMap",
    "Gamepad",
    "GamepadAxes",
    "GamepadButtons",
    "GamepadConfig",
    "GamepadMapper",
    "load_gamepad_config",
]

_log = logging.getLogger(__name__)

SOURCE = "gamepad"


@dataclass(frozen=True)
class AxisMap:
    """One SDL joystick axis."""

    axis: int = field(doc="SDL axis number", ge=0)
    invert: bool = field(doc="flip the sign (SDL reports a stick pushed up as negative)",
                         default=False)

    def read(self, axes: Sequence[float]) -> float:
        """The axis value in [-1, 1] (0 if the pad has fewer axes)."""
        if self.axis >= len(axes):
            return 0.0
        value = max(-1.0, min(1.0, float(axes[self.axis])))
        return -value if self.invert else value


@dataclass(frozen=True)
class GamepadAxes:
    """Which axis moves what (positive: forward, right, clockwise from above, up)."""

    forward: AxisMap = field(doc="translation along the team's forward axis")
    right: AxisMap = field(doc="translation to the team's right")
    rotate: AxisMap = field(doc="rotation about the centroid, positive clockwise from above")
    altitude: AxisMap = field(doc="climb (positive) or descend")


@dataclass(frozen=True)
class GamepadButtons:
    """Which SDL button number does what."""

    scale_up: int = field(doc="grow the shape by one step", ge=0)
    scale_down: int = field(doc="shrink the shape by one step", ge=0)
    guidance_on: int = field(doc="switch the formation motion on", ge=0)
    guidance_off: int = field(doc="switch the formation motion off (the team holds)", ge=0)
    abort: int = field(doc="abort: freeze the motion, hold, then land", ge=0)
    resume: int | None = field(doc="resume: switch the vehicles that left offboard back to it "
                                   "(none: no button)", default=None, ge=0)


@dataclass(frozen=True)
class GamepadConfig:
    """The pad's mapping; see configs/gamepad.yaml."""

    axes: GamepadAxes = field(doc="axis mapping")
    buttons: GamepadButtons = field(doc="button mapping")
    deadzone: float = field(doc="axis values within this of the centre count as released",
                            default=0.08, ge=0.0, lt=1.0)
    altitude_rate: float = field(doc="altitude target rate at full deflection, m/s",
                                 default=0.3, gt=0.0)
    poll_hz: float = field(doc="how often the pad is read, Hz", default=50.0, gt=0.0, le=500.0)
    device: str = field(doc="use the first pad whose name contains this (empty: any pad)",
                        default="")

    def __post_init__(self) -> None:
        b = self.buttons
        numbers = [b.scale_up, b.scale_down, b.guidance_on, b.guidance_off, b.abort]
        numbers += [b.resume] if b.resume is not None else []
        if len(set(numbers)) != len(numbers):
            raise ValueError(f"buttons: each action needs its own button, got {numbers}")


def load_gamepad_config(path: str | Path) -> GamepadConfig:
    """Load and validate a gamepad mapping; ConfigError (one line) on any mistake."""
    return from_mapping(GamepadConfig, load_yaml(path), str(path))


class GamepadMapper:
    """Turns the pad's axes and button presses into operator commands (no SDL here).

    Args:
        config: the mapping.
        operator: where the commands go.
        clock: the loop's clock.
        on_abort: called when the abort button is pressed (whoever holds control).
        on_resume: called when the resume button (if mapped) is pressed.
        may_steer: whether the pad may steer now (default: always).
    """

    def __init__(self, config: GamepadConfig, operator: OperatorCommand, clock: Clock, *,
                 on_abort: Callable[[], None],
                 on_resume: Callable[[], None] = lambda: None,
                 may_steer: Callable[[], bool] = lambda: True) -> None:
        self.config = config
        self._operator = operator
        self._clock = clock
        self._on_abort = on_abort
        self._on_resume = on_resume
        self._may_steer = may_steer
        self._active = False

    def _steers(self) -> bool:
        """True if the pad may steer; centres the sticks it held when it just lost the right."""
        if self._may_steer():
            return True
        if self._active:
            now = self._clock.now()
            if self._operator.snapshot(now).source == SOURCE:  # not the new pilot's sticks
                self._operator.release(now=now, source=f"{SOURCE} silenced")
            self._active = False
        return False

    def _centred(self, value: float) -> float:
        return 0.0 if abs(value) <= self.config.deadzone else value

    def axes(self, axes: Sequence[float], dt: float) -> None:
        """Apply the axes held for ``dt`` seconds (nothing while the pad may not steer)."""
        if not self._steers():
            return
        a = self.config.axes
        now = self._clock.now()
        sticks = tuple(self._centred(m.read(axes)) for m in (a.forward, a.right, a.rotate))
        if any(sticks) or self._active:
            self._operator.set_sticks(*sticks, now=now, source=SOURCE)
        self._active = any(sticks)
        climb = self._centred(a.altitude.read(axes))
        if climb:
            target = self._operator.snapshot(now).altitude_target
            self._operator.set_altitude(target + climb * self.config.altitude_rate * dt, now=now)

    def button(self, number: int) -> None:
        """Act on a button press (only the abort while the pad may not steer)."""
        b = self.config.buttons
        if number == b.abort:
            self._on_abort()
        elif not self._steers():
            return
        elif number == b.resume:
            self._on_resume()
        elif number == b.scale_up:
            self._operator.step_scale(1)
        elif number == b.scale_down:
            self._operator.step_scale(-1)
        elif number == b.guidance_on:
            self._operator.set_guidance(True)
        elif number == b.guidance_off:
            self._operator.set_guidance(False)

    def lost(self, why: str = "unplugged") -> None:
        """The pad (or its axes: ``why``) went away: centre the sticks if it was steering."""
        if self._active:
            self._operator.release(now=self._clock.now(), source=f"{SOURCE} {why}")
            self._active = False


MAX_FAULTS_REPORTED = 20
"""Distinct faults reported per reader; past this they are counted only (a fault that
changes its text every poll must not flood the page's events or the log)."""

AXES_RETRY_S = 1.0
"""After the axes failed to read, how long the reader leaves them before it tries again, s
(the buttons are read meanwhile; a pad whose axes always fail is one fault a second)."""


class Gamepad:
    """Reads the pad on its own thread; ``start()`` then ``close()``.

    SDL is set up on that thread with no window (``SDL_VIDEODRIVER=dummy``
    unless set) and background joystick events allowed.

    Args:
        config: the mapping.
        operator: where the commands go.
        clock: the loop's clock.
        on_abort: called when the abort button is pressed (on the pad's thread).
        on_resume: called when the resume button (if mapped) is pressed (same thread).
        may_steer: whether the pad may steer now (asked on the pad's thread).
        on_fault: told (one line, pad's thread) the first time each distinct fault
            happens; the thread goes on reading. The default only logs.
    """

    def __init__(self, config: GamepadConfig, operator: OperatorCommand, clock: Clock, *,
                 on_abort: Callable[[], None],
                 on_resume: Callable[[], None] = lambda: None,
                 may_steer: Callable[[], bool] = lambda: True,
                 on_fault: Callable[[str], None] = lambda _text: None) -> None:
        self.mapper = GamepadMapper(config, operator, clock, on_abort=on_abort,
                                    on_resume=on_resume, may_steer=may_steer)
        self._config = config
        self._on_fault = on_fault
        self._reported: set[str] = set()
        self.faults = 0
        """Exceptions caught on the pad's thread so far (each distinct one reported once)."""
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._error: str | None = None
        self._thread = threading.Thread(target=self._run, daemon=True, name="gamepad")
        self._pad = None  # the pygame Joystick in use
        self._pad_id = -1
        self._axes_retry_at: float | None = None  # monotonic; set while the axes fail
        self.name: str | None = None
        """Name of the pad in use, None while there is none."""

    def start(self, *, timeout: float = 5.0) -> None:
        """Start reading; returns once SDL is up (RuntimeError if it cannot start)."""
        self._thread.start()
        if not self._ready.wait(timeout) or self._error is not None:
            raise RuntimeError(f"gamepad: SDL did not start: {self._error or 'timed out'}")

    def close(self) -> None:
        """Stop reading; idempotent."""
        self._stop.set()
        join_thread(self._thread, 2.0, what="the gamepad reader")

    def _run(self) -> None:
        os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        os.environ.setdefault("SDL_JOYSTICK_ALLOW_BACKGROUND_EVENTS", "1")
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        try:
            import pygame

            pygame.display.init()
            pygame.joystick.init()
        except Exception as exc:  # no pygame, or SDL cannot start: say so in start()
            self._error = f"{type(exc).__name__}: {exc}"
            self._ready.set()
            return
        self._ready.set()
        period = 1.0 / self._config.poll_hz
        try:
            while not self._stop.wait(period):
                self._poll(pygame, period)
        finally:
            pygame.joystick.quit()
            pygame.display.quit()

    def _poll(self, pygame: ModuleType, period: float) -> None:
        """One read of the pad; every step guarded on its own, so a fault in one event
        (or in the axes) neither ends the thread nor drops the other events."""
        try:
            events = pygame.event.get()
        except Exception as exc:
            self._fault("reading events", exc)
            events = []
        for event in events:
            try:
                self._event(pygame, event)
            except Exception as exc:
                self._fault(f"handling {_event_name(pygame, event)}", exc)
        pad = self._pad
        now = time.monotonic()
        if pad is None or (self._axes_retry_at is not None and now < self._axes_retry_at):
            return
        try:
            axes = [pad.get_axis(k) for k in range(pad.get_numaxes())]
        except Exception as exc:  # sticks centred, the pad and its buttons kept
            self._fault("reading the axes", exc)
            if self._axes_retry_at is None:
                self._centre("axes failing")
            self._axes_retry_at = now + AXES_RETRY_S
            return
        self._axes_retry_at = None
        try:
            self.mapper.axes(axes, period)
        except Exception as exc:
            self._fault("applying the axes", exc)

    def _fault(self, doing: str, exc: Exception) -> None:
        """Report an exception once per distinct text (log and ``on_fault``); never raises."""
        self.faults += 1
        text = f"gamepad: {doing} failed: {type(exc).__name__}: {exc}"
        if text in self._reported or len(self._reported) >= MAX_FAULTS_REPORTED:
            return
        self._reported.add(text)
        _log.warning("%s (the gamepad reads on)", text, exc_info=exc)
        try:
            self._on_fault(text)
        except Exception:  # a broken reporter must not end the thread either
            _log.exception("gamepad: reporting a fault failed")

    def _drop_pad(self) -> None:
        """Forget the pad in use and centre its sticks."""
        self._pad, self._pad_id, self.name = None, -1, None
        self._centre("unplugged")

    def _centre(self, why: str) -> None:
        """Centre the sticks the pad held (``why``: the source shown); never raises."""
        try:
            self.mapper.lost(why)
        except Exception as exc:
            self._fault("centring the sticks", exc)

    def _event(self, pygame: ModuleType, event: Any) -> None:
        if event.type == pygame.JOYDEVICEADDED and self._pad is None:
            self._open(pygame, event.device_index)
        elif event.type == pygame.JOYDEVICEREMOVED and event.instance_id == self._pad_id:
            _log.warning("gamepad %s unplugged", self.name)
            self._drop_pad()
            self._reopen(pygame)
        elif event.type == pygame.JOYBUTTONDOWN and event.instance_id == self._pad_id:
            self.mapper.button(event.button)

    def _reopen(self, pygame: ModuleType) -> None:
        """Use the first pad still plugged in that matches the config, if any."""
        for index in range(pygame.joystick.get_count()):
            if self._open(pygame, index):
                return

    def _open(self, pygame: ModuleType, index: int) -> bool:
        """Use joystick ``index`` if its name matches the config."""
        pad = pygame.joystick.Joystick(index)
        if self._config.device and self._config.device not in pad.get_name():
            return False
        pad.init()
        self._pad, self._pad_id, self.name = pad, pad.get_instance_id(), pad.get_name()
        self._axes_retry_at = None  # a new pad: read its axes at once
        _log.info("gamepad %s: %d axes, %d buttons", self.name, pad.get_numaxes(),
                  pad.get_numbuttons())
        return True


def _event_name(pygame: ModuleType, event: Any) -> str:
    """The SDL event's name for a fault message (its number if pygame cannot name it)."""
    try:
        return str(pygame.event.event_name(event.type))
    except Exception:
        return f"event {getattr(event, 'type', '?')}"
