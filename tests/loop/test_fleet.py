"""The fleet table: real links over UDP write each vehicle's telemetry into its row."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.link._profiles import make_profile
from gcs.loop import FleetTable
from gcs.wire import SimMode
from tests.support.links import Rig, heartbeat, make_rig


@pytest.fixture
def rigs() -> Iterator[list[Rig]]:
    made = [make_rig() for _ in range(2)]
    yield made
    for r in made:
        r.link.close()
        r.sock.close()


def position(rig: Rig, x: float, y: float, z: float, vx: float = 0.0) -> bytes:
    return rig.encode(rig.vehicle.mav.local_position_ned_encode(10, x, y, z, vx, 0.0, 0.0))


def wait_until(condition: object, what: str) -> None:
    deadline = time.monotonic() + 3.0
    while not condition():  # type: ignore[operator]
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.005)


def test_rows_follow_each_vehicles_telemetry(rigs: list[Rig]) -> None:
    first, second = rigs
    # Links here all talk to system id 1; the table only cares about formation order.
    profiles = {7: make_profile("sim", first.link), 9: make_profile("sim", second.link)}
    # What arrived before the table existed is in it too.
    first.send(position(first, 1.0, 2.0, -3.0, vx=0.5))
    first.wait(lambda t: t.position is not None, "first position")
    table = FleetTable((7, 9), profiles)
    state = table.read(time.monotonic())
    np.testing.assert_allclose(state.p_ned[0], [1.0, 2.0, -3.0])
    assert state.v_ned[0, 0] == pytest.approx(0.5)
    assert np.all(np.isnan(state.p_ned[1])) and math.isinf(state.age[1])
    assert state.modes == ("unknown", "unknown") and not state.armed.any()
    assert np.isnan(state.tilt).all() and np.all(state.yaw == 0.0)
    assert not state.located  # vehicle 9 never reported: the loop holds still

    second.send(position(second, -1.0, 0.5, -2.0),
                heartbeat(second, armed=True, custom_mode=SimMode.OFFBOARD),
                second.encode(second.vehicle.mav.attitude_encode(10, 0.1, 0.2, 1.5, 0, 0, 0)))
    wait_until(lambda: table.read(time.monotonic()).modes[1] == "OFFBOARD", "vehicle 9's mode")
    wait_until(lambda: np.isfinite(table.read(time.monotonic()).tilt[1]), "vehicle 9's attitude")
    now = time.monotonic()
    state = table.read(now)
    np.testing.assert_allclose(state.p_ned[1], [-1.0, 0.5, -2.0])
    assert state.armed.tolist() == [False, True]
    assert state.located
    assert state.yaw[1] == pytest.approx(1.5, abs=1e-6)
    assert state.tilt[1] == pytest.approx(math.acos(math.cos(0.1) * math.cos(0.2)), abs=1e-6)
    assert 0.0 <= state.age[1] < 1.0 and 0.0 <= state.heartbeat_age[1] < 1.0
    assert math.isinf(state.heartbeat_age[0])
    # a later reading ages, a newer message refreshes only its own vehicle
    assert table.read(now + 2.0).age[1] == pytest.approx(state.age[1] + 2.0)
    first.send(position(first, 4.0, 4.0, -4.0))
    wait_until(lambda: table.read(time.monotonic()).p_ned[0, 0] == 4.0, "vehicle 7's update")
    np.testing.assert_allclose(table.read(time.monotonic()).p_ned[1], [-1.0, 0.5, -2.0])


def test_a_read_is_a_copy_that_later_telemetry_does_not_change(rigs: list[Rig]) -> None:
    first, second = rigs
    table = FleetTable((1, 2), {1: make_profile("sim", first.link),
                                2: make_profile("sim", second.link)})
    first.send(position(first, 1.0, 1.0, -1.0))
    wait_until(lambda: table.read(time.monotonic()).p_ned[0, 0] == 1.0, "first position")
    before = table.read(time.monotonic())
    first.send(position(first, 2.0, 1.0, -1.0),
               heartbeat(first, custom_mode=SimMode.HOLD))
    wait_until(lambda: table.read(time.monotonic()).modes[0] == "HOLD", "the mode change")
    assert before.p_ned[0, 0] == 1.0 and before.modes[0] == "unknown"


def test_sys_status_sets_the_battery(rigs: list[Rig]) -> None:
    first, second = rigs
    table = FleetTable((1, 2), {1: make_profile("sim", first.link),
                                2: make_profile("sim", second.link)})
    present = v20.MAV_SYS_STATUS_SENSOR_3D_GYRO
    first.send(first.encode(first.vehicle.mav.sys_status_encode(
        present, present, present, 100, 11800, 150, 64, 0, 0, 0, 0, 0, 0)))
    wait_until(lambda: table.read(time.monotonic()).battery[0] == 64, "the battery")
    assert np.isnan(table.read(time.monotonic()).battery[1])
