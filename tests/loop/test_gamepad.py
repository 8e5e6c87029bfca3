"""The gamepad: its YAML mapping, and a real (virtual) SDL joystick driving the operator.

SDL's virtual joysticks (``SDL_JoystickAttachVirtual``, SDL >= 2.0.14) are real
devices to SDL: they are plugged in and out, raise the same hot-plug events and
report axes and buttons through the same calls as a USB pad. They work
headless, so the reader is tested end to end without hardware or mocks.
"""

from __future__ import annotations

import ctypes
import glob
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from gcs.app import free_tcp_port
from gcs.common import ConfigError, from_mapping
from gcs.config import OperatorConfig, load_team
from gcs.loop import Gamepad, OperatorCommand, WallClock, load_gamepad_config
from gcs.loop._gamepad import AXES_RETRY_S, GamepadConfig, GamepadMapper
from tests.support.paths import ROOT
from web._control_lock import ControlLock
from web._launch import default_gamepad

MAPPING = ROOT / "configs" / "gamepad.yaml"
OP = OperatorConfig(deadzone=0.05, expo=0.0, stick_timeout=5.0, altitude_max=4.0)
GUI = load_team(ROOT / "configs" / "bebop_square.yaml").config.guidance


def operator() -> tuple[OperatorCommand, WallClock]:
    clock = WallClock()
    return OperatorCommand(OP, GUI, now=clock.now()), clock


def mapping(**changes: object) -> GamepadConfig:
    raw = {
        "axes": {"forward": {"axis": 4, "invert": True}, "right": {"axis": 3},
                 "rotate": {"axis": 0}, "altitude": {"axis": 1, "invert": True}},
        "buttons": {"scale_up": 5, "scale_down": 4, "guidance_on": 7, "guidance_off": 6,
                    "abort": 1},
    }
    return from_mapping(GamepadConfig, raw | changes, "test")


# -- the mapping ----------------------------------------------------------------------


def test_the_shipped_mapping_loads() -> None:
    config = load_gamepad_config(MAPPING)
    assert config.axes.forward.axis == 4 and config.axes.forward.invert
    assert config.buttons.abort == 1 and config.deadzone == pytest.approx(0.08)


def test_a_wrong_mapping_is_refused_in_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "pad.yaml"
    bad.write_text(MAPPING.read_text().replace("scale_down: 4", "scale_down: 5"))
    with pytest.raises(ConfigError, match="each action needs its own button"):
        load_gamepad_config(bad)
    bad.write_text(MAPPING.read_text().replace("deadzone:", "dead_zone:"))
    with pytest.raises(ConfigError, match=r"pad.yaml: dead_zone: unknown field"):
        load_gamepad_config(bad)
    bad.write_text(MAPPING.read_text().replace("axis: 3}", "axis: -3}"))
    with pytest.raises(ConfigError, match=r"axes.right.axis: must be at least 0"):
        load_gamepad_config(bad)


def test_axes_become_sticks_only_outside_the_deadzone() -> None:
    op, clock = operator()
    op.set_sticks(0.0, 0.7, 0.0, now=clock.now(), source="browser#1")
    pad = GamepadMapper(mapping(), op, clock, on_abort=lambda: None)
    pad.axes([0.02, 0.0, 0.0, -0.03, 0.05, 0.0], dt=0.02)  # a pad at rest
    assert op.snapshot(clock.now()).source == "browser#1"  # not overridden
    pad.axes([0.5, 0.0, 0.0, 0.25, -1.0, 0.0], dt=0.02)
    snap = op.snapshot(clock.now())
    assert snap.source == "gamepad"
    assert (snap.demand.forward, snap.demand.right) == (pytest.approx(1.0), pytest.approx(0.2105,
                                                                                          abs=1e-3))
    assert snap.demand.rotate > 0.4
    pad.axes([0.0] * 6, dt=0.02)  # back to the centre: one zero is written
    assert op.snapshot(clock.now()).demand.forward == 0.0
    op.set_sticks(0.0, -0.6, 0.0, now=clock.now(), source="browser#1")
    pad.axes([0.0] * 6, dt=0.02)
    assert op.snapshot(clock.now()).source == "browser#1"


