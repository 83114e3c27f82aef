"""ActionRunner.abort_goals: the running goal's behaviour is canceled, then the goal ends ABORTED
with the reason, and the runner goes on taking goals (unlike a shutdown)."""

from __future__ import annotations

from actions import ActionClient, ActionRunner, ActionServer, GoalStatus
from tests.test_toy_action import WAVE, Loop, WaveBehaviour


def test_abort_goals_ends_the_running_goal_and_the_runner_goes_on():
    runner = ActionRunner()
    behaviours: list[WaveBehaviour] = []

    def make() -> WaveBehaviour:
        behaviours.append(WaveBehaviour())
        return behaviours[-1]

    ActionServer(runner, WAVE, "wave", make)
    loop = Loop(runner)
    client = ActionClient(runner, WAVE, "wave")
    running = client.send_goal_async(WAVE.Goal(waves=3))
    loop.spin_once()
    assert running.result().status is GoalStatus.EXECUTING
    runner.abort_goals(loop.now_s, "state lost")
    ended = running.result().get_result_async().result(0)
    assert ended.status is GoalStatus.ABORTED
    assert ended.result.message == "state lost while the goal was EXECUTING"
    assert behaviours[0].canceled == "state lost"  # told first, to release the robot
    runner.abort_goals(loop.now_s, "again")  # nothing running: nothing happens
    later = client.send_goal_and_wait(WAVE.Goal(waves=1))
    assert later.status is GoalStatus.SUCCEEDED and len(behaviours) == 2
