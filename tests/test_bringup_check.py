"""The bring-up check (:mod:`actions.robot.bringup_check`, ``go2-wbc check --dds``): what
it finds in synthetic streams framed as a GO2, Unitree's Python simulator and broken robots,
and against the simulator bridge on loopback DDS."""

from __future__ import annotations

import io
import json
import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from actions.robot.bringup_check import (
    GRAVITY_M_S2,
    base_height,
    check_stream,
)
from sim.bridge_config import BridgeConfig
from sim.cli import main
from sim.cli.check import run_check
from sim.cli.parser import build_parser
from sim.dds_bridge import DdsBridge
from sim.state_framing import UNITREE_PYTHON_RATE_HZ
from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES, Go2Description
from wbc.robot_io.dds.c_layout import LEVEL_FLAG_LOW, crc_ok, set_crc
from wbc.robot_io.dds.low_state_conversion import low_state_from_sensor_record
from wbc.robot_io.dds.state_listener import ListenedStream, StateListener
from wbc.robot_io.sensor_record import SensorRecord

DOMAIN_ID = 170 + os.getpid() % 30  # concurrent test runs stay apart
DESCRIPTION = Go2Description.default()
STANDING = DESCRIPTION.pose("standing")[7:]
LYING = DESCRIPTION.pose("lying")[7:]


def _stream(*, count: int = 500, period_s: float = 2e-3, joints: np.ndarray = STANDING,
            framing: str = "go2", feet: float = 110.0, gravity: float = GRAVITY_M_S2,
            gyro_bias: float = 0.0, seed: int = 0, writers: int = 0, commands: int = 0,
            frozen: bool = False) -> ListenedStream:
    """``count`` states of a still robot in ``joints`` (description order), framed as a GO2
    (``go2``: head, level_flag, tick, CRC) or as Unitree's Python simulator (``python``: all
    0, no foot force)."""
    rng = np.random.default_rng(seed)
    records = []
    def noise(sigma: float, size: int) -> np.ndarray:
        return np.zeros(size) if frozen else rng.normal(0.0, sigma, size)

    for k in range(count):
        sample = SensorRecord(
            stamp_s=k * period_s, tick=k + 1, imu_quaternion_wxyz=[1.0, 0.0, 0.0, 0.0],
            gyroscope_rad_s=gyro_bias + noise(0.004, 3),
            accelerometer_m_s2=[0.0, 0.0, gravity] + noise(0.03, 3),
            q=joints + noise(5e-5, 12), dq=noise(0.02, 12),
            tau_est=np.zeros(12),
            foot_force=(feet + noise(3.0, 4) if framing == "go2"
                        else np.zeros(4)))
        record = low_state_from_sensor_record(sample)
        if framing == "python":
            record["head"] = (0, 0)
            record["level_flag"] = 0
            record["tick"] = 0
            record["crc"] = 0
        else:
            record["level_flag"] = LEVEL_FLAG_LOW
            set_crc(record)
        records.append(record)
    times = np.arange(count) * period_s
    return ListenedStream(arrival_s=times, sent_s=times, writers=np.ones(count, np.uint64),
                          records=records, listened_s=count * period_s,
                          state_writers=1, command_writers=writers, commands_seen=commands)


def _text(report) -> str:
    return "\n".join(report.lines())