def test_the_altitude_axis_moves_the_target_at_its_rate() -> None:
    op, clock = operator()
    pad = GamepadMapper(mapping(altitude_rate=0.5), op, clock, on_abort=lambda: None)
    for _ in range(50):
        pad.axes([0.0, -1.0, 0.0, 0.0, 0.0, 0.0], dt=0.02)  # left stick up for 1 s
    assert op.snapshot(clock.now()).altitude_target == pytest.approx(0.5)


def test_buttons_scale_switch_guidance_and_abort() -> None:
    op, clock = operator()
    aborts: list[float] = []
    pad = GamepadMapper(mapping(), op, clock, on_abort=lambda: aborts.append(clock.now()))
    pad.button(5)
    pad.button(5)
    pad.button(4)
    assert op.snapshot(clock.now()).scale_target == pytest.approx(1.05)
    pad.button(6)
    assert not op.snapshot(clock.now()).guidance_on
    pad.button(7)
    assert op.snapshot(clock.now()).guidance_on
    pad.button(2)  # not mapped: nothing
    assert not aborts
    pad.button(1)
    assert len(aborts) == 1


def test_the_pad_steers_only_while_no_browser_holds_control() -> None:
    """One pilot at a time: a viewer holding control silences the pad, except its abort."""
    op, clock = operator()
    lock = ControlLock()
    aborts: list[float] = []
    pad = GamepadMapper(mapping(), op, clock, on_abort=lambda: aborts.append(clock.now()),
                        may_steer=lambda: lock.holder is None)
    pad.axes([0.0, 0.0, 0.0, 0.0, -1.0, 0.0], dt=0.02)  # forward, nobody in a browser holds
    assert op.snapshot(clock.now()).demand.forward == pytest.approx(1.0)

    lock.take(3)  # a viewer takes control while the pad is deflected: centred at once
    pad.axes([0.0, 0.0, 0.0, 0.0, -1.0, 0.0], dt=0.02)
    snap = op.snapshot(clock.now())
    assert snap.demand.forward == 0.0 and snap.source == "gamepad silenced"
    op.set_sticks(0.0, 0.5, 0.0, now=clock.now(), source="browser#3")
    for _ in range(5):  # neither its sticks, altitude, scale nor guidance switch act now
        pad.axes([0.7, -1.0, 0.0, 0.0, -1.0, 0.0], dt=0.02)
    for button in (5, 6):
        pad.button(button)
    snap = op.snapshot(clock.now())
    assert snap.source == "browser#3" and snap.demand.forward == 0.0 and snap.demand.right > 0.4
    assert snap.altitude_target == 0.0 and snap.scale_target == 1.0 and snap.guidance_on
    pad.button(1)  # ... but its abort does, as any viewer's
    assert len(aborts) == 1

    lock.release(3)  # the viewer lets go: the pad steers again
    pad.axes([0.0, 0.0, 0.0, 1.0, 0.0, 0.0], dt=0.02)
    assert op.snapshot(clock.now()).source == "gamepad"
    assert op.snapshot(clock.now()).demand.right == pytest.approx(1.0)


def test_the_resume_button_is_optional_and_has_its_own_number() -> None:
    op, clock = operator()
    resumes: list[float] = []
    pad = GamepadMapper(mapping(), op, clock, on_abort=lambda: None,
                        on_resume=lambda: resumes.append(clock.now()))
    pad.button(3)  # not mapped here
    assert not resumes
    buttons = {"scale_up": 5, "scale_down": 4, "guidance_on": 7, "guidance_off": 6,
               "abort": 1, "resume": 3}
    pad = GamepadMapper(mapping(buttons=buttons), op, clock, on_abort=lambda: None,
                        on_resume=lambda: resumes.append(clock.now()))
    pad.button(3)
    assert len(resumes) == 1
    assert load_gamepad_config(MAPPING).buttons.resume == 3
    with pytest.raises(ValueError, match="each action needs its own button"):
        mapping(buttons=buttons | {"resume": 1})


# -- a virtual SDL joystick -----------------------------------------------------------


