"""The GO2's low-level DDS messages (``rt/lowcmd``, ``rt/lowstate``) for Eclipse Cyclone DDS.

Modules (import them directly; this package re-exports nothing):

- :mod:`~wbc.robot_io.dds.go2_types`: the IDL types as ``IdlStruct`` classes, the topic names.
- :mod:`~wbc.robot_io.dds.c_layout`: the C memory image as NumPy records, the CRC.
- :mod:`~wbc.robot_io.dds.cdr_codec`: CDR to and from a record in one compiled byte copy.
- :mod:`~wbc.robot_io.dds.wire_message`: ``LowStateMessage`` / ``LowCmdMessage``, samples for
  a cyclonedds ``Topic`` that (de)serialise through the codec.
- :mod:`~wbc.robot_io.dds.low_state_conversion`, :mod:`~wbc.robot_io.dds.low_cmd_conversion`:
  records to and from :class:`~wbc.robot_io.sensor_record.SensorRecord` and
  :class:`~wbc.robot_io.sdk_motor_command.SdkMotorCommand`.
- :mod:`~wbc.robot_io.dds.domain_config`: a domain bound to one network interface, joined
  through :func:`~wbc.robot_io.dds.domain_config.join_domain` (one configuration per domain id
  and process, shared by every :class:`~wbc.robot_io.dds.domain_config.DomainHandle`).
"""
