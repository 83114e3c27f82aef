"""The whole-body controller and its parts: configuration, contact schedule, the QP's problem,
plans and kernels, failure recovery, motor command shaping, and the simpler controllers beside it.
"""
