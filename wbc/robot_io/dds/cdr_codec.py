"""CDR encoding of a C-image record (:mod:`wbc.robot_io.dds.c_layout`) as one compiled byte copy.

The GO2's messages are final structs of primitives and fixed arrays, so their CDR encoding is
a fixed byte layout: every primitive aligned to its own size (at most 8 in XCDR1, 4 in XCDR2;
none here is larger than 4) relative to the payload start, with no struct padding, after a
4-byte encapsulation header. XCDR2 adds one thing for these types: a 4-byte length (DHEADER)
before each array of structs (``motor_cmd``, ``motor_state``). The C image pads structs to
their alignment, so the two layouts part from byte 22 on (``motor_cmd[0].mode``).

Both layouts are fixed, so converting one to the other is a byte permutation, computed once
from the record's dtype: :class:`CdrCodec` encodes and decodes with one compiled gather
(~1 us) where cyclonedds' Python ``IdlStruct`` machinery walks the fields (~0.1-0.3 ms).
``tests/test_dds_messages.py`` checks the bytes against ``IdlStruct.serialize`` for both
XCDR versions.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from wbc.core.errors import ConfigurationError, WbcError
from wbc.robot_io.dds.c_layout import check_record, zero_record

#: Encapsulation identifiers (first two header bytes, big-endian) of a final struct:
#: ``(xcdr_version, little_endian)``.
_ENCAPSULATIONS: dict[int, tuple[int, bool]] = {
    0x0000: (1, False),  # CDR_BE
    0x0001: (1, True),   # CDR_LE
    0x0006: (2, False),  # PLAIN_CDR2_BE
    0x0007: (2, True),   # PLAIN_CDR2_LE
}
_HEADER_SIZE = 4
_ALIGN_MAX = {1: 8, 2: 4}


class FrameError(WbcError, ValueError):
    """A received message that cannot be used: its encoding, size, header or CRC is wrong.

    The message names the field, what was received and what is valid.
    """


_BYTES_RO = numba.types.Array(numba.uint8, 1, "C", readonly=True)
_INDEX = numba.intp[::1]


@numba.njit(numba.void(_BYTES_RO, _INDEX, numba.uint8[::1], _INDEX), cache=True)
def _permute(source, source_index, target, target_index):  # pragma: no cover - compiled
    """``target[target_index[i]] = source[source_index[i]]`` for every ``i``."""
    for i in range(source_index.shape[0]):
        target[target_index[i]] = source[source_index[i]]


@dataclass(frozen=True)
class _Layout:
    """One XCDR version's encoding of a record: which message byte holds which C byte."""

    #: Message size without the trailing alignment padding [B], header included.
    size: int
    #: C-image byte of each encoded data byte (little-endian message).
    c_index: np.ndarray
    #: Message byte of each encoded data byte, little-endian.
    le_index: np.ndarray
    #: Message byte of each encoded data byte, big-endian (bytes of a primitive reversed).
    be_index: np.ndarray
    #: ``(message offset, array field name, content length [B])`` of each XCDR2 DHEADER.
    dheaders: tuple[tuple[int, str, int], ...]
    #: Flat little-endian dtype of the message (header as ``encapsulation``), for inspection.
    dtype: np.dtype


def _layout(record_dtype: np.dtype, version: int) -> _Layout:
    align_max = _ALIGN_MAX[version]
    c_index: list[int] = []
    le_index: list[int] = []
    be_index: list[int] = []
    dheaders: list[tuple[int, str, int]] = []
    fields: dict[str, tuple[np.dtype, int]] = {
        "encapsulation": (np.dtype(("u1", _HEADER_SIZE)), 0)}
    pos = _HEADER_SIZE  # the message offset; alignment counts from the payload start

    def align(size: int) -> int:
        step = min(size, align_max)
        return _HEADER_SIZE + (pos - _HEADER_SIZE + step - 1) // step * step

    def walk(dtype: np.dtype, c_base: int, prefix: str) -> None:
        nonlocal pos
        fields_of: Mapping[str, Any] = dtype.fields or {}
        for name in dtype.names or ():
            field_dtype, c_offset = fields_of[name][:2]
            elem, shape = field_dtype.subdtype or (field_dtype, ())
            count = int(np.prod(shape))
            c_offset += c_base
            if elem.names is not None:  # a struct, or an array of structs
                if not shape:
                    walk(elem, c_offset, f"{prefix}{name}.")
                    continue
                start = 0
                if version == 2:
                    pos = align(4)
                    start = pos
                    pos += 4
                for k in range(count):
                    walk(elem, c_offset + k * elem.itemsize, f"{prefix}{name}[{k}].")
                if version == 2:
                    dheaders.append((start, prefix + name, pos - start - 4))
                continue
            size = elem.itemsize
            pos = align(size)
            fields[prefix + name] = (np.dtype((elem.newbyteorder("<"), shape)) if shape
                                     else elem.newbyteorder("<"), pos)
            for k in range(count):
                for b in range(size):
                    c_index.append(c_offset + k * size + b)
                    le_index.append(pos + b)
                    be_index.append(pos + size - 1 - b)
                pos += size

    walk(record_dtype, 0, "")
    flat = np.dtype({"names": list(fields), "formats": [f for f, _ in fields.values()],
                     "offsets": [o for _, o in fields.values()], "itemsize": pos})
    return _Layout(size=pos, c_index=np.array(c_index, dtype=np.intp),
                   le_index=np.array(le_index, dtype=np.intp),
                   be_index=np.array(be_index, dtype=np.intp), dheaders=tuple(dheaders),
                   dtype=flat)


