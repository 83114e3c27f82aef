"""The robot loop: the robot interface, the control loop that reads the robot, estimates its
state, ticks the actions and writes the motor command (a simulator or a real GO2), a
recorded robot.
"""
