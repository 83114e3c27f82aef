"""The QP benchmark's report as text and as a plot of the tick-time distributions."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.lift_timing import STAGES
from benchmarks.tsid_row import format_tsid_row


def _fmt(value: Any, digits: int = 0) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}" if digits >= 0 else f"{value:.1e}"
    return str(value)


def backend_line(row: dict[str, Any]) -> str:
    """One backend's row of the tick-time table, or ``skipped: <reason>`` (one line)."""
    if row["skipped"]:
        return f"{row['name']:<22}skipped: {row['skipped']}"
    st = row["stage_median_us"]
    return (f"{row['name']:<22}{row['ticks']:>6}{_fmt(st['model']):>7}"
            f"{_fmt(st['assembly']):>7}{_fmt(st['solve']):>8}{_fmt(row['median_us']):>8}"
            f"{_fmt(row['p90_us']):>8}{_fmt(row['p99_us']):>8}{_fmt(row['max_us']):>8}"
            f"{_fmt(row['max_eq_violation'], -1):>9}{_fmt(row['max_ineq_violation'], -1):>10}"
            f"{row['failures']:>5}{_fmt(row['ratio_to_placo'], 2):>8}"
            f"{_fmt(row['cpu_median_us']):>8}{_fmt(row['cpu_ratio_to_placo'], 2):>8}"
            f"{_fmt(100 * row['cpu_share']):>5}")


def format_report(report: dict[str, Any]) -> str:
    """The tables as plain text."""
    m = report["machine"]
    versions = ", ".join(f"{k} {v}" for k, v in m["versions"].items() if v)
    load = m["load_average_1_5_15_min"][0]
    lines = [(f"Machine: {m['cpu']}, {m['cores']} cores, load {load:.2f} at start, "
             f"Python {m['python']}; {versions}"),
             f"Mode: {report['mode']}. {report['episode']['description']}", ""]
    head = (f"{'backend':<22}{'ticks':>6}{'model':>7}{'asm':>7}{'solve':>8}"
            f"{'median':>8}{'p90':>8}{'p99':>8}{'max':>8}{'eq viol':>9}{'ineq viol':>10}"
            f"{'fail':>5}{'x PlaCo':>8}{'cpu med':>8}{'x PlaCo':>8}{'cpu%':>5}")
    lines += ["Tick time [us] per backend (stage columns: medians)", head, "-" * len(head)]
    lines += [backend_line(row) for row in report["backends"]]
    h2h = report["head_to_head"]
    d, p = h2h["default"], h2h["placo"]
    low, mid, high = h2h["block_ratio_p10_p50_p90"]
    lines += ["", (f"Head to head, the same lift in lockstep (turns of {h2h['block_ticks']} "
                   f"ticks): default median {d['median']:.0f} us (p99 {d['p99']:.0f}), PlaCo "
                   f"median {p['median']:.0f} us (p99 {p['p99']:.0f}): ratio of medians "
                   f"{h2h['median_ratio']:.2f}; per turn p10/p50/p90 {low:.2f}/{mid:.2f}/"
                   f"{high:.2f}")]
    rec = report["recorded"]
    lines += ["", (f"Alone, on the recorded states of one lift ({rec['ticks']} ticks, no "
                   "simulation between ticks): tick time [us]")]
    head = f"{'controller':<26}{'model':>7}{'asm':>7}{'solve':>8}{'median':>8}{'p90':>8}{'p99':>8}"
    lines += [head, "-" * len(head)]
    for name, row in rec["rows"].items():
        st = row["stage_median_us"]
        lines.append(f"{name:<26}{_fmt(st.get('model')):>7}{_fmt(st.get('assembly')):>7}"
                     f"{_fmt(st.get('solve')):>8}{_fmt(row['median_us']):>8}"
                     f"{_fmt(row['p90_us']):>8}{_fmt(row['p99_us']):>8}")
    lines += ["", "Scaling: tick time [us] vs contacts and tasks"]
    head = (f"{'controller':<16}{'scenario':<44}{'QP':<36}{'ticks':>6}{'median':>8}{'p90':>8}"
            f"{'p99':>8}{'cpu med':>8}{'x PlaCo':>8}{'turns p10/p50/p90':>19}")
    lines += [head, "-" * len(head)]
    for row in report["scaling"]:
        # Reports written before the scaling ran in turns have no ratio.
        turns = row.get("block_ratio_p10_p50_p90")
        lines.append(f"{row['controller']:<16}{row['scenario']:<44}{row['qp']:<36}"
                     f"{row['ticks']:>6}{_fmt(row['median_us']):>8}{_fmt(row['p90_us']):>8}"
                     f"{_fmt(row['p99_us']):>8}{_fmt(row['cpu_median_us']):>8}"
                     f"{_fmt(row.get('ratio_to_placo'), 2):>8}"
                     f"{'/'.join(f'{r:.2f}' for r in turns) if turns else '-':>19}")
    if "tsid" in report:  # reports written before the TSID row have none
        lines += ["", format_tsid_row(report["tsid"])]
    ep = report["episode_table"]
    lines += ["", f"Episode quality, {ep['controller']} ({ep['description']})"]
    for key, value in ep["metrics"].items():
        lines.append(f"  {key:<30}{_fmt(value, 3) if isinstance(value, float) else value}")
    lines += ["", *[f"Note: {n}" for n in report["notes"]]]
    return "\n".join(lines)


def plot(report: dict[str, Any], path: Path) -> None:
    """Tick-time distribution per backend (box plot, log scale) and the median stages."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in report["backends"] if not r["skipped"]]
    fig, (left, right) = plt.subplots(1, 2, figsize=(14, 5.5),
                                      gridspec_kw={"width_ratios": [3, 2]})
    left.boxplot([r["total_samples_us"] for r in rows], whis=(1, 99), showfliers=True,
                 flierprops={"markersize": 2, "alpha": 0.3})
    left.set_xticks(range(1, len(rows) + 1), [r["name"] for r in rows], rotation=35,
                    ha="right")
    left.set_yscale("log")
    left.set_ylabel("tick time [us] (whiskers: p1-p99)")
    left.set_title(f"Control tick, closed-loop high five ({report['mode']} mode)")
    left.grid(True, which="both", axis="y", alpha=0.3)
    bottom = np.zeros(len(rows))
    for stage in STAGES[:-1]:
        values = np.array([r["stage_median_us"][stage] or 0.0 for r in rows])
        right.barh(range(len(rows)), values, left=bottom, label=stage)
        bottom += values
    right.set_yticks(range(len(rows)), [r["name"] for r in rows])
    right.set_xlabel("median stage time [us] (stacked; stages a controller reports)")
    right.legend(loc="lower right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
