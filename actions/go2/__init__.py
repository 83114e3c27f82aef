"""The GO2's behaviours served as actions: HighFive, FollowJointTrajectory, Stand and Sit, and
the context they read the robot through.
"""
