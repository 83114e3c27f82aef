"""The sweep's tables and heat maps, from records laid out by the swept fields."""

from __future__ import annotations

from benchmarks.sweep_report import SweepReport
from benchmarks.sweep_spec import DIRECTIONS, IMPULSES, SweepSpec

PUSHES = {"pushes": {"directions_deg": [0, 90, 315], "impulses_ns": [4, 8]}, "metrics": False}


def records(spec: SweepSpec, outcome) -> dict:
    """A record per episode whose outcome is ``outcome(episode)`` (``E``: an error)."""
    out = {}
    for episode in spec.episodes():
        letter = outcome(episode)
        if letter == "E":
            out[episode.key] = {"key": episode.key, "error": "RuntimeError: boom"}
            continue
        impulse = episode.get(IMPULSES, 0.0)
        result = {"outcome": letter, "min_height_m": 0.3 - 0.01 * impulse,
                  "max_tilt_deg": impulse}
        if episode.get("metrics"):
            result.update(tracking_rms_mm=1.5, stance_sliding_max_mm=0.2, qp_failures=0)
        out[episode.key] = {"key": episode.key, "result": result}
    return out


def corner(episode) -> str:
    return "A" if (episode.get(DIRECTIONS), episode.get(IMPULSES)) == (315.0, 8.0) else "S"


def test_one_case_prints_the_robustness_benchmarks_grid():
    spec = SweepSpec.from_mapping(PUSHES, name="pushes")
    report = SweepReport(spec, records(spec, corner))
    assert report.table().splitlines() == [
        ("Pushes on the base during the hold (0.1 s, starting 0.2 s into a 1 s hold of a 0.40 m "
         "high five)"),
        "S succeeded, A aborted (foot put down, robot up), F fell",
        "",
        "impulse [N s] | direction [deg]",
        "              |    0   90  315",
        "            4 |    S    S    S",
        "            8 |    S    S    A",
        "",
        "succeeded 5/6 (83 %), aborted 1, fell 0; any fall: no"]


def test_cases_are_counted_per_cell_and_per_row():
    spec = SweepSpec.from_mapping({**PUSHES, "metrics": True,
                                   "plant": {"payload_kg": [0, 2]}}, name="payload")

    def outcome(episode):
        if episode.get("plant.payload_kg") == 2.0 and episode.get(IMPULSES) == 8.0:
            return {0.0: "F", 90.0: "E", 315.0: "A"}[episode.get(DIRECTIONS)]
        return corner(episode)

    report = SweepReport(spec, records(spec, outcome))
    lines = report.table().splitlines()
    assert lines[1] == ("S succeeded, A aborted (foot put down, robot up), F fell, E error; "
                        "each cell: the outcomes of its 2 cases (plant.payload_kg)")
    assert lines[4:7] == ["              |    0   90  315",
                          "            4 |   2S   2S   2S",
                          "            8 | 1S1F 1S1E   2A"]
    assert lines[10:14] == [
        "plant.payload_kg | runs   S   A   F   E |  min z  tilt track RMS sliding QP fail",
        "                 |                      |    [m] [deg]      [mm]    [mm]",
        "               0 |    6   5   1   0   0 |  0.220   8.0      1.50    0.20       0",
        "               2 |    6   3   1   1   1 |  0.220   8.0      1.50    0.20       0"]
    assert lines[-2:] == [
        "succeeded 8/12 (67 %), aborted 2, fell 1; any fall: yes; errors 1",
        "fell at: plant.payload_kg=2, pushes.impulses_ns=8, pushes.directions_deg=0"]
    grid, payload = report.panels()
    assert (grid.x, grid.y) == (DIRECTIONS, IMPULSES)
    assert grid.text()["0", "8"] == "1S1F"
    assert (payload.x, payload.y) == ("plant.payload_kg", IMPULSES)
    assert payload.text() == {("0", "4"): "3S", ("0", "8"): "2S1A", ("2", "4"): "3S",
                              ("2", "8"): "1A1F1E"}


def test_pairs_of_plant_fields_get_a_heat_map_each(tmp_path):
    spec = SweepSpec.from_mapping({"metrics": False, "plant": {
        "joint_damping": [1, 2, 3], "payload_kg": [0, 2], "delay_ticks": [0, 2]}})
    report = SweepReport(spec, records(spec, lambda e: "F" if e.get("plant.joint_damping") == 3
                                       and e.get("plant.delay_ticks") == 2 else "S"))
    panels = report.panels()
    assert [(p.x, p.y) for p in panels] == [
        ("plant.joint_damping", "plant.payload_kg"), ("plant.joint_damping", "plant.delay_ticks"),
        ("plant.payload_kg", "plant.delay_ticks")]
    assert panels[1].text()["3", "2"] == "2F" and panels[1].text()["3", "0"] == "2S"
    assert report.table().splitlines()[0].startswith("Cases (every episode;")
    path = report.write_heat_map(tmp_path / "plots" / "sweep.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 10_000


def test_episodes_without_a_record_count_as_not_run():
    spec = SweepSpec.from_mapping(PUSHES)
    done = dict(list(records(spec, corner).items())[:4])
    report = SweepReport(spec, done)
    assert report.counts() == {"S": 4, "-": 2}
    assert report.table().splitlines()[-1] == (
        "succeeded 4/6 (67 %), aborted 0, fell 0; any fall: no; not run 2")
