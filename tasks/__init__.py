"""Acceleration-level tasks for whole-body control: error, Jacobian and drift from Pinocchio."""
