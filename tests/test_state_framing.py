"""The bridge's framings (:mod:`sim.state_framing`): states framed as a GO2 and as Unitree's
simulators frame them (recognised as such by the controller's
:func:`~wbc.robot_io.dds.stream_kind.framing_of`), a command held as one torque, the seeded
gaps, and the command slot's Unitree behaviour (no torque before the first command, the last
one held). No DDS, no physics."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from sim.bridge_config import BridgeConfig
from sim.cli.bridge import bridge_config
from sim.cli.parser import build_parser
from sim.command_slot import COMMAND, STAND, CommandSlot
from sim.state_framing import (
    GAP_MAX_S,
    GAP_MIN_S,
    GO2,
    UNITREE_CPP,
    UNITREE_PYTHON,
    StateFraming,
    StateGaps,
)
from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.c_layout import LOW_STATE_DTYPE, crc_ok, zero_record
from wbc.robot_io.dds.low_state_conversion import low_state_from_sensor_record
from wbc.robot_io.dds.stream_kind import framing_of
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sensor_record import SensorRecord


def go2_state() -> np.ndarray:
    sensor = SensorRecord.zeros()
    sensor.tick = 17
    sensor.q[:] = np.linspace(-1.0, 1.0, 12)
    sensor.foot_force[:] = (30.0, 40.0, 50.0, 60.0)
    sensor.imu_quaternion_wxyz[:] = (0.99, 0.1, 0.0, 0.0)
    record = zero_record(LOW_STATE_DTYPE)
    StateFraming(GO2).header(record)
    return low_state_from_sensor_record(sensor, out=record)


@pytest.mark.parametrize("name", [GO2, UNITREE_CPP, UNITREE_PYTHON])
def test_each_framing_is_recognised_as_itself(name):
    record = go2_state()
    framing = StateFraming(name)
    framing.header(record)
    framing.frame(record, sim_time_s=1.2345)
    assert framing_of(record) == (name, "")


def test_unitree_framings_send_what_unitrees_simulators_send():
    cpp, python = go2_state(), go2_state()
    for record, name in ((cpp, UNITREE_CPP), (python, UNITREE_PYTHON)):
        StateFraming(name).header(record)
        StateFraming(name).frame(record, sim_time_s=1.2345)
        assert tuple(record["head"]) == (0, 0) and int(record["level_flag"]) == 0
        assert not record["foot_force"].any() and not record["motor_state"]["mode"].any()
    assert int(cpp["tick"]) == 1234 and crc_ok(cpp)  # simulated milliseconds, a valid CRC
    assert cpp["imu_state"]["rpy"][0] != 0.0
    assert int(python["tick"]) == 0 and int(python["crc"]) == 0
    assert not python["imu_state"]["rpy"].any()
    go2 = go2_state()
    assert tuple(go2["head"]) == (0xFE, 0xEF) and int(go2["level_flag"]) == 0xFF
    assert int(go2["tick"]) == 17 and go2["foot_force"].any()


def test_the_python_peer_turns_a_command_into_one_clipped_torque():
    sim = SimpleNamespace(joint_state=lambda: (np.full(12, 0.5), np.full(12, -1.0)),
                          effort_limit=np.full(12, 20.0))
    command = MotorCommand(q_des=np.full(12, 0.6), dq_des=np.zeros(12), kp=np.full(12, 50.0),
                           kd=np.full(12, 2.0), tau_ff=np.linspace(-30.0, 30.0, 12))
    held = StateFraming(UNITREE_PYTHON).applied(command, sim)
    expected = np.clip(command.tau_ff + 50.0 * 0.1 + 2.0 * 1.0, -20.0, 20.0)
    np.testing.assert_allclose(held.tau_ff, expected)
    assert not held.kp.any() and not held.kd.any()
    assert StateFraming(UNITREE_CPP).applied(command, sim) is command  # its PD every step
    assert StateFraming(UNITREE_PYTHON).applied(None, sim) is None


def test_gaps_are_seeded_and_last_10_to_50_ms():
    def gaps(seed: int) -> list[str]:
        model = StateGaps(seed)
        return [model.at_state(0.005 * k) for k in range(20_000)]  # 100 s at 200 Hz

    first = gaps(0)  # the bridge's default seed
    assert first == gaps(0)
    kinds = np.array(first)
    starts = np.flatnonzero((kinds[1:] != "") & (kinds[:-1] == "")) + 1
    lengths = [np.argmax(kinds[s:] == "") * 0.005 for s in starts]
    assert 100 <= len(starts) <= 300  # 1 % of the states start one
    assert min(lengths) >= GAP_MIN_S - 1e-9 and max(lengths) <= GAP_MAX_S + 0.005
    # A new state between two gaps: never a longer stretch without one than a gap.
    assert (np.diff(np.flatnonzero(kinds == "")) - 1).max() * 0.005 <= GAP_MAX_S + 0.005
    assert {"silent", "frozen"} <= set(first)


def test_a_unitree_slot_applies_no_torque_first_and_holds_the_last_command():
    slot = CommandSlot(None, timeout_s=None)
    first = slot.step(None, now_s=0.0)
    assert slot.mode == STAND and not (first.kp.any() or first.kd.any() or first.tau_ff.any())
    command = MotorCommand(q_des=np.zeros(12), dq_des=np.zeros(12), kp=np.zeros(12),
                           kd=np.zeros(12), tau_ff=np.full(12, 3.0))
    slot.step(command, now_s=1.0)
    assert slot.step(None, now_s=1000.0) is command and slot.mode == COMMAND


@pytest.mark.parametrize("argv, expected", [
    ([], (GO2, 500.0, "standing")),
    (["--framing", "unitree-python"], (UNITREE_PYTHON, 200.0, "lying")),
    (["--framing", "unitree-cpp"], (UNITREE_CPP, 500.0, "lying")),
    (["--framing", "unitree-python", "--rate", "1000", "--pose", "standing"],
     (UNITREE_PYTHON, 1000.0, "standing")),
])
def test_bridge_options_give_each_framing_its_rate_and_start_pose(argv, expected):
    args = build_parser().parse_args(["bridge", *argv])
    config = bridge_config(args)
    assert (config.framing, config.rate_hz, config.pose) == expected


def test_an_unknown_framing_is_refused_with_the_valid_ones():
    with pytest.raises(ConfigurationError, match=r"^framing: expected one of go2, unitree-cpp, "
                                                 r"unitree-python, received 'ros'$"):
        BridgeConfig(framing="ros")
