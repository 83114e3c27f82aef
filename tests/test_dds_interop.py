"""Our cyclonedds 11.0.1 side and a Cyclone DDS 0.10.2 C peer (unitree_sdk2's stack) on lo:
the type hashes, every field both ways, and the SDK's CRC checked by each side on the other's
messages (the peer computes it from its C memory: an independent check of ours)."""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import time
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from cyclonedds.core import (
    InstanceState,
    Policy,
    Qos,
    ReadCondition,
    SampleState,
    ViewState,
    WaitSet,
)
from cyclonedds.idl import IdlStruct
from cyclonedds.internal import InvalidSample
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from wbc.robot_io.dds.c_layout import crc_ok, set_crc
from wbc.robot_io.dds.domain_config import DomainHandle, delete_entities, join_domain
from wbc.robot_io.dds.go2_types import (
    LOW_CMD_TOPIC,
    LOW_STATE_TOPIC,
    BmsCmd_,
    BmsState_,
    IMUState_,
    LowCmd_,
    LowState_,
    MotorCmd_,
    MotorState_,
)
from wbc.robot_io.dds.wire_message import LowCmdMessage, LowStateMessage, WireMessage

ROOT = Path(__file__).resolve().parents[1]
PEER_SRC = ROOT / "scripts" / "go2_peer"
PEER_SOURCES = ("unitree_go.idl", "go2_peer.c", "build.sh")

# The peer: what unitree_sdk2's ChannelFactory::Init(domain, "lo") configures. Our side joins
# lo through join_domain, which turns multicast off there as a 0.10.x peer does on lo (with
# multicast left on, 11.0.1 and 0.10.x never discover each other on lo).
LO_CONFIG_PEER = (
    '<CycloneDDS><Domain Id="any"><General><Interfaces>'
    '<NetworkInterface name="lo" priority="default" multicast="default"/>'
    "</Interfaces></General></Domain></CycloneDDS>"
)
TICKS = 20
PEER_TIMEOUT_S = 20.0
RESEND_S = 0.05  # lockstep: a state or command unanswered this long is sent again
SUMMARY = re.compile(r"^go2_peer summary: (.*)$", re.MULTILINE)

TYPES = (MotorCmd_, BmsCmd_, LowCmd_, IMUState_, MotorState_, BmsState_, LowState_)
#: The fast sample class (numpy codec) of each IdlStruct message class.
WIRE = {LowState_: LowStateMessage, LowCmd_: LowCmdMessage}
#: Our side's sample classes: cyclonedds' IdlStruct serialiser, or the numpy codec.
SIDES = ("IdlStruct", "WireMessage")


# --- The two functions the peer shares (scripts/go2_peer/go2_peer.c) ------------------------
# Every value is exact in float32, so both sides compare whole messages with ==.


def known_state(k: int) -> LowState_:
    """The LowState_ of tick k: every field a function of k, as the peer's known_state()."""
    return LowState_(
        head=[0xFE, 0xEF], level_flag=0xFF, frame_reserve=k & 0xFF, sn=[k, 1000 + k],
        version=[0x0102, 0x0304], bandwidth=0x1200 + (k & 0xFF),
        imu_state=IMUState_(
            quaternion=[k + 0.25 * j for j in range(4)],
            gyroscope=[-(k + 0.5 * j) for j in range(3)],
            accelerometer=[9.75 + j for j in range(3)], rpy=[0.125 * j for j in range(3)],
            temperature=40 + k % 10),
        motor_state=[
            MotorState_(mode=1, q=0.5 * i + 0.0625 * k, dq=-0.25 * i, tau_est=0.125 * i,
                        temperature=30 + i, lost=20 * k + i, reserve=[i, k])
            for i in range(20)],
        bms_state=BmsState_(version_high=1, version_low=2, status=3, soc=k % 101,
                            current=-1500, cycle=7, bq_ntc=[25, 26], mcu_ntc=[27, 28],
                            cell_vol=[3700 + j for j in range(15)]),
        foot_force=[10 * j - 15 for j in range(4)], foot_force_est=[-j for j in range(4)],
        tick=k, wireless_remote=[(7 * j + k) & 0xFF for j in range(40)], bit_flag=0x5A,
        adc_reel=0.5, temperature_ntc1=45, temperature_ntc2=46, power_v=28.25, power_a=-1.5,
        fan_frequency=[1000 * j + k for j in range(4)], reserve=0xDEADBEEF, crc=0)