def _sdl() -> ctypes.CDLL:
    """The SDL library pygame itself loaded (same process-wide joystick state)."""
    pygame = pytest.importorskip("pygame", reason="the gamepad reader needs pygame")
    base = Path(pygame.__file__).parent
    candidates = [*glob.glob(str(base.parent / "pygame.libs" / "libSDL2-*")),
                  *glob.glob(str(base / ".dylibs" / "libSDL2*")),
                  *glob.glob(str(base / "SDL2.dll"))]
    if not candidates:
        pytest.skip("cannot find the SDL library bundled with pygame")
    sdl = ctypes.CDLL(candidates[0])
    if not hasattr(sdl, "SDL_JoystickAttachVirtual"):
        pytest.skip("pygame's SDL has no virtual joysticks (needs SDL >= 2.0.14)")
    sdl.SDL_JoystickAttachVirtual.restype = ctypes.c_int
    sdl.SDL_JoystickAttachVirtual.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int,
                                              ctypes.c_int]
    sdl.SDL_JoystickOpen.restype = ctypes.c_void_p
    sdl.SDL_JoystickOpen.argtypes = [ctypes.c_int]
    sdl.SDL_JoystickClose.argtypes = [ctypes.c_void_p]
    sdl.SDL_JoystickDetachVirtual.argtypes = [ctypes.c_int]
    sdl.SDL_JoystickSetVirtualAxis.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int16]
    sdl.SDL_JoystickSetVirtualButton.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint8]
    sdl.SDL_NumJoysticks.restype = ctypes.c_int
    return sdl


class VirtualPad:
    """A plugged-in virtual Xbox-like pad: 6 axes, 11 buttons."""

    GAMECONTROLLER = 1  # SDL_JOYSTICK_TYPE_GAMECONTROLLER

    def __init__(self, sdl: ctypes.CDLL) -> None:
        self._sdl = sdl
        self.index = sdl.SDL_JoystickAttachVirtual(self.GAMECONTROLLER, 6, 11, 0)
        assert self.index >= 0, "SDL_JoystickAttachVirtual failed"
        self._handle = sdl.SDL_JoystickOpen(self.index)
        assert self._handle, "SDL_JoystickOpen failed"
        for axis in range(6):
            self.axis(axis, 0.0)

    def axis(self, axis: int, value: float) -> None:
        raw = max(-32768, min(32767, round(value * 32767)))
        assert self._sdl.SDL_JoystickSetVirtualAxis(self._handle, axis, raw) == 0

    def button(self, button: int, down: bool) -> None:
        assert self._sdl.SDL_JoystickSetVirtualButton(self._handle, button, int(down)) == 0

    def unplug(self) -> None:
        self._sdl.SDL_JoystickClose(self._handle)
        self._sdl.SDL_JoystickDetachVirtual(self.index)


@pytest.fixture
def reader() -> Iterator[tuple[Gamepad, OperatorCommand, WallClock, list[float]]]:
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    _sdl()  # skips when there is no pygame/SDL with virtual joysticks
    op, clock = operator()
    aborts: list[float] = []
    pad = Gamepad(load_gamepad_config(MAPPING), op, clock,
                  on_abort=lambda: aborts.append(clock.now()))
    pad.start()
    try:
        yield pad, op, clock, aborts
    finally:
        pad.close()


def eventually(check: Callable[[], bool], what: str, timeout: float = 3.0) -> None:
    deadline = time.monotonic() + timeout
    while not check():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


def test_no_pad_is_harmless(reader) -> None:  # type: ignore[no-untyped-def]
    pad, op, clock, aborts = reader
    time.sleep(0.3)
    snap = op.snapshot(clock.now())
    assert pad.name is None and snap.source == "none" and not aborts


