"""The GO2's wire on Eclipse Cyclone DDS: its messages (``rt/lowcmd``, ``rt/lowstate``, the
simulator's truth), both ends of the topic pair, the SDK's QoS, the domains, and the actions'
DDS transport. The one home of ``cyclonedds``: no module outside this package imports it.

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
- :mod:`~wbc.robot_io.dds.sdk_qos`: unitree_sdk2's QoS, one copy for both ends.
- :mod:`~wbc.robot_io.dds.controller_end`: ``ControllerEnd`` (``rt/lowstate`` read,
  ``rt/lowcmd`` written); :mod:`~wbc.robot_io.dds.robot_end`: ``RobotEnd`` (``rt/lowcmd`` read,
  ``rt/lowstate`` and the truth written); :mod:`~wbc.robot_io.dds.sim_truth`: the truth's type.
- :mod:`~wbc.robot_io.dds.state_listener`: the bring-up check's readers.
- :mod:`~wbc.robot_io.dds.action_messages`, :mod:`~wbc.robot_io.dds.action_endpoints`,
  :mod:`~wbc.robot_io.dds.served_directory`: actions over DDS (JSON payload topics).
- :mod:`~wbc.robot_io.dds.topic_endpoints`: a reader or writer of any one topic (tools).
"""
