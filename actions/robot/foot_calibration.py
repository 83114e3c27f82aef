"""The sensors calibrated on the robot while it stands: foot forces in newtons, the IMU at rest.

:class:`StandingCalibration` is a loop hook. For ``duration_s`` (2 s by default) it moves the
controller's centre-of-mass target once round a small circle (4.5 cm: every foot's load swings
by about +-13 N on a GO2), and meanwhile

- fits each foot sensor's ``counts = offset + gain x N``
  (:class:`wbc.estimation.foot_force_calibration.FootForceFit`) against the normal force the
  robot's weight puts on that foot: the smallest-forces split of the weight about the
  centre of pressure, which is the centre of mass ahead of its circle by ``h w^2 / g``
  (the circle's acceleration); measured on the realistic plant, that reference follows the
  true per-foot forces to 0.84-0.96 of their swing, where the controller's own commanded
  forces overshoot it (1.05-1.17) and the forces from the joint torques through the foot
  Jacobians are off by the joints' static friction (4 N a foot standing still);
- averages the IMU: the gyroscope's bias (the base turns back to where it started), the
  accelerometer's norm (gravity's 9.81 m/s^2 times its scale) and its horizontal bias
  against the floor's "up" from the four feet (a level floor: the feet's plane), which a
  standing robot's attitude filter cannot tell from a tilt.

At the end it gives the estimator the learnt calibration
(:meth:`wbc.estimation.state_estimator.EstimatorBase.set_foot_calibration`), puts the
centre-of-mass target back and keeps :attr:`StandingCalibration.report`; a fit that fails
(a foot whose load did not change, a sensor that does not follow its load) keeps the
estimator's calibration and says why. :func:`calibrate_standing` runs it on a loop.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from actions.go2.robot_context import STANDING_HEIGHT_M
from actions.robot.control_loop import ControlLoop
from actions.robot.rest_sequence import Phase
from wbc.controller.balance_controller import BalanceController
from wbc.controller.control_output import ControlOutput
from wbc.core.conventions import GRAVITY_M_S2
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float
from wbc.estimation.foot_force_calibration import FootForceCalibration, WeightShiftFit
from wbc.estimation.invariant_ekf import InvariantEkf
from wbc.estimation.state_estimator import EstimatorBase
from wbc.robot_io.sensor_record import SensorRecord


@dataclass(frozen=True)
class ImuAtRest:
    """What the IMU read while the robot stood (means over the calibration).

    Attributes:
        gyro_bias_rad_s: The gyroscope's mean [rad/s] (3,): its bias, the base having turned
            back to where it started.
        gravity_m_s2: The accelerometer's mean norm [m/s^2]; over 9.81 it is the
            accelerometer's scale.
        accel_bias_m_s2: The accelerometer's mean less gravity along the feet's "up" [m/s^2]
            (3,), body frame: its bias on a level floor (horizontal components: what reads
            as tilt).
        up_body: The floor's "up" in the base frame from the feet (3,) at the end: the
            base's true tilt on a level floor.
        turn_deg: How far the estimator's orientation was turned to it [deg] (an estimator
            that takes the bias: :meth:`wbc.InvariantEkf.set_imu_at_rest`; 0 otherwise).
    """

    gyro_bias_rad_s: np.ndarray
    gravity_m_s2: float
    accel_bias_m_s2: np.ndarray
    up_body: np.ndarray
    turn_deg: float = 0.0

    @property
    def tilt_from_bias_deg(self) -> float:
        """The tilt [deg] the horizontal accelerometer bias reads as at rest."""
        return math.degrees(math.atan2(float(np.hypot(*self.accel_bias_m_s2[:2])),
                                       GRAVITY_M_S2))

    def describe(self) -> str:
        """One line."""
        g = self.gyro_bias_rad_s
        b = self.accel_bias_m_s2
        return (f"IMU at rest: gyro bias ({g[0]:+.4f}, {g[1]:+.4f}, {g[2]:+.4f}) rad/s; gravity "
                f"{self.gravity_m_s2:.3f} m/s^2 (scale {self.gravity_m_s2 / GRAVITY_M_S2:.4f}); "
                f"accelerometer bias against the feet's level ({b[0]:+.3f}, {b[1]:+.3f}, "
                f"{b[2]:+.3f}) m/s^2, reading as {self.tilt_from_bias_deg:.2f} deg of tilt"
                + (f"; the estimate's tilt corrected by {self.turn_deg:.2f} deg"
                   if self.turn_deg else ""))


@dataclass(frozen=True)
class CalibrationReport:
    """What a standing calibration learnt.

    Attributes:
        feet: The foot sensors' calibration now in use (the previous one if the fit failed).
        learnt: The fit succeeded and the estimator uses it.
        problem: Why the fit failed ('' when it did not).
        spread_n: Each foot's load's standard deviation over the fit [N], ``LEGS`` order.
        imu: The IMU at rest.
        samples: Sensor samples read.
    """

    feet: FootForceCalibration
    learnt: bool
    problem: str
    spread_n: np.ndarray
    imu: ImuAtRest
    samples: int

    def as_dict(self) -> dict[str, Any]:
        """Plain values, JSON-ready."""
        imu = self.imu
        return {"feet": {"offset": list(self.feet.offset), "gain": list(self.feet.gain),
                         "source": self.feet.source},
                "learnt": self.learnt, "problem": self.problem,
                "spread_n": [round(float(x), 3) for x in self.spread_n],
                "imu": {"gyro_bias_rad_s": imu.gyro_bias_rad_s.tolist(),
                        "gravity_m_s2": imu.gravity_m_s2,
                        "accel_bias_m_s2": imu.accel_bias_m_s2.tolist(),
                        "tilt_from_bias_deg": imu.tilt_from_bias_deg,
                        "turn_deg": imu.turn_deg},
                "samples": self.samples}

    def describe(self) -> str:
        """Two lines: the feet and the IMU."""
        head = "calibration: " + self.feet.describe()
        if not self.learnt:
            head += f" (not learnt: {self.problem})"
        return f"{head}\ncalibration: {self.imu.describe()}"


class StandingCalibration:
    """A loop hook that calibrates the foot sensors and checks the IMU while the robot stands
    (see the module docstring).

    Args:
        duration_s: How long [s] it sways and fits (one circle).
        radius_m: The centre of mass's circle's radius [m].
        skip_s: Time [s] at the start left out of the fit (the sway starting).
        apply_imu: Give an estimator that learns the accelerometer's bias
            (:class:`wbc.InvariantEkf`) the bias and the tilt measured against the feet.
    """

    def __init__(self, *, duration_s: float = 2.0, radius_m: float = 0.045,
                 skip_s: float = 0.1, apply_imu: bool = True):
        self.duration_s = as_float("duration_s", duration_s, low=0.2, high=60.0)
        self.radius_m = as_float("radius_m", radius_m, low=0.0, high=0.06)
        self.skip_s = as_float("skip_s", skip_s, low=0.0, high=self.duration_s / 2)
        if not isinstance(apply_imu, bool):
            raise ConfigurationError(f"apply_imu: expected true or false, received {apply_imu!r}")
        self.apply_imu = apply_imu
        self.fit: WeightShiftFit | None = None
        self.report: CalibrationReport | None = None
        self._start_s: float | None = None
        self._centre = np.zeros(3)
        self._target = np.zeros(3)
        self._gyro = np.zeros(3)
        self._accel = np.zeros(3)
        self._accel_norm = 0.0
        self._up = np.zeros(3)
        self._imu_samples = 0
        # The feet in the base frame and the base's world velocity at the first and the last
        # sample: how far the base turned and sped up over the window.
        self._feet_first = np.zeros((4, 3))
        self._feet_last = np.zeros((4, 3))
        self._velocity_first = np.zeros(3)
        self._velocity_last = np.zeros(3)
        self._first_s = self._last_s = 0.0

    @property
    def done(self) -> bool:
        """The calibration has ended (its :attr:`report` is ready)."""
        return self.report is not None

    def cancel(self, controller: BalanceController) -> None:
        """Stop before the end, learning nothing: the centre-of-mass target back where it
        was when the calibration started."""
        if self._start_s is not None and not self.done:
            controller.set_com_target(self._target)

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        if self.done:
            return
        estimator = loop.estimator
        if estimator is None:
            raise ConfigurationError(
                "StandingCalibration: the loop reads no sensors (state='truth'); calibrate "
                "on a loop with state='estimate'")
        controller = loop.controller
        now = loop.robot.time_s
        if self._start_s is None:
            self._start_s = now
            self._target = controller.com_target
            self._centre = self._target - np.array([self.radius_m, 0.0, 0.0])
        elapsed = now - self._start_s
        omega = 2.0 * math.pi / self.duration_s
        sample = estimator.last_sample
        if sample is not None and estimator.estimate.trusted:
            if elapsed >= self.skip_s:
                self._add_feet(controller, sample, omega)
            # The IMU over the whole circle, at whose end the base is back where it began.
            self._add_imu(estimator, sample)
        if elapsed >= self.duration_s:
            controller.set_com_target(self._target)
            self._finish(estimator)
            return
        phase = omega * elapsed
        offset = self.radius_m * np.array([math.cos(phase), math.sin(phase), 0.0])
        velocity = self.radius_m * omega * np.array([-math.sin(phase), math.cos(phase), 0.0])
        controller.set_com_target(self._centre + offset, velocity, -omega ** 2 * offset)

    def _add_feet(self, controller: BalanceController, sample: SensorRecord,
                  omega: float) -> None:
        feet = controller.foot_positions()
        com = controller.com_position()
        height = float(com[2] - feet[:, 2].mean())
        # The centre of pressure: the centre of mass less h / g times its acceleration, which
        # on the circle is -omega^2 times its offset from the circle's centre.
        zmp = com[:2] + height * omega ** 2 / GRAVITY_M_S2 * (com[:2] - self._centre[:2])
        if self.fit is None:
            self.fit = WeightShiftFit(controller.description.total_mass * GRAVITY_M_S2)
        self.fit.add(sample.foot_force, feet[:, :2], zmp)

    def _add_imu(self, estimator: EstimatorBase, sample: SensorRecord) -> None:
        self._gyro += sample.gyroscope_rad_s
        self._accel += sample.accelerometer_m_s2
        self._accel_norm += float(np.linalg.norm(sample.accelerometer_m_s2))
        feet = estimator.legs.foot_position
        self._up += _feet_up(feet)
        q, v = estimator.estimate.q, estimator.estimate.v
        velocity = _rotation(q[3:7]) @ v[:3]  # the base's, world frame [m/s]
        if self._imu_samples == 0:
            self._feet_first[:] = feet
            self._velocity_first[:] = velocity
            self._first_s = sample.stamp_s
        self._feet_last[:] = feet
        self._velocity_last[:] = velocity
        self._last_s = sample.stamp_s
        self._imu_samples += 1

    def _finish(self, estimator: EstimatorBase) -> None:
        n = max(self._imu_samples, 1)
        span = max(self._last_s - self._first_s, 1e-9)
        up = self._up / max(float(np.linalg.norm(self._up)), 1e-12)
        # The window's mean specific force is gravity's plus the base's mean acceleration
        # (its velocity's change over the window: the circle ends moving), and its mean
        # angular velocity the turn between the first and the last sample, which the feet
        # standing on the floor give (their base-frame positions turned the other way).
        turned = _turn(self._feet_first, self._feet_last) / span
        world_to_base = _rotation(estimator.estimate.q[3:7]).T
        sped_up = world_to_base @ (self._velocity_last - self._velocity_first) / span
        imu = ImuAtRest(gyro_bias_rad_s=self._gyro / n - turned,
                        gravity_m_s2=self._accel_norm / n,
                        accel_bias_m_s2=self._accel / n - sped_up - GRAVITY_M_S2 * up,
                        up_body=_feet_up(self._feet_last))
        if self.apply_imu and isinstance(estimator, InvariantEkf):
            turn = estimator.set_imu_at_rest(imu.accel_bias_m_s2, imu.up_body)
            imu = dataclasses.replace(imu, turn_deg=math.degrees(turn))
        fit = self.fit or WeightShiftFit(1.0)
        try:
            feet = fit.result(
                source=f"learnt standing, {self.duration_s:g} s, {fit.samples} samples")
        except ConfigurationError as err:
            self.report = CalibrationReport(feet=estimator.foot_calibration, learnt=False,
                                            problem=str(err), spread_n=fit.spread_n(),
                                            imu=imu, samples=fit.samples)
            return
        estimator.set_foot_calibration(feet)
        self.report = CalibrationReport(feet=feet, learnt=True, problem="",
                                        spread_n=fit.spread_n(), imu=imu,
                                        samples=fit.samples)


def _rotation(quat_xyzw: np.ndarray) -> np.ndarray:
    """The rotation matrix of a unit quaternion in Pinocchio's (x, y, z, w) order."""
    x, y, z, w = quat_xyzw
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _turn(feet_first: np.ndarray, feet_last: np.ndarray) -> np.ndarray:
    """The base's rotation [rad] (rotation vector, base frame) from the first sample to the
    last, from the feet's base-frame positions (4, 3) at both, the feet fixed on the floor:
    ``first = R last`` about their centroids (Kabsch)."""
    a = feet_first - feet_first.mean(axis=0)
    b = feet_last - feet_last.mean(axis=0)
    u, _, vt = np.linalg.svd(a.T @ b)
    d = np.sign(np.linalg.det(u @ vt))
    r = u @ np.diag([1.0, 1.0, d]) @ vt
    angle = math.acos(max(-1.0, min(1.0, (np.trace(r) - 1.0) / 2.0)))
    axis = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    scale = 0.5 if angle < 1e-9 else angle / (2.0 * math.sin(angle))
    return scale * axis


