"""What a stream of ``LowState_`` says about the robot that sends it, before anything commands it:
the bring-up check behind ``go2-wbc check --dds``.

From a few seconds of states (:class:`~wbc.robot_io.dds.state_listener.ListenedStream`) it
finds, each as a :class:`Finding` (a problem or not, in words):

- **timing**: the rate (from the writer's own timestamps), the jitter and the longest gap;
- **framing**: ``head``, ``level_flag``, the CRC (valid, absent as 0, or wrong) and the
  ``tick`` (counting, always 0, frozen), repeated samples, and a stream that never changes;
- **joints**: finite, and within the GO2's ranges read in the SDK's motor order (what a GO2
  and Unitree's simulators send) and, for comparison, read in the description's order;
- **pose**: the base height the joints and the IMU's attitude give on flat ground (lying,
  standing), and whether the robot is still;
- **IMU**: the quaternion's norm, the tilt, the gyroscope's mean at rest (its bias) and the
  accelerometer's norm at rest (gravity, 9.81 m/s^2);
- **foot force**: each foot's counts (absent when all are 0, as Unitree's simulators send)
  and, with the robot lying or standing still, what they say of the sensors' offsets;
- **commands**: who else writes ``rt/lowcmd`` (the check writes nothing).

It ends with the settings to use, or with what is wrong.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from wbc.estimation.foot_force_calibration import FootForceCalibration, static_foot_loads
from wbc.model.description import FOOT_RADIUS_M, JOINT_NAMES, LEGS, Go2Description
from wbc.model.joint_map import JointMap
from wbc.robot_io.dds.low_state_conversion import sensor_record_from_low_state
from wbc.robot_io.dds.low_state_stream import LowStateStream, default_stale_after_s
from wbc.robot_io.dds.state_listener import ListenedStream
from wbc.robot_io.sensor_record import SensorRecord

GRAVITY_M_S2 = 9.80665
#: Joint readings this far [rad] outside the URDF's limits still count as in range (encoder
#: offsets, a calf resting just past its stop as in Unitree's simulator).
RANGE_MARGIN_RAD = 0.1
#: A robot whose joint positions spread less than this [rad, standard deviation over the
#: listening, the worst joint] and whose gyroscope reads less than :data:`STILL_GYRO_RAD_S`
#: [rad/s, RMS about its mean] is still. Positions, not velocities: a GO2's joint velocity
#: readings are noisy (a robot standing still reads several 0.01 rad/s), its encoders are not.
STILL_JOINT_RAD = 0.005
STILL_GYRO_RAD_S = 0.02
#: Base heights [m] below which the robot is lying, above which it is standing.
LYING_BELOW_M, STANDING_ABOVE_M = 0.15, 0.25
#: Gravity's norm off by more than this share is a problem (a wrong scale or a bad IMU).
GRAVITY_TOLERANCE = 0.05
#: A gyroscope mean above this at rest [rad/s] is a large bias.
GYRO_BIAS_LIMIT_RAD_S = 0.05
#: The default foot-force calibration reading the weight this far off [share] gets gains to
#: set (the estimator's own weight check names a calibration off by much more).
CALIBRATION_TOLERANCE = 0.15
#: Fewest states for a verdict.
MIN_STATES = 10


@dataclass(frozen=True)
class Finding:
    """One thing the check found.

    Attributes:
        topic: What it is about (``timing``, ``framing``, ``joints``, ...).
        text: What was found, in words.
        problem: It must be dealt with before the robot is controlled.
    """

    topic: str
    text: str
    problem: bool = False


@dataclass
class BringupReport:
    """The check's findings and the settings they lead to."""

    findings: list[Finding] = field(default_factory=list)
    #: Figures by name (rate_hz, base_height_m, gyro_bias_rad_s, ...), for a JSON report.
    figures: dict[str, object] = field(default_factory=dict)
    #: The settings to use, in words (command-line options with why).
    settings: list[str] = field(default_factory=list)

    @property
    def problems(self) -> list[Finding]:
        """The findings that are problems."""
        return [f for f in self.findings if f.problem]

    @property
    def ok(self) -> bool:
        """Nothing must be dealt with first."""
        return not self.problems

    def add(self, topic: str, text: str, *, problem: bool = False) -> None:
        """Add a finding."""
        self.findings.append(Finding(topic, text, problem))

    def lines(self) -> list[str]:
        """The report as printed: findings, then the settings or what is wrong."""
        width = max((len(f.topic) for f in self.findings), default=0)
        out = [f"{f.topic:<{width}}  {'PROBLEM: ' if f.problem else ''}{f.text}"
               for f in self.findings]
        if self.ok:
            out.append("settings to use:")
            out.extend(f"  {s}" for s in self.settings or ["the defaults"])
        else:
            out.append(f"{len(self.problems)} problem(s) to deal with before controlling "
                       "this robot:")
            out.extend(f"  - {f.topic}: {f.text}" for f in self.problems)
        return out


