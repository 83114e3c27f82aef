"""The GO2's model: its description (URDF, joints, feet, poses), joint orders, rigid-body
and leg kinematics, support polygons.
"""
