"""A sweep's summary: the outcome tables (as the robustness benchmark prints them) and heat maps."""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.robustness_report import push_grid_lines
from benchmarks.sweep_spec import DIRECTIONS, IMPULSES, EpisodeSpec, SweepSpec, value_text

#: Outcomes from worst to best: E the episode raised, F fell, A aborted with the robot up,
#: S succeeded; ``-`` not run (yet).
OUTCOMES = ("E", "F", "A", "S", "-")
OUTCOME_NAMES = {"S": "succeeded", "A": "aborted, robot up", "F": "fell", "E": "error",
                 "-": "not run"}
#: Heat-map colours (colour-blind safe: blue, orange, vermilion, grey).
COLOURS = {"S": "#56B4E9", "A": "#E69F00", "F": "#D55E00", "E": "#999999", "-": "#FFFFFF"}
#: Axis titles of the fields tables and plots name often.
TITLES = {DIRECTIONS: "direction [deg]", IMPULSES: "impulse [N s]"}


def outcome_of(record: Mapping[str, Any] | None) -> str:
    """``S``, ``A``, ``F`` from a record's result, ``E`` for an error, ``-`` without a record."""
    if record is None:
        return "-"
    if "result" not in record:
        return "E"
    return record["result"]["outcome"]


def cell_text(counts: Counter[str]) -> str:
    """One episode: its letter; more: counts, worst last (``3S1A``)."""
    if sum(counts.values()) == 1:
        return next(iter(counts))
    return "".join(f"{counts[o]}{o}" for o in reversed(OUTCOMES) if counts[o])


@dataclass
class Panel:
    """One heat map: outcomes counted per (x value, y value), over every other field."""

    x: str
    x_values: tuple[Any, ...]
    y: str
    y_values: tuple[Any, ...]
    cells: dict[tuple[Any, Any], Counter[str]] = field(default_factory=dict)

    def text(self) -> dict[tuple[str, str], str]:
        """Each cell's text by its values as shown: ``{("90", "8"): "S"}``."""
        return {(value_text(x), value_text(y)): cell_text(c) for (x, y), c in self.cells.items()}


