"""The robustness benchmark's report as text: the push grid and the plant and sweep tables."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from benchmarks.plant_cases import SWEEP_HOLD_S
from sim.episode import episode_default


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def push_grid_lines(directions: Sequence[str], impulses: Sequence[str],
                    cell: Callable[[str, str], str]) -> list[str]:
    """The push grid as text: a row per impulse, a column per direction, each cell
    ``cell(impulse, direction)`` (columns at least 4 characters wide)."""
    width = max(4, *(len(cell(i, d)) for i in impulses for d in directions)) + 1
    lines = ["impulse [N s] | direction [deg]",
             "              |" + "".join(f"{d:>{width}}" for d in directions)]
    for impulse in impulses:
        lines.append(f"{impulse:>13} |" + "".join(
            f"{cell(impulse, d):>{width}}" for d in directions))
    return lines


def format_report(report: dict[str, Any]) -> str:
    """The two tables as text."""
    grid = report["push_grid"]
    title = (f"Pushes on the base during the hold ({grid['duration_s']:g} s, starting "
             f"{grid['starts_into_hold_s']:g} s into a {report['goal']['hold_s']} s hold of a "
             f"{report['goal']['target_height_m']:.2f} m high five)")
    outcome = {(f"{c['impulse_ns']:g}", str(c["direction_deg"])): c["outcome"]
               for c in grid["cells"]}
    lines = [(f"State: estimated ({episode_default('estimator')}) from the "
              f"{episode_default('sensors')} sensors unless "
              "a row says otherwise; everything measured on the simulator's truth"), "",
             title, "S succeeded, A aborted (foot put down, robot up), F fell", "",
             *push_grid_lines([str(d) for d in grid["directions_deg"]],
                              [f"{i:g}" for i in grid["impulses_ns"]],
                              lambda impulse, direction: outcome[impulse, direction])]
    total = len(grid["cells"])
    lines += ["", f"succeeded {grid['succeeded']}/{total} ({100 * grid['success_rate']:.0f} %), "
              f"aborted {grid['aborted']}, fell {grid['fell']}; any fall: "
              f"{_yes(grid['any_fall'])}" + "".join(
                  f"; fell at {c['impulse_ns']:g} N s toward {c['direction_deg']} deg"
                  for c in grid["cells"] if c["outcome"] == "F"), "",
              "Plant changes (no push)", ""]
    header = (f"{'plant change':<66} {'result':<9} {'track RMS':>9} {'hold RMS':>8} "
              f"{'sliding':>7} {'min z':>5} {'tilt':>5} {'end tilt':>8} {'QP fail':>7} "
              f"{'standing':>8} {'fell':>4}")
    units = (f"{'':<66} {'':<9} {'[mm]':>9} {'[mm]':>8} {'[mm]':>7} {'[m]':>5} {'[deg]':>5} "
             f"{'[deg]':>8}")
    lines += [header, units]
    for row in report["plant_changes"]:
        lines.append(f"{row['name']:<66} {row['status']:<9} {row['tracking_rms_mm']:>9.2f} "
                     f"{row['holding_rms_mm']:>8.2f} {row['stance_sliding_max_mm']:>7.2f} "
                     f"{row['min_height_m']:>5.3f} {row['max_tilt_deg']:>5.1f} "
                     f"{row['final_tilt_deg']:>8.1f} {row['qp_failures']:>7} "
                     f"{_yes(row['standing']):>8} {_yes(row['fell']):>4}")
    for key, title in (("joint_sweep", "Joint friction sweep (Menagerie contacts)"),
                       ("calf_sweep", "Calf friction sweep (identified joints)")):
        sweep = report[key]
        lines += ["", f"{title}, {SWEEP_HOLD_S} s hold, {sweep['wall_s']:g} s wall", "",
                  (f"{'plant':<40} {'result':<9} {'track RMS':>9} {'hold RMS':>8} "
                   f"{'sliding':>7} {'tilt':>5} {'end tilt':>8} {'QP fail':>7}")]
        for row in sweep["rows"]:
            lines.append(f"{row['name']:<40} {row['status']:<9} {row['tracking_rms_mm']:>9.2f} "
                         f"{row['holding_rms_mm']:>8.2f} {row['stance_sliding_max_mm']:>7.2f} "
                         f"{row['max_tilt_deg']:>5.2f} {row['final_tilt_deg']:>8.2f} "
                         f"{row['qp_failures']:>7}")
        lines.append(f"succeeded {sweep['succeeded']}/{len(sweep['rows'])}, max tilt "
                     f"{sweep['max_tilt_deg']:.2f} deg, worst end tilt "
                     f"{sweep['max_final_tilt_deg']:.2f} deg")
    if "compensation" in report:
        lines += ["", "Known joint friction fed forward (known_joint_damping/_friction)", "",
                  (f"{'plant':<32} {'friction':<8} {'result':<9} {'track RMS':>9} "
                   f"{'hold RMS':>8} {'sliding':>7} {'tilt':>5} {'end tilt':>8}")]
        for row in report["compensation"]["rows"]:
            lines.append(f"{row['name']:<32} {'known' if row['known_friction'] else 'unknown':<8} "
                         f"{row['status']:<9} {row['tracking_rms_mm']:>9.2f} "
                         f"{row['holding_rms_mm']:>8.2f} {row['stance_sliding_max_mm']:>7.2f} "
                         f"{row['max_tilt_deg']:>5.2f} {row['final_tilt_deg']:>8.2f}")
    return "\n".join(lines)
