"""Actions over Cyclone DDS: a bridge that serves a runner's action servers to other processes
(:mod:`actions.dds.dds_action_bridge`) and the client that talks to it
(:mod:`actions.dds.dds_action_client`), with their wire types, topics and QoS.
"""
