"""Real-time scheduling for the bridge and the controller process (SCHED_FIFO when permitted)."""

import subprocess
import sys

import pytest

from actions.robot.realtime_priority import check_priority, in_realtime, request_realtime
from sim.cli import main
from wbc.core.errors import ConfigurationError

_CHILD = """
import threading
from actions.robot.realtime_priority import in_realtime, request_realtime
said = request_realtime(7)
inherited = []
worker = threading.Thread(target=lambda: inherited.append(in_realtime()))
worker.start(); worker.join()
print(said); print(in_realtime(), inherited[0])
"""


def test_zero_leaves_the_scheduling_as_it_is():
    before = in_realtime()
    assert request_realtime(0) == "scheduling: ordinary (--rt-priority 0)"
    assert in_realtime() == before


@pytest.mark.parametrize("bad", [-1, 100, 2.5, True, "50"])
def test_a_priority_out_of_range_names_what_is_valid(bad):
    with pytest.raises(ConfigurationError, match=r"^priority: expected a whole number in "
                                                 r"\[0, 99\] \(0: ordinary scheduling\), "
                                                 rf"received {bad!r}"):
        check_priority(bad)


def test_real_time_when_permitted_and_the_threads_started_after_inherit_it():
    """In a child process (the test process keeps its scheduling): it either runs under
    SCHED_FIFO, with the threads it starts afterwards, or says why not and runs as before."""
    done = subprocess.run([sys.executable, "-c", _CHILD], capture_output=True, text=True,
                          timeout=60, check=True)
    said, flags = done.stdout.strip().splitlines()
    if said == "scheduling: real-time, SCHED_FIFO priority 7":
        assert flags == "True True"
    else:
        assert said.startswith("scheduling: ordinary (SCHED_FIFO 7 ") and flags == "False False"


def test_the_command_line_refuses_a_bad_priority(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["run", "--dds", "--rt-priority", "100"])
    assert exit_info.value.code == 2
    assert ("--rt-priority: expected a SCHED_FIFO priority in [0, 99] (0: ordinary "
            "scheduling), received '100'") in capsys.readouterr().err
