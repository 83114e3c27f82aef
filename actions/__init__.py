"""Actions with ROS 2 semantics, without ROS: goals, feedback, cancellation, results."""
