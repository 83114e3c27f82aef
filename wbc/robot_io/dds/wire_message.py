"""``LowState_`` and ``LowCmd_`` samples for a normal cyclonedds ``Topic``, ``DataWriter`` and
``DataReader``, (de)serialised by a compiled byte copy instead of cyclonedds' Python machinery.

How cyclonedds 11.0.1 uses a topic's data type (``cyclonedds/topic.py``, ``pub.py``,
``sub.py``):

- ``Topic(participant, name, data_type)`` needs ``data_type.__idl__``: it calls its
  ``populate()`` and ``fill_type_data()``, and the C layer reads the type name, the XTypes type
  information and mapping, keylessness and the supported XCDR versions from it.
- ``DataWriter.write(sample)`` checks ``isinstance(sample, topic.data_type)``, calls
  ``sample.serialize(use_version_2=...)`` (``None`` unless the writer's QoS picks a data
  representation: then the type's default, XCDR1 here) and pads the bytes to a multiple of 4.
- ``DataReader.take()`` / ``read()`` call ``topic.data_type.deserialize(data)`` for each valid
  sample (``deserialize_key`` for an invalid one, e.g. a writer that went away) and set
  ``sample_info`` on the result.

The classes here share the ``__idl__`` of :class:`~wbc.robot_io.dds.go2_types.LowState_` /
``LowCmd_``: the type registered on the wire (name, type information, hashes) is exactly
theirs, so peers using the ``IdlStruct`` classes (or unitree_sdk2) match. Each sample holds a
C-image record (:mod:`wbc.robot_io.dds.c_layout`), the one the CRC and the conversions use::

    topic = Topic(participant, LOW_STATE_TOPIC, LowStateMessage)
    reader = DataReader(participant, topic)
    for message in reader.take():
        record = message.record        # 0-d array of LOW_STATE_DTYPE
"""

from __future__ import annotations

from typing import Any, ClassVar, Self

import numpy as np

from wbc.robot_io.dds.c_layout import LOW_CMD_DTYPE, LOW_STATE_DTYPE, check_record, zero_record
from wbc.robot_io.dds.cdr_codec import CdrCodec
from wbc.robot_io.dds.go2_types import LowCmd_, LowState_


class WireMessage:
    """A sample of one of the GO2's message types, holding its C-image record.

    Subclasses set the IDL class (:attr:`idl_type`) they stand for on the wire.
    """

    #: The ``IdlStruct`` class whose wire type this class uses.
    idl_type: ClassVar[type[Any]]
    #: That class's IDL description, read by cyclonedds' ``Topic`` (the same object).
    __idl__: ClassVar[Any]
    #: The C-image record dtype.
    dtype: ClassVar[np.dtype]
    _codec: ClassVar[CdrCodec]

    __slots__ = ("record", "sample_info")

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.__idl__ = cls.idl_type.__idl__
        cls._codec = CdrCodec(cls.dtype, cls.idl_type.__name__)

    def __init__(self, record: np.ndarray | None = None):
        """Args:
            record: The C-image record this sample carries, not copied: a writer sends what
                it holds when written. A zeroed record when not given.

        Raises:
            ConfigurationError: ``record`` is not a 0-d array of :attr:`dtype`.
        """
        if record is None:
            record = zero_record(self.dtype)
        else:
            check_record(record, self.dtype, "record")
        self.record: np.ndarray = record
        #: Set by ``DataReader.take``/``read``: cyclonedds' ``SampleInfo``.
        self.sample_info: Any = None

    def serialize(self, use_version_2: bool | None = None) -> bytes:
        """The CDR message, byte for byte what ``idl_type.serialize`` would give on a
        little-endian host (the only byte order written).

        Args:
            use_version_2: XCDR2 when true, XCDR1 when false, the type's default (XCDR1) when
                ``None``: what ``DataWriter.write`` passes.
        """
        if use_version_2 is None:
            self.__idl__.populate()  # sets default_version (idempotent, cheap)
            use_version_2 = self.__idl__.default_version == 2
        return self._codec.encode(self.record, xcdr_version=2 if use_version_2 else 1)

    @classmethod
    def deserialize(cls, data: bytes, has_header: bool = True,
                    use_version_2: bool | None = None) -> Self:
        """A sample from a CDR message (what ``DataReader.take`` calls).

        Raises:
            FrameError: A message of the wrong size or encoding.
        """
        record = cls._codec.decode(data, has_header=has_header,
                                   xcdr_version=2 if use_version_2 else 1)
        sample = cls.__new__(cls)
        sample.record = record
        sample.sample_info = None
        return sample

    @classmethod
    def deserialize_key(cls, data: bytes, has_header: bool = True,
                        use_version_2: bool | None = None) -> Self:
        """The key of a message: these types are keyless, so an all-zero sample."""
        return cls()

    def to_idl(self) -> Any:
        """The same message as an instance of :attr:`idl_type` (slow: for tests and tools)."""
        return self.idl_type.deserialize(self.serialize())

    @classmethod
    def from_idl(cls, sample: Any) -> Self:
        """A sample holding the record of an :attr:`idl_type` instance."""
        return cls.deserialize(sample.serialize())

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return self.record.tobytes() == other.record.tobytes()

    __hash__ = None  # type: ignore[assignment]  # mutable

    def __repr__(self) -> str:
        return f"{type(self).__name__}(record=<{self.dtype.itemsize} B C image>)"


class LowStateMessage(WireMessage):
    """A ``rt/lowstate`` sample (``unitree_go::msg::dds_::LowState_``) holding a
    :data:`~wbc.robot_io.dds.c_layout.LOW_STATE_DTYPE` record."""

    idl_type = LowState_
    dtype = LOW_STATE_DTYPE
    __slots__ = ()


class LowCmdMessage(WireMessage):
    """A ``rt/lowcmd`` sample (``unitree_go::msg::dds_::LowCmd_``) holding a
    :data:`~wbc.robot_io.dds.c_layout.LOW_CMD_DTYPE` record."""

    idl_type = LowCmd_
    dtype = LOW_CMD_DTYPE
    __slots__ = ()