def check_stream(stream: ListenedStream, *,
                 description: Go2Description | None = None) -> BringupReport:
    """Everything :mod:`this module <actions.robot.bringup_check>` finds in ``stream``.

    Args:
        stream: What the listener heard.
        description: The robot (the installed GO2 by default).
    """
    description = description or Go2Description.default()
    report = BringupReport()
    count = len(stream.records)
    report.figures["states"] = count
    if count < MIN_STATES:
        report.add("stream", f"{count} LowState_ in {stream.listened_s:.1f} s on rt/lowstate "
                             f"({stream.state_writers} writer(s) matched): no GO2 streams here",
                   problem=True)
        _check_commands(report, stream)
        return report
    _check_timing(report, stream)
    _check_framing(report, stream)
    samples = [sensor_record_from_low_state(r) for r in stream.records]
    q = np.array([s.q for s in samples])
    _check_joints(report, q, description)
    still = _check_pose(report, q, samples, description)
    _check_imu(report, samples, still=still)
    geometry = _geometry(q.mean(axis=0), np.mean([s.imu_quaternion_wxyz for s in samples],
                                                 axis=0), description)
    _check_feet(report, np.array([s.foot_force for s in samples]), geometry,
                weight_n=description.total_mass * GRAVITY_M_S2)
    _check_commands(report, stream)
    _settings(report)
    return report


def _settings(report: BringupReport) -> None:
    """The settings the findings lead to (printed when nothing is a problem)."""
    figures, settings = report.figures, report.settings
    kind = figures.get("kind")
    if kind is not None:
        settings.append(f"stream {kind}: run --dds recognises it by itself (no option)")
    period = figures.get("period_s")
    if isinstance(period, float):
        gap = float(figures["longest_gap_s"])  # type: ignore[arg-type]
        limit = default_stale_after_s(period, gap)
        first = default_stale_after_s(period)
        settings.append(
            f"staleness limit: run --dds derives it from the rate at its start ({first * 1e3:.0f}"
            f" ms at {1.0 / period:.0f} Hz: 20 periods or twice the longest gap, 20 to 250 ms)"
            + (f"; gaps of {gap * 1e3:.0f} ms came later here: --stale-after {limit:.3g}"
               if limit > first else ""))
    if figures.get("foot_force_absent"):
        settings.append("foot force absent: contact from the schedule only (run --dds does "
                        "it by itself when every count is 0)")
    if figures.get("still") and "gyro_bias_rad_s" in figures:
        settings.append("gyroscope bias and gravity in range: the estimator learns the bias "
                        "as it runs (no option)")


def _check_timing(report: BringupReport, stream: ListenedStream) -> None:
    sent = np.diff(stream.sent_s)
    if len(sent) == 0 or not np.all(np.isfinite(sent)):
        return
    period = float(np.median(sent))
    rate = 1.0 / period if period > 0.0 else math.inf
    jitter = np.abs(sent - period)
    p99 = float(np.percentile(jitter, 99))
    gap = float(np.max(sent))
    late = int(np.count_nonzero(sent > 2.0 * period))
    report.figures.update(rate_hz=rate, period_s=period, jitter_p99_s=p99, longest_gap_s=gap,
                          gaps_over_two_periods=late)
    writers = len(np.unique(stream.writers))
    report.add("timing", f"{len(stream.records)} states over {stream.sent_s[-1]:.2f} s: "
                         f"{rate:.0f} Hz (median period {period * 1e3:.2f} ms), jitter p99 "
                         f"{p99 * 1e3:.2f} ms, longest gap {gap * 1e3:.1f} ms, {late} gap(s) "
                         "over two periods", problem=writers > 1)
    if writers > 1:
        report.add("timing", f"{writers} writers of rt/lowstate: two robots or a robot and a "
                             "simulator on one domain; stop all but one", problem=True)