class SweepReport:
    """The outcomes of a sweep's episodes, laid out by its swept fields.

    Args:
        spec: The sweep.
        records: Records by episode key (:meth:`benchmarks.sweep_results.SweepResults.load`
            or the run's own); an episode without one counts as not run.
    """

    def __init__(self, spec: SweepSpec, records: Mapping[str, Mapping[str, Any]]) -> None:
        self.spec = spec
        self.rows: list[tuple[EpisodeSpec, Mapping[str, Any] | None]] = [
            (episode, records.get(episode.key)) for episode in spec.episodes()]

    def counts(self) -> Counter[str]:
        """Episodes per outcome."""
        return Counter(outcome_of(record) for _, record in self.rows)

    # ------------------------------------------------------------------ heat maps

    def panels(self) -> list[Panel]:
        """Direction x impulse (with pushes), then every pair of the other swept fields.

        A single other swept field is laid out against the impulse (or alone).
        """
        spec = self.spec
        directions, impulses = spec.axis(DIRECTIONS), spec.axis(IMPULSES)
        pairs: list[tuple[str, str | None]] = []
        if directions is not None and impulses is not None:
            pairs.append((DIRECTIONS, IMPULSES))
        others = [a.path for a in spec.case_axes]
        pairs += list(itertools.combinations(others, 2))
        if len(others) == 1:
            pairs.append((others[0], IMPULSES if impulses is not None else None))
        if not pairs:
            pairs.append((DIRECTIONS, IMPULSES) if directions is not None else ("seed", None))
        panels = []
        for x, y in pairs:
            x_values = spec.axis(x).values
            y_values = spec.axis(y).values if y is not None else ("all",)
            panel = Panel(x, x_values, y or "", y_values)
            for episode, record in self.rows:
                where = (episode.get(x), episode.get(y) if y is not None else "all")
                panel.cells.setdefault(where, Counter())[outcome_of(record)] += 1
            panels.append(panel)
        return panels

    def write_heat_map(self, path: str | Path) -> Path:
        """Draw :meth:`panels` into a PNG at ``path``; returns the path."""
        import matplotlib

        matplotlib.use("Agg")  # files only: no display needed
        import matplotlib.pyplot as plt
        from matplotlib.patches import Patch

        panels = self.panels()
        widths = [max(3.0, 0.75 * len(p.x_values) + 1.6) for p in panels]
        height = max(2.4, 0.5 * max(len(p.y_values) for p in panels) + 1.8)
        fig, axes = plt.subplots(1, len(panels), figsize=(sum(widths), height),
                                 gridspec_kw={"width_ratios": widths}, squeeze=False)
        for ax, panel in zip(axes[0], panels):
            self._draw(ax, panel)
        present = [o for o in reversed(OUTCOMES) if o in "SAF" or self.counts()[o]]
        fig.legend(handles=[Patch(facecolor=COLOURS[o], edgecolor="0.3",
                                  label=f"{o} {OUTCOME_NAMES[o]}") for o in present],
                   loc="lower center", ncol=len(present), frameon=False)
        total = len(self.rows)
        fig.suptitle(f"{self.spec.name}: {total} episodes; a cell holding several is split by "
                     f"their outcomes (counts on it)", fontsize=10)
        fig.tight_layout(rect=(0, 0.08, 1, 0.93))
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=110)
        plt.close(fig)
        return path

    @staticmethod
    def _draw(ax: Any, panel: Panel) -> None:
        """Each cell split left to right by its outcomes' shares (S, A, F, E), counts on top."""
        from matplotlib.patches import Rectangle

        nx, ny = len(panel.x_values), len(panel.y_values)
        for i, y in enumerate(panel.y_values):
            for j, x in enumerate(panel.x_values):
                counts = panel.cells.get((x, y), Counter({"-": 1}))
                left, total = j - 0.5, sum(counts.values())
                for outcome in reversed(OUTCOMES):
                    width = counts[outcome] / total
                    if width:
                        ax.add_patch(Rectangle((left, i - 0.5), width, 1.0, linewidth=0,
                                               facecolor=COLOURS[outcome]))
                        left += width
                text = cell_text(counts)
                ax.text(j, i, text, ha="center", va="center",
                        fontsize=9 if len(text) <= 2 else 7)
        ax.set_xlim(-0.5, nx - 0.5)
        ax.set_ylim(-0.5, ny - 0.5)
        ax.set_xticks(range(nx), [value_text(v) for v in panel.x_values])
        ax.set_yticks(range(ny), [value_text(v) for v in panel.y_values])
        ax.set_xlabel(TITLES.get(panel.x, panel.x))
        ax.set_ylabel(TITLES.get(panel.y, panel.y))
        for k in range(1, nx):
            ax.axvline(k - 0.5, color="white", linewidth=1.5)
        for k in range(1, ny):
            ax.axhline(k - 0.5, color="white", linewidth=1.5)

    # ------------------------------------------------------------------ tables

    def table(self) -> str:
        """The push grid (impulse rows x direction columns), the cases and the totals."""
        lines: list[str] = []
        if self.spec.axis(DIRECTIONS) is not None:
            lines += self._push_grid() + [""]
        if self.spec.case_axes or self.spec.axis(DIRECTIONS) is None:
            lines += self._cases() + [""]
        lines.append(self._totals())
        return "\n".join(lines)

    def _fixed(self, path: str) -> str | None:
        axis = self.spec.axis(path)
        return None if axis is None or axis.swept else value_text(axis.values[0])

    def _push_grid(self) -> list[str]:
        spec = self.spec
        duration, start = self._fixed("pushes.duration_s"), self._fixed("pushes.into_hold_s")
        hold, height = self._fixed("hold_s"), self._fixed("height_m")
        push = (f"{duration} s, starting {start} s into " if duration and start else "during ")
        goal = (f"a {hold} s hold of a {float(height):.2f} m high five" if hold and height
                else "the hold of the high five")
        cases = len(self.rows) // (len(spec.axis(DIRECTIONS).values)
                                   * len(spec.axis(IMPULSES).values))
        over = (f"; each cell: the outcomes of its {cases} cases "
                f"({', '.join(a.path for a in spec.case_axes)})" if cases > 1 else "")
        panel = next(p for p in self.panels() if (p.x, p.y) == (DIRECTIONS, IMPULSES))
        texts = panel.text()
        return [f"Pushes on the base during the hold ({push}{goal})",
                (f"S succeeded, A aborted (foot put down, robot up), F fell"
                 f"{', E error' if self.counts()['E'] else ''}{over}"), "",
                *push_grid_lines([value_text(d) for d in panel.x_values],
                                 [value_text(i) for i in panel.y_values],
                                 lambda impulse, direction: texts[direction, impulse])]

    def _cases(self) -> list[str]:
        axes = [a.path for a in self.spec.case_axes]
        groups: dict[tuple[Any, ...], list[Mapping[str, Any] | None]] = {}
        for episode, record in self.rows:
            groups.setdefault(tuple(episode.get(p) for p in axes), []).append(record)
        results = [r["result"] for _, r in self.rows if r is not None and "result" in r]
        measured = any("tracking_rms_mm" in r for r in results)
        errors = self.counts()["E"] > 0
        names = axes or ["case"]
        widths = [max(len(n), 6) for n in names]
        header = " ".join(f"{n:>{w}}" for n, w in zip(names, widths))
        header += f" | {'runs':>4} {'S':>3} {'A':>3} {'F':>3}" + (f" {'E':>3}" if errors else "")
        header += f" | {'min z':>6} {'tilt':>5}"
        units = " ".join(" " * w for w in widths) + " | " + " " * (4 + 12 + (4 if errors else 0))
        units += f" | {'[m]':>6} {'[deg]':>5}"
        if measured:
            header += f" {'track RMS':>9} {'sliding':>7} {'QP fail':>7}"
            units += f" {'[mm]':>9} {'[mm]':>7} {'':>7}"
        over = ("outcomes over the pushes" if self.spec.axis(DIRECTIONS) is not None
                else "every episode")
        lines = [(f"Cases ({over}; min z: lowest base, tilt: largest; the worst of the case's "
                  "episodes)"), "", header, units.rstrip()]
        for values, records in groups.items():
            counts = Counter(outcome_of(r) for r in records)
            done = [r["result"] for r in records if r is not None and "result" in r]
            cells = [value_text(v) for v in values] or ["all"]
            line = " ".join(f"{c:>{w}}" for c, w in zip(cells, widths))
            line += (f" | {len(records):>4} {counts['S']:>3} {counts['A']:>3} {counts['F']:>3}"
                     + (f" {counts['E']:>3}" if errors else ""))
            line += (f" | {_extreme(done, 'min_height_m', min, 3):>6} "
                     f"{_extreme(done, 'max_tilt_deg', max, 1):>5}")
            if measured:
                line += (f" {_extreme(done, 'tracking_rms_mm', max, 2):>9} "
                         f"{_extreme(done, 'stance_sliding_max_mm', max, 2):>7} "
                         f"{_extreme(done, 'qp_failures', max, 0):>7}")
            lines.append(line)
        return lines

    def _totals(self) -> str:
        counts = self.counts()
        total = len(self.rows)
        text = (f"succeeded {counts['S']}/{total} ({100 * counts['S'] / total:.0f} %), aborted "
                f"{counts['A']}, fell {counts['F']}; any fall: {'yes' if counts['F'] else 'no'}")
        if counts["E"]:
            text += f"; errors {counts['E']}"
        if counts["-"]:
            text += f"; not run {counts['-']}"
        falls = [episode.label() for episode, record in self.rows if outcome_of(record) == "F"]
        if falls:
            shown = "; ".join(falls[:5]) + (f"; and {len(falls) - 5} more" if len(falls) > 5
                                             else "")
            text += f"\nfell at: {shown}"
        return text


def _extreme(rows: Sequence[Mapping[str, Any]], key: str, pick: Any, digits: int) -> str:
    values = [row[key] for row in rows if key in row]
    return f"{pick(values):.{digits}f}" if values else "-"
