"""A run's channels in Foxglove's schemas, written to an MCAP file and/or served on a local
WebSocket: :class:`RunChannels`, the one home of ``foxglove-sdk``.

Typed channels (Foxglove's own schemas, protobuf on the wire): ``/tf`` (FrameTransforms),
``/joint_states`` (JointStates), ``/markers`` (SceneUpdate), ``/log`` (Log). JSON channels,
each with a JSON schema: ``/plot``, ``/contacts``, ``/controller/timing``,
``/action/feedback``, ``/wbc/state`` (the raw arrays a replay reads back), ``/walking``
(while a motion walks: commanded and measured velocity in the heading frame, the swing and
loaded feet; the channel exists from its first message) and ``/robot_description`` (the
URDF, schema ``std_msgs/msg/String`` as the 3D panel's URDF layer expects, its meshes as
``file://`` URIs on this machine). The MCAP file also holds the URDF as an attachment and the
run's description as metadata.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import foxglove
from foxglove.channels import (
    FrameTransformsChannel,
    JointStatesChannel,
    LogChannel,
    SceneUpdateChannel,
)

from wbc.core.errors import ConfigurationError
from wbc.model.description import Go2Description

#: The MCAP chunk size [bytes] before compression: a chunk is compressed inside the ``log``
#: call that fills it, and 64 kB (not the SDK's 1 MB) keeps that call's longest time near
#: 1 ms of CPU instead of 1.8 ms (measured: 1,500 snapshots), the file 9 % larger. Zstd
#: compresses in the calling thread (``compression_threads=0``), not in as many threads as
#: there are cores, which would take every core from the control loop at once.
CHUNK_BYTES = 64 * 1024
#: The 3D panel's URDF layer reads a topic of this schema.
DESCRIPTION_SCHEMA = "std_msgs/msg/String"
_NUMBER = {"type": "number"}
_NUMBERS = {"type": "array", "items": _NUMBER}
WALKING_VELOCITY = ("forward, lateral [m/s], yaw rate [rad/s] in the heading frame; null "
                    "while nothing walks")
#: JSON channel -> (schema name, properties).
JSON_CHANNELS: dict[str, tuple[str, dict[str, Any]]] = {
    "/plot": ("go2_wbc.Plot", {
        "base_height_m": _NUMBER, "base_height_true_m": _NUMBER, "base_speed_mps": _NUMBER,
        "base_speed_true_mps": _NUMBER, "foot_error_m": _NUMBER, "com_margin_m": _NUMBER}),
    "/contacts": ("go2_wbc.Contacts", {
        "legs": {"type": "array", "items": {"type": "string"}},
        "force_n": {"type": "array", "items": _NUMBERS}, "normal_force_n": _NUMBERS,
        "estimate_contact": _NUMBERS, "stance": {"type": "array",
                                                 "items": {"type": "boolean"}}}),
    "/controller/timing": ("go2_wbc.Timing", {
        "tick_us": _NUMBER, "qp_ok": {"type": "boolean"}, "status": {"type": "string"},
        "missed": {"type": "boolean"}, "stages_us": {"type": "object"},
        "dropped": {"type": "integer"}}),
    "/action/feedback": ("go2_wbc.ActionFeedback", {
        "phase": {"type": "string"}, "progress": _NUMBER}),
    "/wbc/state": ("go2_wbc.State", {
        "t_s": _NUMBER, "q": _NUMBERS, "v": _NUMBERS, "tau": _NUMBERS, "q_true": _NUMBERS,
        "v_true": _NUMBERS, "foot_target": {"type": "array", "items": _NUMBERS},
        "foot_position": {"type": "array", "items": _NUMBERS}, "phase": {"type": "string"},
        "tick_us": _NUMBER, "qp_ok": {"type": "boolean"},
        "commanded_velocity": {**_NUMBERS, "description": WALKING_VELOCITY}}),
}
#: A heading-frame velocity's fields on ``/walking``.
_VELOCITY = {"type": "object", "properties": {
    "forward_mps": _NUMBER, "lateral_mps": _NUMBER, "yaw_rate_radps": _NUMBER}}
#: ``/walking``: created at its first message (a run that never walks has no such channel).
WALKING_CHANNEL = ("/walking", "go2_wbc.Walking", {
    "commanded": _VELOCITY, "measured": _VELOCITY, "measured_true": _VELOCITY,
    "swing_legs": {"type": "array", "items": {"type": "string"}},
    "legs": {"type": "array", "items": {"type": "string"}},
    "loaded": {"type": "array", "items": {"type": "boolean"}}})


def _json_schema(name: str, properties: dict[str, Any]) -> foxglove.Schema:
    schema = {"type": "object", "title": name, "properties": properties}
    return foxglove.Schema(name=name, encoding="jsonschema", data=json.dumps(schema).encode())


def description_text(description: Go2Description) -> str:
    """The URDF with its ``package://`` mesh URIs as ``file://`` URIs on this machine (the
    3D panel of a desktop Foxglove or Lichtblick loads them)."""
    share = description.package_share_dir.as_uri() + "/"
    return description.urdf_path.read_text(encoding="utf-8").replace("package://", share)


class RunChannels:
    """The channels of one run, logged to an MCAP file, a WebSocket server, or both.

    Args:
        mcap_path: The MCAP file to write (replaced if it exists); ``None``: none.
        port: The local WebSocket port to serve on (127.0.0.1; 0: any free port);
            ``None``: no server.
        metadata: The run's description (command, rates, plant, state source), as strings.
        description: The robot's model (its URDF).
        server_listener: Told of the live clients' subscriptions (a
            ``foxglove.websocket.ServerListener``; none by default).

    Raises:
        ConfigurationError: Neither a file nor a port, or the port cannot be served.
    """

    def __init__(self, *, mcap_path: Path | str | None = None, port: int | None = None,
                 metadata: dict[str, str] | None = None,
                 description: Go2Description | None = None, server_listener: Any = None):
        if mcap_path is None and port is None:
            raise ConfigurationError("RunChannels: expected an mcap_path, a port or both, "
                                     "received neither")
        self.description = description or Go2Description.default()
        self.context = context = foxglove.Context()
        self.tf = FrameTransformsChannel("/tf", context=context)
        self.joints = JointStatesChannel("/joint_states", context=context)
        self.markers = SceneUpdateChannel("/markers", context=context)
        self.log = LogChannel("/log", context=context)
        self.json: dict[str, foxglove.Channel] = {
            topic: foxglove.Channel(topic, schema=_json_schema(name, properties),
                                    message_encoding="json", context=context)
            for topic, (name, properties) in JSON_CHANNELS.items()}
        self.robot_description = foxglove.Channel(
            "/robot_description", message_encoding="json", context=context,
            schema=_json_schema(DESCRIPTION_SCHEMA, {"data": {"type": "string"}}))
        self.urdf_text = description_text(self.description)
        self.walking: foxglove.Channel | None = None
        self.writer: Any = None
        self.server: Any = None
        self._port: int | None = None
        if mcap_path is not None:
            from foxglove.mcap import MCAPWriteOptions

            self.writer = foxglove.open_mcap(
                str(mcap_path), allow_overwrite=True, context=context,
                writer_options=MCAPWriteOptions(chunk_size=CHUNK_BYTES,
                                                compression_threads=0))
            now_ns = time.time_ns()
            self.writer.attach(log_time=now_ns, create_time=now_ns, name="go2.urdf",
                               media_type="application/xml",
                               data=self.description.urdf_path.read_bytes())
            self.writer.write_metadata("go2-wbc", dict(metadata or {}))
        if port is not None:
            try:
                self.server = foxglove.start_server(
                    name="go2-wbc", host="127.0.0.1", port=port, context=context,
                    asset_handler=self._asset, server_listener=server_listener)
            except Exception as err:  # the SDK raises its own types for a busy port
                if self.writer is not None:
                    self.writer.close()
                raise ConfigurationError(f"--foxglove: cannot serve on 127.0.0.1:{port} "
                                         f"({' '.join(str(err).split())}); give another "
                                         "port") from err
            self._port = int(self.server.port)

    @property
    def port(self) -> int | None:
        """The WebSocket server's port, also once closed (``None``: no server)."""
        return self._port

    def log_json(self, topic: str, message: dict[str, Any], time_ns: int) -> None:
        """Log ``message`` on the JSON channel ``topic`` (one of :data:`JSON_CHANNELS`)."""
        self.json[topic].log(message, log_time=time_ns)

    def log_walking(self, message: dict[str, Any], time_ns: int) -> None:
        """Log ``message`` on ``/walking`` (:data:`WALKING_CHANNEL`), the channel created at
        the first one."""
        if self.walking is None:
            topic, name, properties = WALKING_CHANNEL
            self.walking = foxglove.Channel(topic, schema=_json_schema(name, properties),
                                            message_encoding="json", context=self.context)
        self.walking.log(message, log_time=time_ns)

    def log_description(self, time_ns: int) -> None:
        """The URDF on ``/robot_description`` (repeated: a live view may join late)."""
        self.robot_description.log({"data": self.urdf_text}, log_time=time_ns)

    def close(self) -> None:
        """Finish the MCAP file (its summary and indexes) and stop the server."""
        if self.writer is not None:
            self.writer.close()
            self.writer = None
        if self.server is not None:
            self.server.stop()
            self.server = None

    def _asset(self, uri: str) -> bytes | None:
        """A mesh the live view asks for by ``file://`` or ``package://`` URI."""
        share = self.description.package_share_dir
        for prefix, root in (("package://", share), (share.as_uri() + "/", share)):
            if uri.startswith(prefix):
                path = (root / uri[len(prefix):]).resolve()
                if path.is_file() and path.is_relative_to(share.resolve()):
                    return path.read_bytes()
        return None


