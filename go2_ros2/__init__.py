"""go2-wbc with ROS 2: the rclpy node, its client and the interface packages' build (the
``ros2`` extra; the one home of ``rclpy``)."""
