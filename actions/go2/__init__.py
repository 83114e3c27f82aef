"""The GO2's behaviours served as actions: HighFive, FollowJointTrajectory, Stand and Sit, the
context they read the robot through, and the GO2's interfaces (go2_interfaces).
"""
