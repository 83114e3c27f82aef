"""``go2-wbc run --dds --ros2`` against the simulated GO2 on DDS (``go2-wbc bridge``): the ROS 2
tutorial's high five client SUCCEEDS across four processes (bridge, controller node, client),
judged on the bridge's truth."""

from __future__ import annotations

import json
from pathlib import Path

from benchmarks.dds_processes import DdsProcesses, ManagedProcess, private_domain_id
from sim.cli.exit_codes import EXIT_INTERRUPTED
from sim.dds_evaluation import goal_runs
from tests.ros2.conftest import client_argv

#: Longest wait [s] for the client's result (imports on a loaded machine included).
CLIENT_TIMEOUT_S = 120.0


def test_the_tutorial_client_s_high_five_succeeds_on_the_controller_on_dds(
        tmp_path: Path) -> None:
    with DdsProcesses(tmp_path, domain_id=private_domain_id(7)) as run:
        bridge = run.bridge()
        controller = run.controller("--ros2")
        assert "ROS 2 node /go2_wbc (RMW rmw_fastrtps_cpp): actions /high_five" in (
            controller.output())
        client = ManagedProcess("client", client_argv("tutorial_high_five_client.py"),
                                output_path=run.path("client.out"))
        run.processes.append(client)
        code = client.wait(CLIENT_TIMEOUT_S)
        assert controller.stop() == EXIT_INTERRUPTED, controller.tail()
        assert bridge.stop() == 0, bridge.tail()
    assert code == 0, client.tail()
    events = [json.loads(line) for line in client.output().splitlines()
              if line.startswith("{")]
    result = events[-1]
    assert result["event"] == "result" and result["status"] == 4 and result["success"], result
    five = [r for r in goal_runs(controller.log_path, bridge.log_path)
            if r.action == "high_five"]
    assert len(five) == 1
    print(f"\nrun --dds --ros2: raised foot {five[0].raised_foot_rms_mm:.2f} mm RMS, tilt "
          f"{five[0].max_tilt_deg:.2f} deg on the bridge's truth")
    assert five[0].raised_foot_rms_mm <= 5.0
    assert five[0].max_tilt_deg <= 3.0
    assert five[0].on_four_feet