def test_a_go2_standing_still_passes_with_its_rate_framing_pose_and_imu_at_rest():
    report = check_stream(_stream(gyro_bias=0.003))
    text = _text(report)
    assert report.ok, text
    assert report.figures["rate_hz"] == pytest.approx(500.0)
    assert ("framing   go2 (a GO2 or go2-wbc bridge): head FE EF, CRC checked; a new sample "
            "has a new tick; level_flag 0xFF") in text
    assert "500 new samples, 0 repeat(s), 0 frame(s) dropped" in text
    assert report.figures["posture"] == "standing"
    assert report.figures["base_height_m"] == pytest.approx(0.335, abs=0.01)  # the SRDF pose
    assert report.figures["still"] is True
    # 500 samples of 0.004 rad/s noise: the mean is within 4 sigma/sqrt(n) of the bias.
    np.testing.assert_allclose(report.figures["gyro_bias_rad_s"], 0.003, atol=0.001)
    assert report.figures["gravity_m_s2"] == pytest.approx(GRAVITY_M_S2, abs=0.01)
    assert "nobody else writes rt/lowcmd" in text
    assert report.settings == [
        "foot-force calibration: the default reads the weight within 15% (no option)",
        "stream go2: run --dds recognises it by itself (no option)",
        ("staleness limit: run --dds derives it from the rate at its start (40 ms at 500 Hz: "
         "20 periods or twice the longest gap, 20 to 250 ms)"),
        ("gyroscope bias and gravity in range: the estimator learns the bias as it runs (no "
         "option)")]
    assert text.splitlines()[-5] == "settings to use:"
    # Each foot's static load, the smallest forces that carry the weight: in the SRDF pose,
    # level, the centre of mass is ahead of the feet's centre, so the front feet carry more.
    loads = np.array(report.figures["static_loads_n"])
    assert loads.sum() == pytest.approx(report.figures["weight_n"])
    np.testing.assert_allclose(loads, report.figures["weight_n"] / 4, rtol=0.15)
    assert loads[0] > loads[2] + 5.0 and loads[1] > loads[3] + 5.0


def test_feet_on_another_scale_get_the_gains_that_read_the_weight():
    """Counts 30 + 0.25/N (the issue's foot sensors) read with the default 10 + 2.5/N."""
    weight = DESCRIPTION.total_mass * GRAVITY_M_S2
    report = check_stream(_stream(feet=30.0 + 0.25 * weight / 4))
    assert report.ok
    assert report.figures["weight_read_with_default_n"] == pytest.approx(
        4 * (0.25 * weight / 4 + 20.0) / 2.5, rel=0.02)
    line = report.settings[0]
    assert line.startswith("foot-force calibration: the default reads the weight -")
    assert " off: --set estimator.foot_force_gain=" in line  # the command line's form
    gains = [float(g) for g in line.split("foot_force_gain=")[1].split(" ")[0].split(",")]
    # At offset 10 the gains read each foot's static load from its count.
    loads = np.array(report.figures["static_loads_n"])
    np.testing.assert_allclose(10.0 + np.array(gains) * loads, 30.0 + 0.25 * weight / 4,
                               rtol=0.01)


def test_unitree_python_framing_is_accepted_with_no_crc_no_tick_and_no_foot_force():
    report = check_stream(_stream(framing="python", joints=LYING))
    text = _text(report)
    assert report.ok, text
    assert ("unitree-python (Unitree's Python simulator (unitree_mujoco simulate_python)): "
            "head 00 00, no CRC (sent as 0: not checked); tick not counting") in text
    assert "foot force absent: contact from the schedule only" in text
    assert report.figures["foot_force_absent"] is True
    assert report.figures["posture"] == "lying"
    assert report.figures["base_height_m"] < 0.15


def test_a_frozen_stream_a_wrong_crc_and_joints_out_of_range_are_problems():
    frozen = check_stream(_stream(frozen=True))
    assert not frozen.ok
    assert any("never changes" in f.text for f in frozen.problems)

    stream = _stream()
    stream.records[7]["crc"] ^= 1
    assert not crc_ok(stream.records[7])
    wrong = check_stream(stream)
    assert [f.topic for f in wrong.problems] == ["framing"]
    assert "499 new samples, 0 repeat(s), 1 frame(s) dropped (the last because LowState_.crc:" \
        in wrong.problems[0].text

    joints = STANDING.copy()
    joints[JOINT_NAMES.index("RL_calf_joint")] = 0.5  # a calf bent the wrong way
    bent = check_stream(_stream(joints=joints))
    assert [f.topic for f in bent.problems] == ["joints"]
    assert "outside the GO2's ranges in the SDK's motor order: RL_calf_joint +0.50 rad" in (
        bent.problems[0].text)


