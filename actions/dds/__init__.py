"""Actions over Cyclone DDS: a bridge that serves a runner's action servers to other processes
(:mod:`actions.dds.dds_action_bridge`) and the client that talks to it
(:mod:`actions.dds.dds_action_client`). Their transport (the message types, topics, QoS,
readers and writers) is in the wire's home, :mod:`wbc.robot_io.dds`
(:mod:`~wbc.robot_io.dds.action_messages`, :mod:`~wbc.robot_io.dds.action_endpoints`,
:mod:`~wbc.robot_io.dds.served_directory`).
"""
