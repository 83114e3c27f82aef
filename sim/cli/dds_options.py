"""``--dds``, ``--domain``, ``--interface``: the options of the ``go2-wbc`` commands that talk to
a robot (or the simulator bridge) over DDS, and the check that no simulation option comes with
them."""

from __future__ import annotations

import argparse
from typing import Any

from actions.robot.realtime_priority import MAX_PRIORITY
from sim.cli.arg_types import whole_in
from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.domain_config import MAX_DOMAIN_ID, check_interface

#: The defaults: the simulator's convention (unitree_mujoco, ``go2-wbc bridge``). A real GO2
#: is domain 0 on the interface of its Ethernet link.
DEFAULT_DOMAIN, DEFAULT_INTERFACE = 1, "lo"
#: Options a command keeps with ``--dds`` (the rest simulate, and are refused).
DDS_KEEPS = frozenset({
    "help", "action", "type", "goal", "feedback", "timeout", "height", "hold", "dds", "domain",
    "interface", "server_timeout"})


#: ``--domain``: a DDS domain id in ``[0, MAX_DOMAIN_ID]``.
domain_id = whole_in(0, MAX_DOMAIN_ID, what="a DDS domain id",
                     note=f"a GO2: 0; the simulator bridge: {DEFAULT_DOMAIN}")


def interface(text: str) -> str:
    """An argparse type: a network interface of this host (the message lists them)."""
    try:
        return check_interface(text)
    except ConfigurationError as err:
        raise argparse.ArgumentTypeError(str(err).removeprefix("interface: ")) from None


def add_dds_options(group: Any, *, flag_help: str | None) -> None:
    """``--domain`` and ``--interface`` (and ``--dds`` with ``flag_help``) on ``group``."""
    if flag_help is not None:
        group.add_argument("--dds", action="store_true", help=flag_help)
    group.add_argument("--domain", type=domain_id, default=DEFAULT_DOMAIN, metavar="ID",
                       help=f"DDS domain id, 0 to {MAX_DOMAIN_ID} (default: {DEFAULT_DOMAIN}, "
                            "the simulator bridge's; a real GO2: 0)")
    group.add_argument("--interface", type=interface, default=DEFAULT_INTERFACE,
                       metavar="NAME",
                       help=f"network interface of the domain (default: {DEFAULT_INTERFACE}; a "
                            "real GO2: the interface of its Ethernet link, e.g. eth0 or enp3s0)")


#: ``--rt-priority``: a ``SCHED_FIFO`` priority in ``[0, MAX_PRIORITY]`` (0: ordinary).
rt_priority = whole_in(0, MAX_PRIORITY, what="a SCHED_FIFO priority",
                       note="0: ordinary scheduling")


def add_priority_option(group: Any, *, default: int, loop: str) -> None:
    """``--rt-priority``: the real-time scheduling of a loop that keeps a robot's clock."""
    group.add_argument("--rt-priority", type=rt_priority, default=default, metavar="N",
                       help=f"run {loop} under SCHED_FIFO at this priority, 1 to "
                            f"{MAX_PRIORITY}, and the DDS threads that deliver its samples one "
                            "above, while it runs and when permitted (root or CAP_SYS_NICE; "
                            "otherwise ordinary, and the first lines say so), so that other "
                            f"processes do not delay its deadlines; 0: ordinary (default: "
                            f"{default})")


def check_dds_options(args: argparse.Namespace) -> None:
    """With ``--dds``: refuse every option that only a simulation uses (a usage error naming
    it); without: refuse ``--domain``/``--interface`` given alone."""
    parser: argparse.ArgumentParser = args.parser
    if not args.dds:
        for dest, flag in (("domain", "--domain"), ("interface", "--interface")):
            if getattr(args, dest) != parser.get_default(dest):
                parser.error(f"{flag}: only used with --dds")
        return
    for action in parser._actions:  # argparse keeps its options there
        dest = action.dest
        if dest in DDS_KEEPS or not action.option_strings:
            continue
        if getattr(args, dest, action.default) != action.default:
            option = action.option_strings[-1]
            if dest == "settings":  # --set: the first path given
                option = f"--set {args.settings[0]}"
            parser.error(f"{option}: a simulation option, not used with "
                         "--dds (the robot on DDS is not simulated here)")
