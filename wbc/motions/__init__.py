"""Motions a controller is taken through: lifting a leg, moving between poses.
"""
