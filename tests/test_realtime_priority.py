"""Real-time scheduling of the bridge's and the controller's loops (SCHED_FIFO when
permitted, while the loop runs, all or nothing)."""

import os
import subprocess
import sys
import threading

import pytest

from actions.robot import realtime_priority
from actions.robot.realtime_priority import (
    RealtimeScheduling,
    Scheduling,
    check_priority,
    thread_scheduling,
)
from sim.cli import main
from wbc.core.errors import ConfigurationError

# A child process (the test process keeps its scheduling): a worker thread named as Cyclone
# names its receive thread, one named as its heartbeat thread; the scheduling of the three
# inside the block and after it.
_CHILD = """
import os, threading
from actions.robot.realtime_priority import RealtimeScheduling, thread_scheduling
ready, done, tids = threading.Event(), threading.Event(), {}
def worker(name):
    tids[name] = threading.get_native_id()
    with open(f"/proc/self/task/{tids[name]}/comm", "w") as comm:
        comm.write(name)
    if len(tids) == 2:
        ready.set()
    done.wait()
workers = [threading.Thread(target=worker, args=(n,)) for n in ("recv", "tev")]
for w in workers:
    w.start()
ready.wait()
def show():
    return " ".join(f"{p}/{q}" for p, q in (thread_scheduling(), thread_scheduling(tids["recv"]),
                                            thread_scheduling(tids["tev"])))
with RealtimeScheduling(7) as scheduling:
    inside = show()
print(scheduling.describe()); print(inside); print(show())
done.set()
for w in workers:
    w.join()
"""


def test_zero_changes_nothing():
    before = thread_scheduling()
    with RealtimeScheduling(0) as scheduling:
        assert thread_scheduling() == before
    assert scheduling == Scheduling(0) and not scheduling.realtime
    assert scheduling.describe() == "scheduling: ordinary (--rt-priority 0)"


@pytest.mark.parametrize("bad", [-1, 100, 2.5, True, "50"])
def test_a_priority_out_of_range_names_what_is_valid(bad):
    with pytest.raises(ConfigurationError, match=r"^priority: expected a whole number in "
                                                 r"\[0, 99\] \(0: ordinary scheduling\), "
                                                 rf"received {bad!r}"):
        check_priority(bad)
    with pytest.raises(ConfigurationError, match=r"^priority: "):
        RealtimeScheduling(bad)


def test_the_loop_and_the_dds_delivery_threads_run_real_time_inside_the_block_only():
    """Either SCHED_FIFO for the loop (7) and the receive thread (8), never for the others,
    and every thread as before after the block; or, where the machine refuses, nothing
    changed and the line says why."""
    done = subprocess.run([sys.executable, "-c", _CHILD], capture_output=True, text=True,
                          timeout=60, check=True)
    said, inside, after = done.stdout.strip().splitlines()
    fifo, other = os.SCHED_FIFO, os.SCHED_OTHER
    assert after == f"{other}/0 {other}/0 {other}/0"
    if said.startswith("scheduling: real-time"):
        assert said == ("scheduling: real-time while the loop runs, SCHED_FIFO 7 "
                        "(DDS delivery: recv 8)")
        assert inside == f"{fifo}/7 {fifo}/8 {other}/0"
    else:
        assert said == ("scheduling: ordinary (SCHED_FIFO 7 needs root or CAP_SYS_NICE; "
                        "deadlines may be missed on a busy machine)")
        assert inside == after


class _FakeKernel:
    """os's scheduling calls on a table of threads; refuses the ``refuse_at``-th set."""

    def __init__(self, tids, refuse_at=None):
        self.table = dict.fromkeys(tids, (os.SCHED_OTHER, 0))
        self.sets = 0
        self.refuse_at = refuse_at

    def getscheduler(self, tid):
        return self.table[tid][0]

    def getparam(self, tid):
        return os.sched_param(self.table[tid][1])

    def setscheduler(self, tid, policy, param):
        self.sets += 1
        if self.sets == self.refuse_at:
            raise PermissionError(1, "Operation not permitted")
        self.table[tid] = (policy, param.sched_priority)


@pytest.fixture
def fake_kernel(monkeypatch):
    def install(refuse_at=None):
        me = threading.get_native_id()
        kernel = _FakeKernel([me, 101, 102, 103], refuse_at)
        monkeypatch.setattr(realtime_priority, "_threads", lambda: [
            (me, "python"), (101, "recvUC"), (102, "recvMC"), (103, "gc")])
        monkeypatch.setattr(os, "sched_getscheduler", kernel.getscheduler)
        monkeypatch.setattr(os, "sched_getparam", kernel.getparam)
        monkeypatch.setattr(os, "sched_setscheduler", kernel.setscheduler)
        return me, kernel
    return install


def test_a_refusal_part_way_leaves_every_thread_as_it_was(fake_kernel):
    _me, kernel = fake_kernel(refuse_at=3)  # the loop and recvUC promoted, then refused
    before = dict(kernel.table)
    with RealtimeScheduling(20) as scheduling:
        assert kernel.table == before
    assert not scheduling.realtime and scheduling.promoted == ()
    assert scheduling.refused == "SCHED_FIFO 20 needs root or CAP_SYS_NICE"
    assert kernel.table == before


def test_every_receive_thread_one_level_above_the_loop_at_most_99(fake_kernel):
    me, kernel = fake_kernel()
    with RealtimeScheduling(99) as scheduling:
        assert kernel.table == {me: (os.SCHED_FIFO, 99), 101: (os.SCHED_FIFO, 99),
                                102: (os.SCHED_FIFO, 99), 103: (os.SCHED_OTHER, 0)}
    assert scheduling.describe() == ("scheduling: real-time while the loop runs, SCHED_FIFO "
                                     "99 (DDS delivery: recvMC 99, recvUC 99)")
    assert set(kernel.table.values()) == {(os.SCHED_OTHER, 0)}
    with RealtimeScheduling(30):
        assert kernel.table[101] == (os.SCHED_FIFO, 31) and kernel.table[me][1] == 30


def test_the_command_line_refuses_a_bad_priority(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["run", "--dds", "--rt-priority", "100"])
    assert exit_info.value.code == 2
    assert ("--rt-priority: expected a SCHED_FIFO priority in [0, 99] (0: ordinary "
            "scheduling), received 100") in capsys.readouterr().err
