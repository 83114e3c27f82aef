"""What ``go2-wbc`` prints: the state and plant lines, feedback, and the metrics' summary."""

from __future__ import annotations

import math
from typing import IO, TYPE_CHECKING

from sim.episode import Episode
from wbc.estimation.estimators import ESTIMATORS

if TYPE_CHECKING:
    from sim.episode_metrics import EpisodeSummary  # imports MuJoCo: not before MUJOCO_GL

#: Sim time [s] between refreshes of the progress line on a terminal.
PROGRESS_REFRESH_S = 0.25


def state_line(episode: Episode) -> str:
    """The first line a run prints: where the controller's state comes from, which sensors."""
    sensors = episode.sensor_model.describe()
    if episode.state == "truth":
        return ("state: the simulator's exact state (--state truth; a GO2 measures no base "
                f"position or velocity); {sensors} unused")
    faults = "".join(f"; fault: {fault.describe()}" for fault in episode.sensor_faults)
    changed = "".join(f", {name}={value}" for name, value in episode.estimator_params)
    return (f"state: estimated ({episode.estimator}, {ESTIMATORS[episode.estimator]}{changed}) "
            f"from {sensors}, seed {episode.sensor_seed}{faults}")


def plant_line(episode: Episode) -> str:
    """The second line: the plant, the control rate, the physics timestep and any delay."""
    line = (f"{episode.plant_model.describe()}; control {episode.control_rate_hz:g} Hz, "
            f"physics {episode.timestep_s * 1e3:g} ms")
    if episode.command_delay_ticks:
        line += f"; commands applied {episode.command_delay_s * 1e3:g} ms late"
    return line


def run_caption(episode: Episode) -> str:
    """The plot's second title line: the plant, the control rate, the state source, the
    estimator and the sensors (``plant menagerie, control 1000 Hz; state estimated by inekf
    from sensors go2, seed 0``)."""
    head = f"plant {episode.plant_model.name}, control {episode.control_rate_hz:g} Hz"
    if episode.state == "truth":
        return f"{head}; state: the simulator's truth (no estimator)"
    faults = "".join(f", fault {fault.kind} at {fault.at_s:g} s"
                     for fault in episode.sensor_faults)
    return (f"{head}; state estimated by {episode.estimator} from sensors "
            f"{episode.sensor_model.name}, seed {episode.sensor_seed}{faults}")


def metrics_text(summary: EpisodeSummary, *, raised: bool, estimated: bool) -> str:
    """The metrics' summary: a line, and one more on the estimate when the state is one."""
    s = summary
    parts = []
    if raised:
        parts.append(f"raised foot error RMS {s.raised_foot_rms_mm:.1f} mm "
                     f"(max {s.raised_foot_max_mm:.1f} mm)")
    parts += [f"stance sliding max {s.stance_sliding_max_mm:.2f} mm",
              f"min CoM margin {s.min_com_margin_mm:.0f} mm",
              f"max tilt {s.max_base_tilt_deg:.1f} deg",
              f"QP failures {s.qp_failures}"
              + (f" ({s.no_state_ticks} ticks damping without a trustworthy state)"
                 if s.no_state_ticks else ""),
              f"tick median {s.tick_median_us:.0f} us (p99 {s.tick_p99_us:.0f} us)",
              f"real-time factor {s.real_time_factor:.2f}"]
    text = "metrics: " + "; ".join(parts)
    if estimated:
        text += (f"\nestimate vs truth: base velocity error RMS "
                 f"{s.estimate_velocity_rms_m_s * 1e3:.1f} mm/s (max "
                 f"{s.estimate_velocity_max_m_s * 1e3:.1f}); height error max "
                 f"{s.estimate_height_max_mm:.2f} mm; roll / pitch error max "
                 f"{s.estimate_roll_max_deg:.2f} / {s.estimate_pitch_max_deg:.2f} deg; drift "
                 f"{s.estimate_horizontal_drift_mm:.1f} mm horizontal, "
                 f"{s.estimate_yaw_drift_deg:.2f} deg yaw")
    return text


class FeedbackPrinter:
    """Prints feedback: one line per phase, plus a refreshed progress line on a terminal."""

    def __init__(self, stream: IO[str], *, tty: bool):
        self.stream = stream
        self.tty = tty
        self.phase = ""
        self._shown_s = -math.inf
        self._progress_line = False

    def feedback(self, now_s: float, phase: str, progress: float, detail: str) -> None:
        """Show one feedback message received at sim time ``now_s`` [s]."""
        text = f"[{now_s:7.3f} s] {100 * progress:4.0f} %  {phase}"
        if detail:
            text += f"  ({detail})"
        if phase != self.phase:
            self.phase = phase
            self.line(text)
        elif self.tty and now_s - self._shown_s >= PROGRESS_REFRESH_S - 1e-9:
            bar = "#" * round(20 * progress)
            self.stream.write(f"\r\033[K{text}  [{bar:<20}]")
            self.stream.flush()
            self._progress_line = True
        else:
            return
        self._shown_s = now_s

    def line(self, text: str) -> None:
        """Print a line, replacing the progress line if one is showing."""
        if self._progress_line:
            self.stream.write("\r\033[K")
            self._progress_line = False
        self.stream.write(text + "\n")
        self.stream.flush()
