"""What recording costs ``go2-wbc run --dds``: the same high five on the simulator bridge with
no recording, with ``--mcap`` and with ``--foxglove`` (a client subscribed to every channel),
interleaved, in one session; each run's deadline misses and tick p99 from its report::

    python -m benchmarks.recording_cost --rate 1000 --repeats 2

Prints one row a run and writes ``--json`` if asked.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import socket
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from benchmarks.dds_outputs import ControllerFigures
from benchmarks.dds_processes import CONTROLLER_READY, DdsProcesses, private_domain_id

MODES = ("none", "mcap", "foxglove")
SUBPROTOCOL = "foxglove.sdk.v1"  # foxglove-sdk 0.30 refuses "foxglove.websocket.v1"
#: Longest wait [s] for the controller to control (start-up on a loaded machine).
START_S = 180.0


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Subscriber(threading.Thread):
    """A Foxglove WebSocket client (``websockets``) that subscribes to every advertised
    channel and counts the messages it receives by channel, until :meth:`stop`."""

    def __init__(self, port: int):
        super().__init__(daemon=True)
        self.port = port
        self.counts: dict[str, int] = {}
        self._done = threading.Event()
        self.error: BaseException | None = None

    def run(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as err:  # noqa: BLE001 - reported by the caller
            self.error = err

    def stop(self) -> None:
        self._done.set()
        self.join(10.0)

    async def _main(self) -> None:
        import websockets

        deadline = time.monotonic() + 60.0
        while True:
            try:
                ws = await websockets.connect(f"ws://127.0.0.1:{self.port}",
                                              subprotocols=[SUBPROTOCOL], max_size=None)
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                await asyncio.sleep(0.1)
        topics: dict[int, str] = {}
        async with ws:
            while not self._done.is_set():
                try:
                    frame = await asyncio.wait_for(ws.recv(), 0.2)
                except TimeoutError:
                    continue
                if isinstance(frame, str):
                    message = json.loads(frame)
                    if message.get("op") == "advertise":
                        subs = []
                        for channel in message["channels"]:
                            sub_id = len(topics) + 1
                            topics[sub_id] = channel["topic"]
                            subs.append({"id": sub_id, "channelId": channel["id"]})
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
                elif frame[0] == 1:  # message data: opcode, subscription id (u32 LE), ...
                    topic = topics.get(int.from_bytes(frame[1:5], "little"), "?")
                    self.counts[topic] = self.counts.get(topic, 0) + 1


def run_once(workdir: Path, mode: str, rate_hz: int) -> dict[str, Any]:
    """One high five under ``run --dds`` at ``rate_hz`` with ``mode``'s recording."""
    extra: list[str] = []
    subscriber = None
    if mode == "mcap":
        extra = ["--mcap", str(workdir / "run.mcap")]
    elif mode == "foxglove":
        port = free_port()
        extra = ["--foxglove", str(port)]
    with DdsProcesses(workdir, domain_id=private_domain_id()) as run:
        bridge = run.bridge(rate_hz=rate_hz, log=False)
        controller = run.controller(*extra, rate_hz=rate_hz, log=False, wait=False)
        controller.wait_for_line(CONTROLLER_READY, timeout_s=START_S)  # a loaded machine
        if mode == "foxglove":
            subscriber = Subscriber(port)
            subscriber.start()
        client = run.high_five(height_m=0.4, hold_s=2.0)
        code = client.wait(START_S)
        controller.stop()
        bridge.stop()
    if subscriber is not None:
        subscriber.stop()
    figures = ControllerFigures.read(controller.report_path)
    row = {"mode": mode, "goal_exit": code, "ticks": figures.ticks,
           "deadline_misses": figures.deadline_misses,
           "miss_percent": round(figures.miss_percent, 3),
           "tick_p99_ms": figures.series["tick"]["p99_ms"],
           "latency_p99_ms": figures.series["latency"]["p99_ms"],
           "hooks_p99_ms": figures.series["hooks"]["p99_ms"]}
    summary = [line for line in controller.output().splitlines() if "snapshots at" in line]
    if summary:
        row["recording"] = summary[-1]
    if subscriber is not None:
        row["received"] = dict(sorted(subscriber.counts.items()))
    return row


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=int, default=1000, help="control rate [Hz]")
    parser.add_argument("--repeats", type=int, default=2, help="rounds of the three modes")
    parser.add_argument("--json", type=Path, help="write the rows here")
    parser.add_argument("--modes", nargs="+", choices=MODES, default=list(MODES),
                        help="the recordings to compare (default: all three)")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.repeats):
            for mode in args.modes:
                workdir = Path(tmp) / f"{r}-{mode}"
                workdir.mkdir()
                row = run_once(workdir, mode, args.rate)
                print(json.dumps(row), flush=True)
                rows.append(row)
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
