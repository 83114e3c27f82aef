"""How the simulated GO2 frames its ``LowState_`` and applies commands, as a GO2 does or as
Unitree's simulators do: :class:`StateFraming` (test peers of the project's own, for
:class:`sim.dds_bridge.DdsBridge`, ``go2-wbc bridge --framing``).

``go2`` (the default)
    As a GO2: ``head`` FE EF, ``level_flag`` 0xFF, leg motors' ``mode`` 0x01, ``rpy``, the
    feet's counts, ``tick`` +1 a state, the CRC; the newest command's PD at each 1 ms physics
    step; the bridge's stand PD before the first command and damping when commands stop.
``unitree-cpp``
    As Unitree's C++ simulator (unitree_mujoco ``simulate``, unitree_sdk2's ``go2_pub.h``):
    ``head`` 00 00, ``level_flag`` 0, ``mode`` 0, ``foot_force`` 0, ``rpy`` from the
    quaternion, ``tick`` the simulated time in milliseconds, a valid CRC; the PD of the newest
    command at each 1 ms physics step, held after the last one (no timeout); no torque before
    the first command.
``unitree-python``
    As Unitree's Python simulator (unitree_mujoco ``simulate_python``): ``head`` 00 00,
    ``level_flag`` 0, ``mode`` 0, ``rpy`` 0, ``foot_force`` 0, ``tick`` 0, ``crc`` 0; 200 Hz
    with gaps (:class:`StateGaps`); each command becomes one torque, ``tau + kp (q_des - q)
    + kd (dq_des - dq)`` computed from the joints when it is taken and clipped to the
    effort limits (MuJoCo's ``ctrlrange``), held until the next command and after the last;
    no torque before the first command.

Unitree's simulators publish their sensors exactly; these peers keep the bridge's sensor model
(``--sensors exact`` for none), but send ``foot_force`` 0 as Unitree's do. They check
``LowCmd_`` as the bridge does (Unitree's accept any).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from wbc.robot_io.dds.c_layout import LEVEL_FLAG_LOW, set_crc
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.unitree_sdk import MODE_ENABLE, SDK_LEG_MOTORS

GO2, UNITREE_CPP, UNITREE_PYTHON = "go2", "unitree-cpp", "unitree-python"
#: The framings, the default first, with what each imitates.
FRAMINGS = {
    GO2: "a GO2: head FE EF, CRC, counting tick, foot counts; stand PD, damping on timeout",
    UNITREE_CPP: "Unitree's C++ simulator: head 00 00, CRC, tick = simulated ms, foot_force 0; "
                 "newest command's PD at 1 kHz, held",
    UNITREE_PYTHON: "Unitree's Python simulator: head 00 00, crc 0, tick 0, foot_force 0, "
                    "200 Hz with 10-50 ms gaps; each command one torque, held",
}
#: The state rate [Hz] of Unitree's Python simulator (``SIMULATE_DT`` = 5 ms).
UNITREE_PYTHON_RATE_HZ = 200.0
#: Its gaps: chance that one starts at a due state, and their length [s] (10 to 50 ms were
#: measured on a loaded 2-core machine).
GAP_CHANCE, GAP_MIN_S, GAP_MAX_S = 0.01, 0.010, 0.050


class StateGaps:
    """Gaps in a 200 Hz stream, as Unitree's Python simulator has them on a loaded machine:
    at each due state a gap starts with :data:`GAP_CHANCE`, lasting :data:`GAP_MIN_S` to
    :data:`GAP_MAX_S`; in half of them (its publishing thread late) no state is sent, in the
    other half (its physics thread late) the physics stands still and the same state is sent
    again. A new state comes between two gaps (back to back they would make a longer one
    than was measured). Seeded: the same gaps every run.
    """

    def __init__(self, seed: int) -> None:
        self._rng = np.random.default_rng(seed)
        self._until_s = -1.0
        #: The current gap's kind: ``"silent"`` or ``"frozen"`` (``""``: none).
        self.kind = ""
        #: Gaps started, and states not sent or sent again.
        self.gaps = 0
        self.states_withheld = 0
        self.states_repeated = 0

    def at_state(self, now_s: float) -> str:
        """At a due state at sim time ``now_s`` [s]: ``""`` (send a new one), ``"silent"``
        (send none) or ``"frozen"`` (send the last one again, the physics halted)."""
        if now_s >= self._until_s:
            ended, self.kind = bool(self.kind), ""
            if not ended and self._rng.random() < GAP_CHANCE:
                self.gaps += 1
                self._until_s = now_s + self._rng.uniform(GAP_MIN_S, GAP_MAX_S)
                self.kind = "frozen" if self._rng.random() < 0.5 else "silent"
        if self.kind == "silent":
            self.states_withheld += 1
        elif self.kind == "frozen":
            self.states_repeated += 1
        return self.kind

    @property
    def physics_halted(self) -> bool:
        """The physics stands still (a frozen gap)."""
        return self.kind == "frozen"

    def report(self) -> dict[str, int]:
        """The gaps' counts."""
        return {"gaps": self.gaps, "states_withheld": self.states_withheld,
                "states_repeated": self.states_repeated}


@dataclass(frozen=True)
class StateFraming:
    """One of :data:`FRAMINGS` (see the module doc).

    Attributes:
        name: The framing's name.
    """

    name: str = GO2

    @property
    def unitree(self) -> bool:
        """One of Unitree's simulators: no stand PD, no damping timeout, ``foot_force`` 0."""
        return self.name != GO2

    def header(self, record: np.ndarray) -> None:
        """Set the fields a state keeps from one to the next (``level_flag``, ``mode``)."""
        record["level_flag"] = 0 if self.unitree else LEVEL_FLAG_LOW
        record["motor_state"]["mode"][:SDK_LEG_MOTORS] = 0 if self.unitree else MODE_ENABLE

    def frame(self, record: np.ndarray, *, sim_time_s: float) -> None:
        """Frame a state that :func:`~wbc.robot_io.dds.low_state_conversion.
        low_state_from_sensor_record` filled (GO2 framing) the way this framing's sender does.
        """
        if not self.unitree:
            return
        record["head"] = (0, 0)
        record["foot_force"] = 0
        if self.name == UNITREE_PYTHON:
            record["imu_state"]["rpy"] = 0.0
            record["tick"] = 0
            record["crc"] = 0
            return
        record["tick"] = round(sim_time_s / 1e-3) % (1 << 32)
        set_crc(record)

    def state_tick(self, record: np.ndarray, own_tick: int) -> int:
        """The tick the truth log keys this state by: the state's where it counts."""
        return int(record["tick"]) if self.name == UNITREE_CPP else own_tick

    def applied(self, command: MotorCommand | None, sim: Any) -> MotorCommand | None:
        """The command the drivers hold from ``command`` (plant order), taken now on ``sim``
        (a :class:`~sim.simulator.Go2Simulator`): itself, or for ``unitree-python`` its
        torque at the joints' present state, clipped to the effort limits, as a pure torque.
        """
        if command is None or self.name != UNITREE_PYTHON:
            return command
        q, dq = sim.joint_state()
        limit = sim.effort_limit
        tau = (command.tau_ff + command.kp * (command.q_des - q)
               + command.kd * (command.dq_des - dq))
        np.clip(tau, -limit, limit, out=tau)
        zeros = np.zeros(len(tau))
        return MotorCommand(q_des=zeros, dq_des=zeros.copy(), kp=zeros.copy(), kd=zeros.copy(),
                            tau_ff=tau)