def _check_framing(report: BringupReport, stream: ListenedStream) -> None:
    """The stream's kind as ``go2-wbc run --dds`` recognises it (the same
    :class:`~wbc.robot_io.dds.low_state_stream.LowStateStream`), judged over every state."""
    states = LowStateStream()
    for record, sent in zip(stream.records, stream.sent_s, strict=True):
        states.accept(record, float(sent))
    kind = states.decide()
    counters = states.counters
    flags = sorted({int(r["level_flag"]) for r in stream.records})
    report.figures.update(stream=states.report(), level_flags=flags)
    if kind is None:
        report.add("framing", f"no frame of a known kind: {states.last_fault}", problem=True)
        return
    report.figures["kind"] = kind.framing
    report.add("framing", f"{kind.framing} ({kind.sender}): {kind.checks()}; level_flag "
                          f"{'/'.join(f'0x{f:02X}' for f in flags)}")
    report.add("framing", f"{counters.new_samples} new samples, {counters.repeats} "
                          f"repeat(s), {counters.dropped} frame(s) dropped"
                          + (f" (the last because {states.last_fault})" if counters.dropped
                             else ""), problem=counters.dropped > 0)
    sensed = {r["imu_state"].tobytes() + r["motor_state"].tobytes() + r["foot_force"].tobytes()
              for r in stream.records}
    if len(sensed) == 1:
        report.add("framing", f"every state carries the same sensor values ({counters.new_samples}"
                              " told apart by the tick alone): the stream keeps arriving but "
                              "never changes (a frozen sensor stream)", problem=True)
    elif counters.tick_frozen:
        report.add("framing", f"the tick stayed put while the content changed in "
                              f"{counters.tick_frozen} state(s): the tick froze", problem=True)


def _check_joints(report: BringupReport, q: np.ndarray, description: Go2Description) -> None:
    if not np.isfinite(q).all():
        bad = sorted({JOINT_NAMES[j] for j in np.nonzero(~np.isfinite(q))[1]})
        report.add("joints", f"non-finite positions at {', '.join(bad)}", problem=True)
        return
    low = description.position_lower - RANGE_MARGIN_RAD
    high = description.position_upper + RANGE_MARGIN_RAD
    sdk_out = _outside(q, low, high)
    # The same slots read in the description's order: what a robot would look like whose
    # motor slots were taken to be FL, FR, RL, RR.
    as_description = q[:, JointMap.unitree_sdk().index]
    other_out = _outside(as_description, low, high)
    report.figures.update(joints_outside_sdk_order=sdk_out, joints_outside_description_order=(
        other_out))
    text = ("within the GO2's ranges in the SDK's motor order (FR, FL, RR, RL)" if not sdk_out
            else f"outside the GO2's ranges in the SDK's motor order: {', '.join(sdk_out)}")
    text += ("; read in the description's order (FL, FR, RL, RR) they are "
             + ("within them too (the ranges cannot tell the two apart here)" if not other_out
                else f"outside at {', '.join(other_out)}"))
    report.add("joints", text, problem=bool(sdk_out))


def _outside(q: np.ndarray, low: np.ndarray, high: np.ndarray) -> list[str]:
    worst = np.maximum(low - q, q - high).max(axis=0)
    return [f"{JOINT_NAMES[j]} {q[np.argmax(np.abs(q[:, j])), j]:+.2f} rad"
            for j in np.nonzero(worst > 0.0)[0]]