def echo(s: LowState_) -> LowCmd_:
    """The LowCmd_ that answers a state, as the peer's echo(): header copied, motor slot i
    from motor_state[i], kp and kd from the IMU and the foot forces, reserve = tick, crc 0."""
    return LowCmd_(
        head=list(s.head), level_flag=s.level_flag, frame_reserve=s.frame_reserve,
        sn=list(s.sn), version=list(s.version), bandwidth=s.bandwidth,
        motor_cmd=[
            MotorCmd_(mode=m.mode, q=m.q, dq=m.dq, tau=m.tau_est,
                      kp=s.imu_state.quaternion[i % 4], kd=float(s.foot_force[i % 4]),
                      reserve=[m.lost, 0, 0])
            for i, m in enumerate(s.motor_state)],
        bms_cmd=BmsCmd_(off=s.bms_state.soc),
        wireless_remote=list(s.wireless_remote),
        led=[s.temperature_ntc1, s.temperature_ntc2, s.imu_state.temperature, s.bit_flag]
        + [0] * 8,
        fan=[f & 0xFF for f in s.fan_frequency[:2]], gpio=s.bms_state.status,
        reserve=s.tick, crc=0)


def plain(message: IdlStruct) -> dict:
    """A message as nested dicts and lists: a received byte array is `bytes`, a built one a
    list, and the two must compare equal."""

    def lists(value):
        if isinstance(value, dict):
            return {key: lists(item) for key, item in value.items()}
        if isinstance(value, (list, tuple, bytes)):
            return [lists(item) for item in value]
        return value

    return lists(asdict(message))


def sample_class(message_class: type, side: str) -> type:
    """The class our side reads or writes ``message_class`` (an IdlStruct class) with."""
    return message_class if side == "IdlStruct" else WIRE[message_class]


def with_crc(message: IdlStruct, side: str) -> Any:
    """``message`` with the SDK's CRC, set by :func:`c_layout.set_crc` on its C image, as a
    sample of ``side``'s class."""
    wire = WIRE[type(message)].from_idl(message)
    set_crc(wire.record)
    return wire if side == "WireMessage" else wire.to_idl()


def as_idl(sample: Any) -> IdlStruct:
    """A received sample as its IdlStruct message."""
    return sample.to_idl() if isinstance(sample, WireMessage) else sample


def record_of(sample: Any) -> np.ndarray:
    """A received sample's C-image record (what the robot computes the CRC over)."""
    if isinstance(sample, WireMessage):
        return sample.record
    return WIRE[type(sample)].from_idl(sample).record


# --- The peer: built once per session, cached by the hash of its sources --------------------


def _missing_toolchain() -> str | None:
    """Why the 0.10.x peer cannot be built here (naming the Debian package), or None."""
    idlc = shutil.which("idlc")
    if idlc is None:
        return "idlc not found: needs Debian's cyclonedds-tools 0.10.x (scripts/setup.sh)"
    version = subprocess.run([idlc, "-v"], capture_output=True, text=True, timeout=30).stdout
    if "0.10." not in version:
        return f"idlc is not Cyclone DDS 0.10.x ({version.strip()!r}): needs cyclonedds-tools"
    if not any(Path(p, "dds", "dds.h").is_file() for p in ("/usr/include", "/usr/local/include")):
        return "dds/dds.h not found: needs Debian's cyclonedds-dev 0.10.x (scripts/setup.sh)"
    if shutil.which(os.environ.get("CC", "gcc")) is None:
        return "no C compiler: needs Debian's gcc"
    return None


