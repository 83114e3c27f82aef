"""The whole-body controller: its configuration, contact modes, QP problem and kernels, motor
command shaping, and the simpler controllers beside it.
"""
