"""ROS 2's standard interfaces that the GO2's actions use: std_msgs, geometry_msgs,
trajectory_msgs and control_msgs (with FollowJointTrajectory), one module per ROS 2 package.

Neither the framework's (the runner never looks inside a message) nor the GO2's (any robot's
joint trajectory server takes them): a floor of their own between the two.
"""
