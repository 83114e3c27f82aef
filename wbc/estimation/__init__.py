"""State estimation: the base's state from what a GO2 measures (IMU, joint encoders, foot
forces) and the controller's contact schedule.
"""