@pytest.fixture(scope="session")
def peer(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The go2_peer binary, from the cache when its sources have not changed."""
    reason = _missing_toolchain()
    if reason is not None:
        pytest.skip(reason)
    digest = hashlib.sha256()
    for name in PEER_SOURCES:
        digest.update((PEER_SRC / name).read_bytes())
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "go2-wbc"
    try:
        cache.mkdir(parents=True, exist_ok=True)
    except OSError:  # a read-only home: build for this session only
        cache = tmp_path_factory.mktemp("go2-wbc")
    out = cache / "go2_peer" / digest.hexdigest()[:16]
    binary = out / "go2_peer"
    if not binary.is_file():
        done = subprocess.run(["bash", str(PEER_SRC / "build.sh"), str(out)],
                              capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, f"building the peer failed:\n{done.stdout}\n{done.stderr}"
    return binary


def _domain_id(offset: int) -> int:
    """A domain of this test process alone (0 is the robot's, 1 unitree_mujoco's), one of four
    (``offset`` 0 to 3)."""
    return 100 + (os.getpid() % 30) * 4 + offset


@dataclass
class Endpoint:
    """Our side on one domain: the SDK's QoS, a writer of one topic and a reader of the other."""

    dds: DomainHandle
    writer: DataWriter
    reader: DataReader
    waitset: WaitSet

    def take(self, timeout_s: float) -> list:
        """Wait up to timeout_s for samples, then take every valid one."""
        self.waitset.wait(duration(seconds=timeout_s))
        # An invalid sample (no data) comes when the peer's writer goes away.
        return [s for s in self.reader.take(N=10) if not isinstance(s, InvalidSample)]

    def close(self) -> None:
        delete_entities(self.waitset, self.reader, self.writer)
        self.dds.close()


@pytest.fixture
def endpoint_factory() -> Iterator:
    made: list[Endpoint] = []

    def make(domain_id: int, write_type: type, write_topic: str, read_type: type,
             read_topic: str) -> Endpoint:
        dds = join_domain("lo", domain_id=domain_id)
        participant = dds.participant
        writer = DataWriter(
            participant, Topic(participant, write_topic, write_type),
            qos=Qos(Policy.Reliability.Reliable(duration(milliseconds=100)),
                    Policy.History.KeepLast(1)))
        reader = DataReader(
            participant, Topic(participant, read_topic, read_type),
            qos=Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(1)))
        waitset = WaitSet(participant)
        waitset.attach(ReadCondition(reader, SampleState.Any | ViewState.Any
                                     | InstanceState.Any))
        made.append(Endpoint(dds, writer, reader, waitset))
        return made[-1]

    yield make
    for endpoint in made:  # readers and writers go before the interpreter's exit
        endpoint.close()


def _start_peer(binary: Path, mode: str, domain_id: int, tmp_path: Path) -> subprocess.Popen:
    env = {**os.environ, "CYCLONEDDS_URI": LO_CONFIG_PEER}
    env.pop("LD_LIBRARY_PATH", None)  # the system's 0.10.2 libddsc, never the wheel's 11.0.1
    # Output to files, not pipes: nothing reads the peer while the test runs.
    with (tmp_path / f"{mode}.out").open("w") as out, (tmp_path / f"{mode}.err").open("w") as err:
        return subprocess.Popen(
            [str(binary), mode, "--domain", str(domain_id), "--count", str(TICKS),
             "--timeout", str(PEER_TIMEOUT_S), "--period-ms", str(int(RESEND_S * 1000))],
            stdout=out, stderr=err, env=env)