def _check_pose(report: BringupReport, q: np.ndarray, samples: list[SensorRecord],
                description: Go2Description) -> bool:
    """The base height on flat ground and whether the robot is still; whether it is."""
    quaternion = np.mean([s.imu_quaternion_wxyz for s in samples], axis=0)
    height = base_height(q.mean(axis=0), quaternion, description)
    gyro = np.array([s.gyroscope_rad_s for s in samples])
    spread = float(q.std(axis=0).max())
    gyro_rms = float(np.sqrt(np.mean((gyro - gyro.mean(axis=0)) ** 2)))
    still = spread < STILL_JOINT_RAD and gyro_rms < STILL_GYRO_RAD_S
    posture = ("lying" if height < LYING_BELOW_M else "standing" if height > STANDING_ABOVE_M
               else "between lying and standing")
    report.figures.update(base_height_m=height, still=still, joint_spread_rad=spread,
                          gyro_rms_rad_s=gyro_rms)
    report.add("pose", f"{posture}: base {height:.3f} m above the feet (joints and IMU "
                       f"attitude, flat ground), {'still' if still else 'moving'} (joint "
                       f"positions spread {spread * 1e3:.1f} mrad at most, gyroscope RMS "
                       f"{gyro_rms:.4f} rad/s)")
    report.figures["posture"] = posture
    return still


def base_height(joint_q: np.ndarray, quaternion_wxyz: np.ndarray,
                description: Go2Description) -> float:
    """The base's height [m] above the lowest three feet on flat ground, from the joints
    (description order) and the IMU's attitude ``(w, x, y, z)``; NaN if either is unusable."""
    geometry = _geometry(joint_q, quaternion_wxyz, description)
    if geometry is None:
        return math.nan
    feet, _ = geometry
    return float(-np.mean(np.sort(feet[:, 2])[:3]) + FOOT_RADIUS_M)


def _geometry(joint_q: np.ndarray, quaternion_wxyz: np.ndarray, description: Go2Description
              ) -> tuple[np.ndarray, np.ndarray] | None:
    """The feet's positions (4, 3) and the centre of mass (3,) [m], ``LEGS`` order, in a
    level frame at the base, from the joints and the IMU's attitude; ``None`` if unusable."""
    norm = float(np.linalg.norm(quaternion_wxyz))
    if not (np.isfinite(joint_q).all() and math.isfinite(norm) and norm > 0.5):
        return None
    w, x, y, z = np.asarray(quaternion_wxyz) / norm
    model = description.model
    data = model.createData()
    config = np.concatenate([[0.0, 0.0, 0.0, x, y, z, w], joint_q])
    pin.framesForwardKinematics(model, data, config)
    com = pin.centerOfMass(model, data, config)
    feet = np.array([data.oMf[model.getFrameId(f"{leg}_foot")].translation for leg in LEGS])
    return feet, np.array(com)


def _check_imu(report: BringupReport, samples: list[SensorRecord], *, still: bool) -> None:
    quats = np.array([s.imu_quaternion_wxyz for s in samples])
    gyro = np.array([s.gyroscope_rad_s for s in samples])
    accel = np.array([s.accelerometer_m_s2 for s in samples])
    if not (np.isfinite(quats).all() and np.isfinite(gyro).all() and np.isfinite(accel).all()):
        report.add("imu", "non-finite IMU readings", problem=True)
        return
    norm = np.linalg.norm(quats, axis=1)
    worst = float(np.max(np.abs(norm - 1.0)))
    w, x, y, z = quats.mean(axis=0) / np.linalg.norm(quats.mean(axis=0))
    roll = math.degrees(math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)))
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x)))))
    report.figures.update(quaternion_norm_error=worst, roll_deg=roll, pitch_deg=pitch)
    report.add("imu", f"quaternion norm within {worst:.1e} of 1, roll {roll:+.1f} deg, pitch "
                      f"{pitch:+.1f} deg", problem=worst > 0.01)
    if not still:
        report.add("imu", "robot moving: gyroscope bias and gravity not measured (check again "
                          "with the robot lying or standing still)")
        return
    bias = gyro.mean(axis=0)
    gravity = float(np.linalg.norm(accel.mean(axis=0)))
    scale = gravity / GRAVITY_M_S2 - 1.0
    report.figures.update(gyro_bias_rad_s=bias.tolist(), gravity_m_s2=gravity)
    report.add("imu", f"at rest: gyroscope bias ({bias[0]:+.4f}, {bias[1]:+.4f}, "
                      f"{bias[2]:+.4f}) rad/s, gravity {gravity:.3f} m/s^2 ({scale:+.1%} of "
                      f"{GRAVITY_M_S2:g})",
               problem=abs(scale) > GRAVITY_TOLERANCE
               or float(np.max(np.abs(bias))) > GYRO_BIAS_LIMIT_RAD_S)


