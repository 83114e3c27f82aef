"""MuJoCo simulation of the GO2: the scene, the plant, and the control loop."""
