"""The ``go2-wbc`` command line."""

from __future__ import annotations

import argparse
import sys

import numpy as np


def _stand_pd(args: argparse.Namespace) -> int:
    from sim.simulator import Go2Simulator
    from wbc.joint_pd_controller import JointPdController

    sim = Go2Simulator()
    controller = JointPdController(sim.description.pose("standing"))
    z0 = sim.state()[0][2]
    steps = int(round(args.duration / sim.timestep_s))
    for _ in range(steps):
        sim.step(controller.compute(*sim.state()))
    q, _ = sim.state()
    forces = sim.foot_contact_forces()
    print(f"stood {sim.time_s:.2f} s under a joint PD with gravity compensation")
    print(f"base height {z0:.4f} m -> {q[2]:.4f} m; drift {np.linalg.norm(q[:2]) * 1e3:.2f} mm")
    print("foot normal forces [N]: " + ", ".join(f"{k} {v[2]:.1f}" for k, v in forces.items()))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="go2-wbc", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    stand = sub.add_parser("stand-pd", help="stand under a joint PD (baseline, no QP)")
    stand.add_argument("--duration", type=float, default=3.0,
                       help="simulated seconds (default: 3.0)")
    stand.set_defaults(run=_stand_pd)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return int(args.run(args))


if __name__ == "__main__":
    sys.exit(main())