def _check_feet(report: BringupReport, counts: np.ndarray, geometry: tuple | None, *,
                weight_n: float) -> None:
    """The foot counts and, with the robot still, what they say of the calibration: lying,
    the counts bound the offsets; standing, each foot's static load (the smallest forces that
    carry the weight, :func:`~wbc.estimation.foot_force_calibration.static_foot_loads`)
    against its count gives the gains at the estimator's offsets."""
    mean = counts.mean(axis=0)
    report.figures["foot_force_mean"] = dict(zip(LEGS, mean.tolist(), strict=True))
    if not counts.any():
        report.figures["foot_force_absent"] = True
        report.add("feet", "foot force absent (every count 0, as Unitree's simulators send): "
                           "contact from the controller's schedule only")
        return
    means = ", ".join(f"{leg} {m:.1f}±{s:.1f}" for leg, m, s in zip(
        LEGS, mean, counts.std(axis=0), strict=True))
    report.add("feet", f"foot-force counts (mean±std): {means}")
    posture = report.figures.get("posture")
    if not report.figures.get("still") or geometry is None:
        return
    if posture == "lying":
        report.add("feet", "lying still: each foot's count is at most its offset plus what "
                           "the foot carries of the body (an upper bound of the offsets)")
        return
    if posture != "standing":
        return
    feet, com = geometry
    loads = static_foot_loads(feet[:, :2], com[:2], weight_n)
    default = FootForceCalibration(source="default")
    carried = float(default.newtons(mean).sum())
    gains = (mean - default.offsets) / loads
    report.figures.update(static_loads_n=loads.tolist(), weight_n=weight_n,
                          weight_read_with_default_n=carried,
                          gains_at_default_offsets=gains.tolist())
    report.add("feet", f"standing still: static loads {_per_leg(loads, '.1f')} N "
                       f"({weight_n:.1f} N in all); the estimator's default calibration "
                       f"({default.offsets[0]:g} + {default.gains[0]:g}/N a foot) reads "
                       f"{carried:.1f} N ({carried / weight_n:.0%} of the weight); at its "
                       f"offsets the gains are {_per_leg(gains, '.3g')} counts/N")
    if abs(carried / weight_n - 1.0) > CALIBRATION_TOLERANCE and np.all(gains > 0.0):
        report.settings.append(
            "foot-force calibration: the default reads the weight "
            f"{carried / weight_n - 1.0:+.0%} off: --set estimator.foot_force_gain="
            f"{','.join(f'{g:.3g}' for g in gains)} (at the default offsets "
            f"{default.offsets[0]:g}; measure the offsets with the feet unloaded, or run the "
            "standing calibration, for both)")
    else:
        report.settings.append("foot-force calibration: the default reads the weight within "
                               f"{CALIBRATION_TOLERANCE:.0%} (no option)")


def _per_leg(values: np.ndarray, fmt: str) -> str:
    return ", ".join(f"{leg} {v:{fmt}}" for leg, v in zip(LEGS, values, strict=True))


def _check_commands(report: BringupReport, stream: ListenedStream) -> None:
    report.figures.update(command_writers=stream.command_writers,
                          commands_seen=stream.commands_seen)
    if stream.command_writers or stream.commands_seen:
        report.add("commands", f"{stream.command_writers} other writer(s) of rt/lowcmd, "
                               f"{stream.commands_seen} command(s) seen: something else "
                               "commands this robot (its sport mode, another controller); "
                               "release or stop it first", problem=True)
    else:
        report.add("commands", "nobody else writes rt/lowcmd")
