"""MuJoCo simulation of the GO2: the scene, the plant, and the control loop."""

from wbc.core.package_shadowing import check_not_shadowed

check_not_shadowed()  # a user's own sim.py or tasks.py: one line naming the file to rename