def _finish_peer(proc: subprocess.Popen, mode: str, tmp_path: Path) -> tuple[dict, str, str]:
    """Wait for the peer (bounded), then its summary fields, stdout and stderr."""
    try:
        proc.wait(timeout=PEER_TIMEOUT_S + 10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    out = (tmp_path / f"{mode}.out").read_text()
    err = (tmp_path / f"{mode}.err").read_text()
    found = SUMMARY.search(out)
    assert found is not None, f"peer exit {proc.returncode}, no summary:\n{out}\n{err}"
    fields = dict(item.split("=", 1) for item in found.group(1).split())
    return fields, out, err


def _assert_clean(fields: dict, err: str, returncode: int | None) -> None:
    assert "invalid type object" not in err, err
    assert (fields["errors"], fields["invalid_type_object"], fields["mismatches"]) == \
        ("0", "0", "0"), fields
    assert (fields["cyclonedds"][:5], fields["result"], returncode) == ("0.10.", "ok", 0), \
        (fields, err)


# --- Tests ----------------------------------------------------------------------------------


def test_python_type_hashes_are_those_of_idlc_0_10(peer: Path) -> None:
    """Our 11.0.1 types and the 0.10.2 idlc's (= the C++ headers') have one minimal hash."""
    generated = (peer.parent / "unitree_go.c").read_text()
    for cls in TYPES:
        name = cls.__name__
        found = re.search(r"#define TYPE_INFO_CDR_unitree_go_msg_dds__" + name
                          + r" \(unsigned char \[\]\)\{(.*?)\}", generated, re.S)
        assert found is not None, name
        info = bytes(int(x, 16) for x in re.findall(r"0x([0-9a-f]{2})", found.group(1)))
        peer_minimal = info[info.index(0xF1) + 1:][:14]  # EK_MINIMAL, then the 14-byte hash
        ours = cls.__idl__.get_type_info().minimal.typeid_with_size.type_id
        assert bytes(ours.value) == peer_minimal, name
    # The C++ prefixes of the facts sheet, once, so that both sides cannot drift together.
    assert bytes(LowCmd_.__idl__.get_type_info().minimal.typeid_with_size.type_id.value) \
        .hex().startswith("832876ceec9737d69f6ed62a3f63")


@pytest.mark.parametrize("side", SIDES)
def test_peer_echoes_our_states(peer: Path, endpoint_factory, tmp_path: Path, side: str) -> None:
    """We publish LowState_ 1..TICKS with the SDK's CRC, the 0.10.2 peer answers each with its
    echo LowCmd_ and finds our CRC valid."""
    domain_id = _domain_id(SIDES.index(side))
    ours = endpoint_factory(domain_id, sample_class(LowState_, side), LOW_STATE_TOPIC,
                            sample_class(LowCmd_, side), LOW_CMD_TOPIC)
    proc = _start_peer(peer, "echo-state", domain_id, tmp_path)
    answers: dict[int, LowCmd_] = {}
    resent = 0
    try:
        deadline = time.monotonic() + PEER_TIMEOUT_S
        for k in range(1, TICKS + 1):
            state = with_crc(known_state(k), side)
            while k not in answers and time.monotonic() < deadline and proc.poll() is None:
                ours.writer.write(state)
                sent_at = time.monotonic()
                while k not in answers and time.monotonic() - sent_at < RESEND_S:
                    for cmd in ours.take(RESEND_S):
                        cmd = as_idl(cmd)
                        answers.setdefault(cmd.reserve, cmd)
                resent += k not in answers
    finally:
        fields, out, err = _finish_peer(proc, "echo-state", tmp_path)
    assert sorted(answers) == list(range(1, TICKS + 1)), (sorted(answers), resent, out, err)
    for k, cmd in answers.items():
        assert plain(cmd) == plain(echo(known_state(k))), k
    _assert_clean(fields, err, proc.returncode)
    # Every state reached the peer intact (it compares with its own known_state()), and the
    # CRC we set is the one the peer computes over the state's C image.
    assert int(fields["matched"]) == int(fields["received"]) >= TICKS, fields
    assert fields["crc_valid"] == fields["received"], fields


@pytest.mark.parametrize("side", SIDES)
def test_we_echo_the_peers_states(peer: Path, endpoint_factory, tmp_path: Path,
                                  side: str) -> None:
    """The 0.10.2 peer publishes LowState_ 1..TICKS with the SDK's CRC, which ours accepts; we
    answer each with a LowCmd_ carrying our CRC, which the peer checks with all its fields."""
    domain_id = _domain_id(2 + SIDES.index(side))
    ours = endpoint_factory(domain_id, sample_class(LowCmd_, side), LOW_CMD_TOPIC,
                            sample_class(LowState_, side), LOW_STATE_TOPIC)
    proc = _start_peer(peer, "publish-state", domain_id, tmp_path)
    states: dict[int, LowState_] = {}
    crc_accepted: dict[int, bool] = {}
    try:
        deadline = time.monotonic() + PEER_TIMEOUT_S
        while proc.poll() is None and time.monotonic() < deadline:
            for sample in ours.take(RESEND_S):
                state = as_idl(sample)
                states.setdefault(state.tick, state)
                crc_accepted.setdefault(state.tick, crc_ok(record_of(sample)))
                ours.writer.write(with_crc(echo(state), side))
    finally:
        fields, out, err = _finish_peer(proc, "publish-state", tmp_path)
    assert sorted(states) == list(range(1, TICKS + 1)), (sorted(states), out, err)
    for k, state in states.items():
        assert state.crc != 0, k  # the peer sets the SDK's CRC of its C image
        assert plain(state) == {**plain(known_state(k)), "crc": state.crc}, k
    # Our CRC of the C image equals the one the peer computed from its C memory.
    assert crc_accepted == dict.fromkeys(range(1, TICKS + 1), True)
    _assert_clean(fields, err, proc.returncode)
    assert (fields["matched"], fields["sent"]) == (str(TICKS), str(TICKS + int(fields["resent"])))
    assert out.count("matches_echo=1") == int(fields["received"]), out
    # Every LowCmd_ we sent carries the CRC the peer computes over its C image, which the
    # robot checks before it takes a command.
    assert fields["crc_valid"] == fields["received"], fields
    assert out.count("crc_valid=1") == int(fields["received"]), out