def _feet_up(feet_body: np.ndarray) -> np.ndarray:
    """The unit normal (body frame) of the plane through four foot centres (4, 3), pointing
    from the feet to the base: on a level floor, gravity's "up"."""
    centred = feet_body - feet_body.mean(axis=0)
    normal = np.linalg.svd(centred)[2][-1]
    return normal if normal @ (-feet_body.mean(axis=0)) > 0 else -normal


def calibrate_standing(loop: ControlLoop, *, duration_s: float = 2.0,
                       radius_m: float = 0.045) -> CalibrationReport:
    """Run a :class:`StandingCalibration` on ``loop`` (standing, no goal running) for
    ``duration_s`` [s] of robot time; its report.

    Raises:
        ConfigurationError: A loop on the exact state (no sensors to calibrate).
    """
    if loop.estimator is None:
        raise ConfigurationError(
            "calibrate_standing: the loop reads no sensors (state='truth'); calibrate on a "
            "loop with state='estimate'")
    routine = StandingCalibration(duration_s=duration_s, radius_m=radius_m)
    loop.hooks.append(routine)
    try:
        while not routine.done:
            loop.spin_once()
    finally:
        loop.hooks.remove(routine)
    report = routine.report
    if report is None:  # cannot happen: the loop above ends when it is set
        raise ConfigurationError("calibrate_standing: the calibration did not end")
    return report