def test_a_plugged_pad_flies_and_unplugging_it_centres_the_sticks(reader) -> None:  # type: ignore[no-untyped-def]
    pad, op, clock, aborts = reader
    sdl = _sdl()
    device = VirtualPad(sdl)
    try:
        eventually(lambda: pad.name is not None, "the pad to be picked up")
        device.axis(4, -1.0)  # right stick up: forward
        device.axis(0, 0.6)  # left stick right: clockwise
        eventually(lambda: op.snapshot(clock.now()).demand.forward > 0.99, "forward")
        snap = op.snapshot(clock.now())
        assert snap.source == "gamepad" and snap.demand.rotate > 0.5
        device.button(5, True)  # RB: grow (held a moment, as a finger does)
        eventually(lambda: op.snapshot(clock.now()).scale_target > 1.0, "scale step")
        device.button(5, False)
        time.sleep(0.1)
        assert op.snapshot(clock.now()).scale_target == pytest.approx(1.05)  # one step
        device.button(1, True)  # B: abort
        eventually(lambda: bool(aborts), "abort")
    finally:
        device.unplug()
    eventually(lambda: pad.name is None, "the pad to be gone")
    snap = op.snapshot(clock.now())
    assert snap.demand.forward == 0.0 and snap.source == "gamepad unplugged"

    again = VirtualPad(sdl)  # plugged back in: picked up again
    try:
        eventually(lambda: pad.name is not None, "the pad to come back")
        again.axis(3, 1.0)  # right stick right
        eventually(lambda: op.snapshot(clock.now()).demand.right > 0.99, "right")
    finally:
        again.unplug()


class Failing:
    """Raises ``exc`` the first ``times`` calls, then behaves as ``inner`` (if any)."""

    def __init__(self, exc: Exception, times: int = 1,
                 inner: Callable[..., object] = lambda *_a, **_k: None) -> None:
        self.exc, self.left, self.inner, self.calls = exc, times, inner, 0

    def __call__(self, *args: object, **kwargs: object) -> object:
        self.calls += 1
        if self.left > 0:
            self.left -= 1
            raise self.exc
        return self.inner(*args, **kwargs)


def faulty_axes(pygame, check: Callable[[int], object]) -> Callable[[int], object]:  # type: ignore[no-untyped-def]
    """pygame's real Joystick class, but every axis read first calls ``check(axis)``,
    which may raise (as a pad's failing axis read does)."""
    real_joystick = pygame.joystick.Joystick

    class Joystick:
        def __init__(self, index: int) -> None:
            self._real = real_joystick(index)

        def get_axis(self, axis: int) -> float:
            check(axis)
            return float(self._real.get_axis(axis))

        def __getattr__(self, name: str) -> object:
            return getattr(self._real, name)

    return Joystick


