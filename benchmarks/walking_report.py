"""The walking benchmark's report as text: speed tracking, pushes, the tick's cost."""

from __future__ import annotations

import math
from typing import Any

#: The commanded components' names, their units.
_AXES = (("forward", "m/s"), ("lateral", "m/s"), ("yaw rate", "rad/s"))


def _number(value: float, spec: str) -> str:
    return "-" if value is None or not math.isfinite(value) else format(value, spec)


def tracking_error(row: dict[str, Any]) -> str:
    """Each commanded component's error relative to the command, in percent
    (``forward -3.2 %``); a walk on the spot: its largest speed [m/s]."""
    parts = []
    for k, (name, _) in enumerate(_AXES):
        if row["command"][k]:
            error = 100.0 * row["relative_error"][k]
            parts.append(f"{name} {error:+.1f} %" if math.isfinite(error) else f"{name} -")
    return ", ".join(parts) or "in place"


def format_report(report: dict[str, Any]) -> str:
    """The three tables as text, with the machine and its load."""
    m = report["machine"]
    versions = ", ".join(f"{k} {v}" for k, v in m["versions"].items() if v)
    lines = [(f"Machine: {m['cpu']}, {m['cores']} cores, load "
              f"{m['load_average_1_5_15_min'][0]:.2f} at start, Python {m['python']}; "
              f"{versions}"),
             (f"Mode: {report['mode']}. Walk goals of {report['walk_s']:g} s on the menagerie "
              "plant, go2 sensors; measured on the simulator's truth, the mean over the "
              f"walking phase from {report['settle_into_walk_s']:g} s after it began")]
    if "tracking" in report:
        lines += ["", *tracking_lines(report["tracking"])]
    if "pushes" in report:
        lines += ["", *push_lines(report["pushes"])]
    if "timing" in report:
        lines += ["", *timing_lines(report["timing"])]
    return "\n".join(lines)


def tracking_lines(tracking: list[dict[str, Any]]) -> list[str]:
    """The speed-tracking table."""
    lines = ["Speed tracking (velocities in the heading frame)"]
    head = (f"{'command':<17}{'state':<9}{'Hz':>5} {'status':<10}{'fell':<5}{'forward':>8}"
            f"{'lateral':>8}{'yaw':>7}  {'error against the command':<28}{'yaw drift':>9}"
            f"{'height':>7}{'range':>6}")
    units = (f"{'':<47}{'[m/s]':>8}{'[m/s]':>8}{'[rad/s]':>7}  {'':<28}{'[deg]':>9}"
             f"{'[m]':>7}{'[mm]':>6}")
    lines += [head, units, "-" * len(head)]
    for row in tracking:
        measured = row["measured"]
        lines.append(
            f"{row['name']:<17}{row['state']:<9}{row['control_rate_hz']:>5.0f} "
            f"{row['status']:<10}"
            f"{'yes' if row['fell'] else 'no':<5}{_number(measured[0], '.3f'):>8}"
            f"{_number(measured[1], '.3f'):>8}{_number(measured[2], '.3f'):>7}  "
            f"{tracking_error(row):<28}{_number(row['yaw_drift_deg'], '+.1f'):>9}"
            f"{_number(row['height_mean_m'], '.3f'):>7}"
            f"{_number(row['height_range_mm'], '.0f'):>6}")
    lines += [f"  {row['name']} on the {row['state']} at {row['control_rate_hz']:g} Hz: "
              f"{row['status']}: {row['message']}"
              for row in tracking if row["status"] != "SUCCEEDED"]
    return lines


def push_lines(pushes: dict[str, Any]) -> list[str]:
    """The pushes' table."""
    force_n = pushes["impulse_ns"] / pushes["duration_s"]
    lines = [(f"Pushes of {pushes['impulse_ns']:g} N s ({force_n:g} N for "
              f"{pushes['duration_s']:g} s) on the base while trotting at "
              f"{pushes['speed_mps']:g} m/s on the estimate, directions from the heading "
              f"(0 forward, 90 left), at seeded instants (seed {pushes['seed']})"),
             (f"{'direction [deg]':<16}{'at [s]':>7}  {'status':<10}{'fell':<5}"
              f"{'min height [m]':>15}{'max tilt [deg]':>15}")]
    for row in pushes["runs"]:
        lines.append(f"{row['direction_deg']:<16}{row['at_s']:>7.2f}  {row['status']:<10}"
                     f"{'yes' if row['fell'] else 'no':<5}{row['min_height_m']:>15.3f}"
                     f"{row['max_tilt_deg']:>15.1f}")
    lines += [f"  toward {row['direction_deg']} deg: {row['status']}: {row['message']}"
              for row in pushes["runs"] if row["status"] != "SUCCEEDED"]
    lines.append(f"fell in {pushes['fell']} of {len(pushes['runs'])}")
    return lines


def timing_lines(timing: dict[str, Any]) -> list[str]:
    """The tick's cost and the real-time factors."""
    lines = [(f"The tick at {timing['control_rate_hz']:g} Hz, walking forward 0.5 m/s for "
              f"{timing['walk_s']:g} s and standing, in lockstep (turns of "
              f"{timing['runs'][0]['lockstep']['turn_ticks']} ticks) [us]; the walking tick "
              "also on the thread's CPU time"),
             (f"{'state':<10}{'part':<12}{'walking':>8}{'p99':>8}{'cpu':>8}{'cpu p99':>8}"
              f"{'standing':>9}{'p99':>8}   {'walking/standing per turn p10-p50-p90'}")]
    for row in timing["runs"]:
        turns = row["lockstep"]
        for part, s in turns["walking_us"].items():
            c, st = row["walking_ticks_cpu_us"][part], turns["standing_us"][part]
            low, mid, high = turns["turn_ratios"][part]
            lines.append(f"{row['state']:<10}{part:<12}{_number(s['median'], '.1f'):>8}"
                         f"{_number(s['p99'], '.1f'):>8}{_number(c['median'], '.1f'):>8}"
                         f"{_number(c['p99'], '.1f'):>8}{_number(st['median'], '.1f'):>9}"
                         f"{_number(st['p99'], '.1f'):>8}   {_number(low, '.2f')}-"
                         f"{_number(mid, '.2f')}-{_number(high, '.2f')}")
    lines.append("")
    lines.append("Real-time factor (ControlLoop.spin_once, goal to result, no instrument; "
                 "rounds of a walk then standing as long, medians):")
    for row in timing["runs"]:
        rounds = row["rounds"]
        walking = [r["walking"] for r in rounds]
        standing = [r["standing"] for r in rounds]
        ratios = [r["walking"] / r["standing"] for r in rounds]
        lines.append(
            f"  {row['state']}: walking {row['real_time_factor']:.2f} ({len(rounds)} rounds "
            f"{min(walking):.2f}-{max(walking):.2f}; sim time over CPU time "
            f"{row['sim_over_cpu']:.2f}, cpu share {row['cpu_share']:.2f}, {row['status']}); "
            f"standing {row['standing_real_time_factor']:.2f} ({min(standing):.2f}-"
            f"{max(standing):.2f}; over CPU time {row['standing_sim_over_cpu']:.2f}); "
            f"walking/standing per round {min(ratios):.2f}-{max(ratios):.2f}")
    return lines