#: Why goals are refused while :class:`CalibrateWhenStanding` runs.
CALIBRATING = "calibrating the sensors while standing"


class CalibrateWhenStanding:
    """A wall-clock loop's callback (``go2-wbc run --dds --calibrate S``): once the robot
    stands under control with no goal running, a :class:`StandingCalibration` of
    ``duration_s`` [s]; goals are refused meanwhile (they would move the centre of mass the
    calibration moves). Abandoned, keeping the estimator's calibration, when the loop falls
    back (no trustworthy state) or is asked to stop.

    Args:
        duration_s: How long [s] it sways and fits.
        say: Told each step (started, the report's lines, abandoned).
    """

    def __init__(self, duration_s: float, say: Callable[[str], None]) -> None:
        self.duration_s = as_float("duration_s", duration_s, low=0.2, high=60.0)
        self.say = say
        self.routine: StandingCalibration | None = None
        #: The calibration's report once it ended; ``None`` before, or when abandoned.
        self.report: CalibrationReport | None = None
        #: Why it was abandoned ('' when it was not).
        self.abandoned = ""

    @property
    def finished(self) -> bool:
        """It ended, with a report or abandoned."""
        return self.report is not None or bool(self.abandoned)

    def __call__(self, rt: Any) -> None:
        if self.finished:
            return
        loop = rt.loop
        context = loop.context
        if self.routine is None:
            if (loop.ready and not context.goal_refusal and not loop.runner.active_goals()
                    and rt.rest.phase is Phase.RUNNING
                    and context.q[2] >= STANDING_HEIGHT_M):
                self.routine = StandingCalibration(duration_s=self.duration_s)
                loop.hooks.append(self.routine)
                context.goal_refusal = CALIBRATING
                self.say(f"calibrating the sensors while standing ({self.duration_s:g} s: the "
                         "centre of mass circles; goals are refused meanwhile)")
            return
        if self.routine.done:
            self._end(loop)
            self.report = self.routine.report
            for line in self.report.describe().splitlines():  # type: ignore[union-attr]
                self.say(line)
        elif context.goal_refusal != CALIBRATING or rt.rest.phase is not Phase.RUNNING:
            self.routine.cancel(loop.controller)
            self._end(loop)
            self.abandoned = context.goal_refusal or f"stopping ({rt.rest.phase.name})"
            self.say(f"calibration abandoned ({self.abandoned}): the estimator keeps "
                     f"{loop.estimator.foot_calibration.describe()}")

    def _end(self, loop: ControlLoop) -> None:
        loop.hooks.remove(self.routine)
        if loop.context.goal_refusal == CALIBRATING:
            loop.context.goal_refusal = ""
