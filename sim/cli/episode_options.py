"""``go2-wbc``'s options as an :class:`sim.episode.Episode`; a bad combination names its option."""

from __future__ import annotations

import argparse
from typing import Any

from sim.cli.options import PUSH_AT_S, PUSH_DIR_DEG
from sim.disturbances import Push
from sim.episode import Episode, EpisodeError, episode_default
from sim.episode_runner import VIDEO_FPS, VIDEO_SIZE
from sim.scene_overlay import DEFAULT_OVERLAYS
from sim.video_recorder import choose_offscreen_gl

#: The setting that changes each episode field by name, where a field takes several.
_SECTIONS = {"plant": "plant", "plant_params": "plant", "sensors": "sensors",
             "sensor_params": "sensors", "estimator_params": "estimator",
             "controller_params": "controller"}
#: The kept flag and the setting of each episode field that one sets.
_SETTINGS = {"command_delay_s": ("--command-delay", "command_delay", "run.command_delay_s"),
             "calibrate_s": ("--calibrate", "calibrate", "run.calibrate_s"),
             "sensor_seed": ("--sensor-seed", "sensor_seed", "sensors.seed"),
             "sensor_faults": ("--sensor-fault", "sensor_fault", "sensors.fault"),
             "start_pose": ("--start-pose", "start_pose", "run.start_pose")}


def check_options(args: argparse.Namespace) -> None:
    """Options that only make sense with another one; the plant, the state and the rates
    checked as an episode (``args.episode``, without its goal yet). A bad one is a usage
    error naming the option (exit 2); an option left out gets its default.

    Imports MuJoCo: a ``--video`` run chooses its rendering backend first.
    """
    if getattr(args, "video", None) is not None:
        choose_offscreen_gl()  # before the episode's checks import MuJoCo, which reads MUJOCO_GL
    args.episode = _episode(args)
    if not hasattr(args, "video"):
        return
    for option, needs in (("fps", "video"), ("video_size", "video"),
                          ("push_at", "push"), ("push_dir", "push")):
        if getattr(args, option) is not None and getattr(args, needs) is None:
            args.parser.error(f"{_named(args, option)}: only used with --{needs}")
    if args.overlay is not None and args.video is None and not args.viewer:
        args.parser.error(f"{_named(args, 'overlay')}: only used with --video or --viewer")
    if args.viewer_exit and not args.viewer:
        args.parser.error(f"{_named(args, 'viewer_exit')}: only used with --viewer")
    args.overlay = DEFAULT_OVERLAYS if args.overlay is None else args.overlay
    args.fps = args.fps or VIDEO_FPS
    args.video_size = args.video_size or VIDEO_SIZE
    args.push_at = PUSH_AT_S if args.push_at is None else args.push_at
    args.push_dir = PUSH_DIR_DEG if args.push_dir is None else args.push_dir


def goal_episode(args: argparse.Namespace, action: str, goal: Any, **changes: Any) -> Episode:
    """``args.episode`` with its goal, and the run options a goal command takes (start pose,
    push, cancel time, pacing) when it has them; ``changes`` last."""
    fields: dict[str, Any] = {"action": action, "goal": goal}
    if hasattr(args, "push"):
        fields.update(cancel_at_s=args.cancel_at, realtime=args.realtime,
                      start_pose=args.start_pose or args.episode.start_pose)
        if args.push is not None:
            force_n, duration_s = args.push
            fields["pushes"] = (Push(at_s=args.push_at, force_n=force_n, duration_s=duration_s,
                                     direction_deg=args.push_dir, relative_to_heading=True),)
    return args.episode.replace(**fields, **changes)


def _named(args: argparse.Namespace, dest: str) -> str:
    """How the user set ``dest``: ``--set PATH`` when a ``--set`` did, else its flag."""
    path = getattr(args, "set_by", {}).get(dest)
    return f"--set {path}" if path else f"--{dest.replace('_', '-')}"


def _refuse_unused_with_truth(args: argparse.Namespace) -> None:
    """With ``--state truth`` no estimator runs and no sensor is read: an option that changes
    them would be ignored without a word, so it is a usage error naming it (as the Python API
    refuses an estimator with ``state='truth'``)."""
    if args.state != "truth":
        args.estimator = args.estimator or episode_default("estimator")
        return
    why = ("not used with --state truth (the controller reads the simulator's exact state: "
           "no estimator runs, no sensor is read); drop it, or use --state estimate")
    if args.estimator is not None:
        args.parser.error(f"--estimator {args.estimator}: {why}")
    if args.estimator_param:
        name, value = args.estimator_param[0]
        args.parser.error(f"--set estimator.{name}={value}: {why}")
    if args.sensor_fault:
        fault = args.sensor_fault[0]
        text = ",".join([fault.kind, f"{fault.at_s:g}", f"{fault.duration_s:g}",
                         *([fault.name] if fault.name else [])])
        named = _named(args, "sensor_fault")
        args.parser.error(f"{named}{'=' if named.startswith('--set') else ' '}{text}: {why}")
    args.estimator = episode_default("estimator")


def _episode(args: argparse.Namespace) -> Episode:
    fields: dict[str, Any] = {
        "action": None, "plant": args.plant, "plant_params": args.plant_param,
        "control_period_s": 1.0 / args.control_rate, "physics_timestep_s": args.physics_dt}
    if hasattr(args, "state"):
        _refuse_unused_with_truth(args)
        fields.update(sensors=args.sensors, sensor_params=args.sensor_param,
                      sensor_seed=args.sensor_seed, state=args.state, estimator=args.estimator,
                      estimator_params=args.estimator_param,
                      sensor_faults=tuple(args.sensor_fault), command_delay_s=args.command_delay,
                      calibrate_s=args.calibrate or 0.0,
                      controller_params=tuple(args.controller_param))
    try:
        return Episode(**fields)
    except EpisodeError as err:
        args.parser.error(_usage(err, args))


def _usage(err: EpisodeError, args: argparse.Namespace) -> str:
    """The usage error for an episode field, in the words of the option that set it."""
    if err.field in ("control_period_s", "physics_timestep_s"):
        from sim.control_loop import PHYSICS_TIMESTEP_S

        period = 1.0 / args.control_rate
        physics = args.physics_dt if args.physics_dt is not None else min(
            PHYSICS_TIMESTEP_S, period)
        return (f"{_named(args, 'control_rate')}: {args.control_rate:g} Hz with --physics-dt "
                f"{physics:g} s: {err}")
    if err.field in _SECTIONS:  # "name: expected ..." names the setting's path
        name, sep, detail = err.detail.partition(": ")
        if sep and " " not in name:
            return f"--set {_SECTIONS[err.field]}.{name}: {detail}"
        return f"--set {_SECTIONS[err.field]}: {err.detail}"
    if err.field in _SETTINGS:
        flag, dest, path = _SETTINGS[err.field]
        return f"{f'--set {path}' if dest in getattr(args, 'set_by', {}) else flag}: {err.detail}"
    return f"--{err.field.replace('_', '-')}: {err.detail}"