def test_a_failing_callback_or_pygame_call_does_not_end_the_reader(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The abort callback, pygame's event queue and an axis read each raise once: every
    fault is reported once, and the pad still steers and aborts afterwards."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    sdl = _sdl()
    import pygame

    op, clock = operator()
    aborts: list[float] = []
    faults: list[str] = []
    on_abort = Failing(RuntimeError("link down"), times=2,
                       inner=lambda: aborts.append(clock.now()))
    pad = Gamepad(load_gamepad_config(MAPPING), op, clock, on_abort=on_abort,
                  on_fault=faults.append)
    pad.start()
    device = VirtualPad(sdl)
    try:
        eventually(lambda: pad.name is not None, "the pad to be picked up")
        for _ in range(3):  # B three times: the first two aborts raise, the third gets through
            device.button(1, True)
            calls = on_abort.calls
            eventually(lambda c=calls: on_abort.calls > c, "the abort callback")
            device.button(1, False)
            time.sleep(0.1)  # a few polls: SDL sees the release before the next press
        assert len(aborts) == 1
        assert faults == ["gamepad: handling JoyButtonDown failed: RuntimeError: link down"]

        broken = Failing(pygame.error("event queue broke"), inner=pygame.event.get)
        monkeypatch.setattr(pygame.event, "get", broken)
        eventually(lambda: broken.calls > 2, "the reader to poll past the fault")
        assert faults[-1] == "gamepad: reading events failed: error: event queue broke"

        axis_fault = Failing(pygame.error("device gone"), inner=None)  # type: ignore[arg-type]
        monkeypatch.setattr(pygame.joystick, "Joystick", faulty_axes(
            pygame, lambda axis: axis_fault(axis) if axis_fault.left > 0 else None))
        device.unplug()  # plugged back in: opened through the faulty wrapper (fails once)
        eventually(lambda: pad.name is None, "the pad to be gone")
        device = VirtualPad(sdl)
        eventually(lambda: axis_fault.calls == 1, "the failing axis read")
        device.axis(4, -1.0)  # forward: read once the pad is taken back
        eventually(lambda: op.snapshot(clock.now()).demand.forward > 0.99, "forward after "
                   "the axis fault")
        assert faults[-1] == "gamepad: reading the axes failed: error: device gone"
        assert len(faults) == 3 and pad.faults == 4  # the abort's twice, reported once
        device.button(1, True)
        eventually(lambda: len(aborts) == 2, "the abort after all three faults")
    finally:
        device.unplug()
        pad.close()


def test_a_pad_whose_axes_keep_failing_still_aborts(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every axis read raises: the sticks it held are centred, the fault is reported once
    (and retried once a second, not every poll), and its buttons, the abort's first, still
    act; once the axes read again, it steers."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    sdl = _sdl()
    import pygame

    broken = threading.Event()

    def check(_axis: int) -> None:
        if broken.is_set():
            raise pygame.error("axis read failed")

    monkeypatch.setattr(pygame.joystick, "Joystick", faulty_axes(pygame, check))
    op, clock = operator()
    aborts: list[float] = []
    faults: list[str] = []
    pad = Gamepad(load_gamepad_config(MAPPING), op, clock,
                  on_abort=lambda: aborts.append(clock.now()), on_fault=faults.append)
    pad.start()
    device = VirtualPad(sdl)
    try:
        eventually(lambda: pad.name is not None, "the pad to be picked up")
        device.axis(4, -1.0)  # forward
        eventually(lambda: op.snapshot(clock.now()).demand.forward > 0.99, "forward")
        broken.set()
        since = time.monotonic()
        eventually(lambda: op.snapshot(clock.now()).source == "gamepad axes failing",
                   "the sticks centred")
        assert op.snapshot(clock.now()).demand.forward == 0.0
        for presses in (1, 2, 3):  # B, pressed and released three times: three aborts
            device.button(1, True)
            eventually(lambda n=presses: len(aborts) == n, f"abort {presses}")
            device.button(1, False)
            time.sleep(0.1)  # a few polls: SDL sees the release before the next press
        device.button(5, True)  # RB: grow, as the other buttons
        eventually(lambda: op.snapshot(clock.now()).scale_target > 1.0, "scale step")
        device.button(5, False)
        assert pad.name is not None
        assert faults == ["gamepad: reading the axes failed: error: axis read failed"]
        assert pad.faults <= 2 + (time.monotonic() - since) / AXES_RETRY_S, pad.faults
        broken.clear()
        eventually(lambda: op.snapshot(clock.now()).demand.forward > 0.99,
                   "forward once the axes read again", timeout=AXES_RETRY_S + 3.0)
    finally:
        device.unplug()
        pad.close()


def test_the_default_mapping_is_found_from_any_directory(tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert default_gamepad() == MAPPING  # the shipped one, beside the package
    own = tmp_path / "configs" / "gamepad.yaml"
    own.parent.mkdir()
    own.write_text(MAPPING.read_text())
    assert default_gamepad().resolve() == own  # a project's own mapping wins, as the team's


def test_a_gcs_started_elsewhere_reads_the_pad(tmp_path: Path) -> None:
    """From a directory without configs/, the shipped mapping is still read.

    ``gcs run`` (no vehicles: its zenoh connects nowhere) rather than ``gcs demo``:
    both start the reader the same way (``web._launch.serve``), and run needs no simulator.
    """
    _sdl()  # skips without pygame's SDL
    config = ROOT / "configs" / "bebop_square.yaml"
    team = tmp_path / "team.yaml"
    team.write_text(config.read_text().replace("airframe: airframes/",
                                               f"airframe: {config.parent / 'airframes'}/")
                    + "\ngcs:\n  zenoh: {mode: peer, connect: []}\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    proc = subprocess.Popen(
        [sys.executable, "-m", "gcs", "run", "--config", str(team), "--port",
         str(free_tcp_port())], cwd=elsewhere, stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1", "SDL_VIDEODRIVER": "dummy"})
    lines: list[str] = []
    try:
        assert proc.stdout is not None
        deadline = time.monotonic() + 60.0
        while not any(re.match(r"gamepad: |GCS page: ", line) for line in lines):
            assert time.monotonic() < deadline, "".join(lines)
            line = proc.stdout.readline()
            assert line, f"gcs run exited: {''.join(lines)}"
            lines.append(line)
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)
    said = next(line for line in lines if line.startswith("gamepad: "))
    assert said.startswith(f"gamepad: mapping {MAPPING};"), said