class CdrCodec:
    """Encodes C-image records of one message type to CDR and decodes them back.

    Encoding writes little-endian (the byte order cyclonedds uses on x86 and ARM hosts);
    decoding reads either byte order and both XCDR versions, from the encapsulation header.

    Example:
        >>> codec = CdrCodec(LOW_STATE_DTYPE, "LowState_")
        >>> data = codec.encode(record, xcdr_version=1)   # bytes, as IdlStruct.serialize
        >>> record = codec.decode(data)                   # a fresh C-image record
    """

    def __init__(self, record_dtype: np.dtype, type_name: str):
        """Args:
            record_dtype: The C-image dtype (aligned structured, primitives of 1 to 4 B).
            type_name: The IDL type's name, for error messages.
        """
        self.record_dtype = record_dtype
        self.type_name = type_name
        self._layouts = {version: _layout(record_dtype, version) for version in _ALIGN_MAX}
        self._templates: dict[int, np.ndarray] = {}
        for version, layout in self._layouts.items():
            # The constant bytes of a little-endian message: header, DHEADERs, zero padding.
            template = np.zeros(layout.size, dtype=np.uint8)
            template[1] = 0x07 if version == 2 else 0x01
            for offset, _, length in layout.dheaders:
                template[offset:offset + 4] = list(length.to_bytes(4, "little"))
            self._templates[version] = template

    def message_size(self, xcdr_version: int = 1) -> int:
        """The encoded size [B], header included, before padding to a multiple of 4."""
        return self._layout(xcdr_version).size

    def cdr_dtype(self, xcdr_version: int = 1) -> np.dtype:
        """A flat little-endian dtype of the whole message (``encapsulation`` header, then
        fields named as ``"motor_state[3].q"``): ``np.frombuffer(data, dtype)`` reads one."""
        return self._layout(xcdr_version).dtype

    def _layout(self, xcdr_version: int) -> _Layout:
        try:
            return self._layouts[xcdr_version]
        except KeyError:
            raise ConfigurationError(
                f"xcdr_version: expected 1 or 2, received {xcdr_version!r}") from None

    def encode(self, record: np.ndarray, *, xcdr_version: int = 1) -> bytes:
        """The CDR message of ``record``, header included, as cyclonedds' ``serialize`` gives it
        (little-endian, not padded to a multiple of 4; ``DataWriter.write`` pads).

        Raises:
            ConfigurationError: ``record`` is not a 0-d array of this codec's dtype, or an
                XCDR version other than 1 or 2.
        """
        layout = self._layout(xcdr_version)
        check_record(record, self.record_dtype, "record")
        message = self._templates[xcdr_version].copy()
        _permute(np.frombuffer(record, dtype=np.uint8), layout.c_index, message,
                 layout.le_index)
        return message.tobytes()

    def decode(self, data: bytes | bytearray | memoryview, *, has_header: bool = True,
               xcdr_version: int = 1, little_endian: bool = True,
               out: np.ndarray | None = None) -> np.ndarray:
        """The C-image record of a CDR message (its padding bytes zero).

        Args:
            data: The message, as a ``DataReader`` hands it over (trailing alignment padding
                of up to 3 bytes allowed).
            has_header: ``data`` starts with the encapsulation header, which gives the XCDR
                version and the byte order. Without it, ``xcdr_version`` and
                ``little_endian`` say how the payload is encoded.
            xcdr_version: 1 or 2, only read when ``has_header`` is false.
            little_endian: The byte order, only read when ``has_header`` is false.
            out: A record of this codec's dtype to fill in place (its padding bytes are left
                as they are); a fresh one when not given.

        Raises:
            FrameError: An unknown encapsulation, a wrong size, or an XCDR2 array length
                that does not match the type.
        """
        if has_header:
            if len(data) < _HEADER_SIZE:
                raise FrameError(
                    f"{self.type_name}: expected a CDR message of at least "
                    f"{self._layouts[1].size} B, received {len(data)} B")
            encapsulation = data[0] << 8 | data[1]
            if encapsulation not in _ENCAPSULATIONS:
                valid = ", ".join(f"0x{e:04X}" for e in _ENCAPSULATIONS)
                raise FrameError(
                    f"{self.type_name}: encapsulation: expected one of {valid} (XCDR1/XCDR2, "
                    f"big/little-endian, final struct), received 0x{encapsulation:04X}")
            xcdr_version, little_endian = _ENCAPSULATIONS[encapsulation]
            message = np.frombuffer(data, dtype=np.uint8)
        else:
            message = np.concatenate([np.zeros(_HEADER_SIZE, np.uint8),
                                      np.frombuffer(data, dtype=np.uint8)])
        layout = self._layout(xcdr_version)
        if not layout.size <= len(message) <= layout.size + 3:
            raise FrameError(
                f"{self.type_name}: expected {layout.size} B of XCDR{xcdr_version} "
                f"(+ up to 3 B of padding), received {len(message)} B")
        for offset, name, length in layout.dheaders:
            received = int.from_bytes(message[offset:offset + 4].tobytes(),
                                      "little" if little_endian else "big")
            if received != length:
                raise FrameError(
                    f"{self.type_name}.{name}: expected an XCDR2 length header of {length} B, "
                    f"received {received}")
        if out is None:
            out = zero_record(self.record_dtype)
        else:
            check_record(out, self.record_dtype, "out")
        _permute(message, layout.le_index if little_endian else layout.be_index,
                 np.frombuffer(out, dtype=np.uint8), layout.c_index)
        return out

