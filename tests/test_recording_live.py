"""``--foxglove``: a Foxglove WebSocket client (the ``websockets`` package) sees every channel
advertised with its schema and receives the snapshots at the recording's rate."""

from __future__ import annotations

import asyncio
import json
import threading

import numpy as np
import pytest
import websockets

from actions.robot.run_channels import RunChannels
from actions.robot.run_recording import RunRecording
from tests.test_recording import SCHEMAS, snapshot

SUBPROTOCOL = "foxglove.sdk.v1"  # foxglove-sdk 0.30 refuses the older "foxglove.websocket.v1"
#: Snapshots sent, at 50 Hz of robot time.
SNAPSHOTS = 20
#: Channels every snapshot feeds.
PER_SNAPSHOT = ("/tf", "/joint_states", "/markers", "/plot", "/contacts",
                "/controller/timing", "/wbc/state")


class Subscriptions:
    """A server listener: the channels a client has subscribed to."""

    def __init__(self, wanted: int):
        self.topics: set[str] = set()
        self.wanted = wanted
        self.all = threading.Event()

    def on_subscribe(self, client: object, channel: object) -> None:
        self.topics.add(channel.topic)  # type: ignore[attr-defined]
        if len(self.topics) >= self.wanted:
            self.all.set()

    def on_unsubscribe(self, client: object, channel: object) -> None:
        """Nothing to do."""


async def _client(recording: RunRecording, listener: Subscriptions, port: int,
                  standing: np.ndarray) -> tuple[dict[str, str], dict[str, list[int]]]:
    """Connect, subscribe to every advertised channel, then send the snapshots; the schema
    of each advertised topic and the log times [ns] received on each."""
    received: dict[str, list[int]] = {}
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[SUBPROTOCOL],
                                  max_size=None) as ws:
        advertised: dict[int, tuple[str, str]] = {}
        while len(advertised) < len(SCHEMAS):
            message = json.loads(await asyncio.wait_for(ws.recv(), 10.0))
            if message["op"] == "advertise":
                for channel in message["channels"]:
                    advertised[channel["id"]] = (channel["topic"], channel["schemaName"])
        subscriptions = {k: topic for k, (topic, _) in enumerate(advertised.values(), 1)}
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": k, "channelId": cid} for k, cid in enumerate(advertised, 1)]}))
        # The server confirms each subscription to its listener (no sleep: an event).
        assert await asyncio.to_thread(listener.all.wait, 10.0)
        for k in range(SNAPSHOTS):
            if recording.due():
                recording.capture(snapshot(k * 0.02, standing))
                recording.drain()
        expected = len(PER_SNAPSHOT) * SNAPSHOTS + 1  # and the URDF once
        while sum(map(len, received.values())) < expected:
            frame = await asyncio.wait_for(ws.recv(), 10.0)
            if isinstance(frame, bytes) and frame[0] == 1:  # opcode, sub id, log time, data
                topic = subscriptions[int.from_bytes(frame[1:5], "little")]
                received.setdefault(topic, []).append(int.from_bytes(frame[5:13], "little"))
    return dict(advertised.values()), received


@pytest.mark.slow  # about 1 s on the loaded 2-core machine
def test_a_websocket_client_receives_every_channel_at_the_recording_rate(description):
    standing = description.pose("standing")
    listener = Subscriptions(len(SCHEMAS))
    channels = RunChannels(port=0, server_listener=listener)
    recording = RunRecording(channels, control_period_s=0.02)  # a snapshot a tick: 50 Hz
    try:
        assert channels.port and channels.port > 0
        schemas, received = asyncio.run(_client(recording, listener, channels.port, standing))
    finally:
        recording.close()
    assert schemas == SCHEMAS
    for topic in PER_SNAPSHOT:
        times = np.array(received[topic])
        assert len(times) == SNAPSHOTS, topic
        assert np.diff(times) == pytest.approx(np.full(SNAPSHOTS - 1, 2e7)), topic  # 50 Hz
    assert len(received["/robot_description"]) == 1
    assert recording.dropped == 0