def test_gravity_off_scale_a_large_gyro_bias_and_another_commander_are_problems():
    scaled = check_stream(_stream(gravity=0.9 * GRAVITY_M_S2))
    assert [f.topic for f in scaled.problems] == ["imu"]
    assert "gravity 8.826 m/s^2 (-10.0% of 9.80665)" in scaled.problems[0].text
    assert not check_stream(_stream(gyro_bias=0.1)).ok
    commanded = check_stream(_stream(writers=1, commands=40))
    assert [f.topic for f in commanded.problems] == ["commands"]
    assert "1 other writer(s) of rt/lowcmd, 40 command(s) seen" in commanded.problems[0].text


def test_too_few_states_say_no_go2_streams_here():
    report = check_stream(_stream(count=3))
    assert not report.ok
    assert "3 LowState_ in 0.0 s on rt/lowstate (1 writer(s) matched): no GO2 streams here" in (
        report.problems[0].text)


def test_base_height_of_the_named_poses_and_a_tilted_imu():
    assert base_height(STANDING, np.array([1.0, 0, 0, 0]), DESCRIPTION) == pytest.approx(
        0.335, abs=0.01)
    assert base_height(LYING, np.array([1.0, 0, 0, 0]), DESCRIPTION) < 0.15
    assert np.isnan(base_height(STANDING, np.zeros(4), DESCRIPTION))


def _check_against(tmp_path: Path, framing: str, rate_hz: float = 500.0
                   ) -> tuple[int, str, dict]:
    """``go2-wbc check --dds`` (1.5 s) against an in-process bridge framed as ``framing``."""
    bridge = DdsBridge(BridgeConfig(domain_id=DOMAIN_ID, framing=framing, rate_hz=rate_hz))
    thread = threading.Thread(target=bridge.run, name="bridge")
    thread.start()
    out = io.StringIO()
    try:
        deadline = time.monotonic() + 30.0  # its topics made first: two threads making the
        while not bridge.is_started:         # same topic at once is refused by Cyclone
            assert time.monotonic() < deadline, "the bridge did not start"
            time.sleep(0.01)
        args = build_parser().parse_args(
            ["check", "--dds", "--domain", str(DOMAIN_ID), "--seconds", "1.5", "--report",
             str(tmp_path / f"{framing}.json")])
        code = run_check(args, stream=out)
    finally:
        bridge.stop()
        thread.join(30.0)
        bridge.close()
    return code, out.getvalue(), json.loads((tmp_path / f"{framing}.json").read_text())


def test_check_against_the_bridge_exits_0_and_on_an_empty_domain_exits_4(tmp_path: Path):
    code, text, report = _check_against(tmp_path, "go2")
    assert code == 0, text
    assert "framing   go2 (a GO2 or go2-wbc bridge)" in text
    assert report["ok"] is True
    # The bridge's 500 Hz, or less when a loaded machine slows its thread (368 Hz seen).
    assert 300.0 < report["figures"]["rate_hz"] < 510.0
    assert report["figures"]["posture"] == "standing"
    assert main(["check", "--dds", "--domain", str((DOMAIN_ID + 31) % 233), "--seconds",
                 "0.5"]) == 4


def test_check_against_the_unitree_python_peer_exits_0_naming_it(tmp_path: Path):
    code, text, report = _check_against(tmp_path, "unitree-python", UNITREE_PYTHON_RATE_HZ)
    assert code == 0, text
    assert "framing   unitree-python (Unitree's Python simulator" in text
    assert report["figures"]["rate_hz"] == pytest.approx(200.0, rel=0.1)
    assert report["figures"]["foot_force_absent"] is True
    # Limp until a first command, as theirs: the robot collapses from standing to lying.
    assert report["figures"]["base_height_m"] < 0.25
    assert ("  staleness limit: run --dds derives it from the rate at its start (100 ms at "
            "200 Hz") in text


def test_the_listener_refuses_a_bad_time_naming_it():
    with StateListener(domain_id=DOMAIN_ID, interface="lo") as listener, pytest.raises(
            ConfigurationError, match="seconds"):
        listener.listen(-1.0)
