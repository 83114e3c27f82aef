"""The controller in a loop of your own: your robot's state in, the motor command out.

Run ``python examples/own_loop.py``. Nothing of this library's simulator or control loop
runs here: every tick, your code hands the controller the robot's state, ``q`` (19,) and
``v`` (18,) in Pinocchio's conventions (base position and quaternion ``x, y, z, w``, then the
joints in the URDF's order FL, FR, RL, RR x hip, thigh, calf; the base's velocities in its
own frame), and sends the motor command it returns to the drivers. A ``LegLift`` is driven
by hand: started, then advanced with the clock every tick; it moves the controller's targets
and contacts through its phases.

The "robot" here is the simplest stand-in for yours: an ideal plant that does exactly what
the controller's model predicts, its state integrated from the planned accelerations. On a
real GO2 the state comes from the state estimator (``wbc.make_estimator``, fed each
``rt/lowstate`` through ``wbc.sensor_record_from_message``) and the command goes to
``rt/lowcmd`` through ``wbc.SdkMotorCommand.from_control_output(out).write_to(low_cmd)``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbc import Go2Description, LegLift, LiftPhase, WholeBodyController


def run(*, height_m: float = 0.30, hold_s: float = 0.5) -> dict[str, float]:
    """Raise the front-right foot to ``height_m`` [m], hold it ``hold_s`` [s], put it back;
    returns the highest the foot went [m], the ticks, and how many were not OK."""
    description = Go2Description.default()
    controller = WholeBodyController()                  # 1 kHz, DAQP, the default gains
    dt = controller.control_period_s
    q = description.pose("standing")                    # your robot's state: q (19,) ...
    v = np.zeros(18)                                    # ... and v (18,)
    controller.reset(q, v)                              # hold this state, four feet down
    lift = LegLift(controller, leg="FR", height_m=height_m, hold_s=hold_s)
    t, highest, ticks, not_ok = 0.0, 0.0, 0, 0
    lift.start(t)
    while lift.phase is not LiftPhase.DONE:
        lift.advance(t)                                 # this tick's targets and contacts
        out = controller.step(q, v)                     # one QP: the motor command
        # Your drivers get, per joint (description order): out.q_des [rad], out.dq_des
        # [rad/s], out.kp [N m/rad], out.kd [N m s/rad], out.tau_ff [N m].
        not_ok += not out.ok
        highest = max(highest, float(controller.foot_position("FR")[2]))
        v = v + out.qdd * dt                            # the stand-in robot moves as planned
        q = pin.integrate(description.model, q, v * dt)
        t += dt
        ticks += 1
    return {"highest_m": highest, "ticks": ticks, "not_ok": not_ok}


if __name__ == "__main__":
    summary = run()
    print(f"FR foot raised to {summary['highest_m']:.3f} m and put back down in "
          f"{summary['ticks']} ticks; ticks not OK: {summary['not_ok']}")