class RelayChannels:
    """A recording's channels re-served as stored (their schemas and bytes untouched), on a
    local WebSocket: what ``go2-wbc replay --foxglove`` serves.

    Args:
        channels: topic -> (schema name, message encoding, schema encoding, schema bytes).
        port: The local port (0: any free one).

    Raises:
        ConfigurationError: The port cannot be served.
    """

    def __init__(self, channels: dict[str, tuple[str, str, str, bytes]], *, port: int):
        self.context = context = foxglove.Context()
        self.channels = {
            topic: foxglove.Channel(topic, message_encoding=encoding, context=context,
                                    schema=foxglove.Schema(name=name, encoding=schema_encoding,
                                                           data=data))
            for topic, (name, encoding, schema_encoding, data) in channels.items()}
        try:
            self.server: Any = foxglove.start_server(name="go2-wbc replay", host="127.0.0.1",
                                                     port=port, context=context)
        except Exception as err:  # the SDK raises its own types for a busy port
            raise ConfigurationError(f"--foxglove: cannot serve on 127.0.0.1:{port} "
                                     f"({' '.join(str(err).split())}); give another "
                                     "port") from err

    @property
    def port(self) -> int:
        """The server's port."""
        return int(self.server.port)

    def log(self, topic: str, data: bytes, time_ns: int) -> None:
        """Re-send one stored message."""
        self.channels[topic].log(data, log_time=time_ns)

    def close(self) -> None:
        """Stop the server."""
        self.server.stop()
