"""What goes to and comes from the robot: the motor command, the sensor record and its log,
the Unitree SDK's low-level records.
"""
