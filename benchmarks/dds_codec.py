"""The cost of the GO2's DDS messages in Python: CDR (de)serialisation through cyclonedds'
``IdlStruct`` against the numpy codec, the CRC, the conversions, and a write + take.

Run ``python -m benchmarks.dds_codec [--repeats N] [--json PATH]``.

Each row times one call ``N`` times (default 2000) after a warm-up and prints the median and
the 99th percentile [us]; ``speed-up`` is the IdlStruct median over the codec's. The
write + take rows publish on a private domain (id 231) bound to ``lo`` and take the sample
from a reader in the same process (Cyclone delivers it during ``write``).
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.reporting import json_safe, machine
from wbc.robot_io.dds.c_layout import (
    crc32_bit_by_bit,
    low_cmd_crc,
    low_state_crc,
    sdk_default_low_cmd,
)
from wbc.robot_io.dds.domain_config import DomainHandle, join_domain
from wbc.robot_io.dds.go2_types import LowCmd_, LowState_
from wbc.robot_io.dds.low_cmd_conversion import (
    low_cmd_from_sdk_command,
    sdk_command_from_low_cmd,
)
from wbc.robot_io.dds.low_state_conversion import (
    low_state_from_sensor_record,
    sensor_record_from_low_state,
)
from wbc.robot_io.dds.topic_endpoints import TopicReader, TopicWriter
from wbc.robot_io.dds.wire_message import LowCmdMessage, LowStateMessage
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sdk_motor_command import SdkMotorCommand
from wbc.robot_io.sensor_record import SensorRecord

_DOMAIN_ID = 231


def timed(call: Callable[[], Any], repeats: int) -> tuple[float, float]:
    """Median and 99th percentile [us] of ``repeats`` calls, after ``repeats // 10`` warm-up."""
    for _ in range(max(1, repeats // 10)):
        call()
    samples = np.empty(repeats)
    clock = time.perf_counter_ns
    for i in range(repeats):
        start = clock()
        call()
        samples[i] = clock() - start
    return float(np.median(samples)) * 1e-3, float(np.percentile(samples, 99)) * 1e-3


def _sensor_record(rng: np.random.Generator) -> SensorRecord:
    quat = rng.normal(size=4)
    return SensorRecord(stamp_s=0.0, tick=1234, imu_quaternion_wxyz=quat / np.linalg.norm(quat),
                        gyroscope_rad_s=rng.normal(size=3), accelerometer_m_s2=rng.normal(size=3),
                        q=rng.uniform(-2, 2, 12), dq=rng.normal(size=12),
                        tau_est=rng.normal(size=12), foot_force=rng.integers(0, 300, 4))


def _command(rng: np.random.Generator) -> SdkMotorCommand:
    return SdkMotorCommand.from_control_output(MotorCommand(
        q_des=rng.uniform(-2, 2, 12), dq_des=rng.normal(size=12), kp=rng.uniform(1, 60, 12),
        kd=rng.uniform(0.5, 5, 12), tau_ff=rng.uniform(-20, 20, 12)))


def codec_rows(repeats: int) -> list[dict[str, Any]]:
    """Serialise / deserialise with IdlStruct and with the codec, both message types."""
    rng = np.random.default_rng(0)
    state = LowStateMessage(low_state_from_sensor_record(_sensor_record(rng)))
    cmd = LowCmdMessage(low_cmd_from_sdk_command(_command(rng)))
    rows = []
    for name, fast in (("LowState_", state), ("LowCmd_", cmd)):
        idl = fast.to_idl()
        for version in (1, 2):
            v2 = version == 2
            data = idl.serialize(use_version_2=v2)
            for operation, slow_call, fast_call in (
                ("serialise", partial(idl.serialize, use_version_2=v2),
                 partial(fast.serialize, use_version_2=v2)),
                ("deserialise", partial(type(idl).deserialize, data),
                 partial(type(fast).deserialize, data)),
            ):
                slow = timed(slow_call, repeats)
                quick = timed(fast_call, repeats)
                rows.append({"message": name, "xcdr": version, "operation": operation,
                             "idlstruct_us": slow, "codec_us": quick,
                             "speed_up": slow[0] / quick[0]})
    return rows


def single_rows(repeats: int) -> list[dict[str, Any]]:
    """The CRC and the conversions, one call each."""
    rng = np.random.default_rng(1)
    sensor = _sensor_record(rng)
    state = low_state_from_sensor_record(sensor)
    command = _command(rng)
    cmd = low_cmd_from_sdk_command(command)
    reused_sensor, reused_cmd = SensorRecord.zeros(), sdk_default_low_cmd()
    state_words = np.frombuffer(state, np.uint32)[:-1]  # every word before the CRC's
    calls: list[tuple[str, Callable[[], Any], int]] = [
        ("CRC LowCmd_ (compiled)", lambda: low_cmd_crc(cmd), repeats),
        ("CRC LowState_ (compiled)", lambda: low_state_crc(state), repeats),
        ("CRC LowState_ (Python bit loop)", lambda: crc32_bit_by_bit(state_words),
         max(20, repeats // 100)),
        ("LowState_ -> SensorRecord (in place)",
         lambda: sensor_record_from_low_state(state, out=reused_sensor), repeats),
        ("SensorRecord -> LowState_ (in place, CRC)",
         lambda: low_state_from_sensor_record(sensor, out=state), repeats),
        ("SdkMotorCommand -> LowCmd_ (in place, CRC)",
         lambda: low_cmd_from_sdk_command(command, out=reused_cmd), repeats),
        ("LowCmd_ -> SdkMotorCommand (checked)", lambda: sdk_command_from_low_cmd(cmd), repeats),
    ]
    return [{"operation": name, "us": timed(call, n), "repeats": n} for name, call, n in calls]


def _write_take(writer_dds: DomainHandle, reader_dds: DomainHandle, topic_name: str,
                data_type: type, sample: Any, repeats: int) -> dict[str, Any]:
    """Time ``write`` then ``take`` of ``sample`` to a reader of a second participant."""
    writer = TopicWriter(writer_dds, topic_name, data_type)
    reader = TopicReader(reader_dds, topic_name, data_type)
    writer.wait_for_reader(2.0)
    write, take = writer.write, reader.take
    taken: list[Any] = []

    def write_take() -> None:
        write(sample)
        taken.extend(take())

    timing = timed(write_take, repeats)
    reader.close()
    writer.close()
    return {"operation": f"write + take {topic_name}", "class": data_type.__name__,
            "us": timing, "taken": len(taken), "written": repeats + max(1, repeats // 10)}


def write_take_rows(repeats: int) -> list[dict[str, Any]]:
    """``DataWriter.write`` then ``DataReader.take`` of one sample, in one process."""
    rng = np.random.default_rng(2)
    state = LowStateMessage(low_state_from_sensor_record(_sensor_record(rng)))
    cmd = LowCmdMessage(low_cmd_from_sdk_command(_command(rng)))
    # Two participants of one domain configuration (join_domain shares it).
    with join_domain("lo", domain_id=_DOMAIN_ID) as writer_dds, \
            join_domain("lo", domain_id=_DOMAIN_ID) as reader_dds:
        return [_write_take(writer_dds, reader_dds, topic_name, data_type,
                            fast if data_type is type(fast) else fast.to_idl(), repeats)
                for topic_name, fast, classes in (
                    ("rt/lowstate", state, (LowState_, LowStateMessage)),
                    ("rt/lowcmd", cmd, (LowCmd_, LowCmdMessage)))
                for data_type in classes]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=2000, help="calls per row (2000)")
    parser.add_argument("--json", type=Path, help="also write the numbers here")
    args = parser.parse_args(argv)
    codec, single, write_take = (codec_rows(args.repeats), single_rows(args.repeats),
                                 write_take_rows(args.repeats))

    print(f"median / p99 [us] over {args.repeats} calls")
    print(f"{'message':10} {'xcdr':>4} {'operation':12} {'IdlStruct':>17} {'numpy codec':>15}"
          f" {'speed-up':>9}")
    for row in codec:
        slow, quick = row["idlstruct_us"], row["codec_us"]
        print(f"{row['message']:10} {row['xcdr']:>4} {row['operation']:12} "
              f"{slow[0]:8.1f} / {slow[1]:6.1f} {quick[0]:6.1f} / {quick[1]:6.1f} "
              f"{row['speed_up']:8.0f}x")
    print()
    for row in single:
        print(f"{row['operation']:44} {row['us'][0]:8.1f} / {row['us'][1]:8.1f}"
              + ("" if row["repeats"] == args.repeats else f"  ({row['repeats']} calls)"))
    print()
    for row in write_take:
        print(f"{row['operation']:22} {row['class']:16} {row['us'][0]:8.1f} / {row['us'][1]:8.1f}"
              f"  taken {row['taken']} of {row['written']}")
    if args.json:
        report = {"machine": machine(("cyclonedds", "numpy", "numba")), "repeats": args.repeats,
                  "codec": codec, "single": single, "write_take": write_take}
        args.json.write_text(json.dumps(json_safe(report), indent=2))


if __name__ == "__main__":
    main()
