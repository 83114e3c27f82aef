"""The ground floor: errors, argument checks, conventions and compiled helpers that every
other floor uses; it imports nothing of the project.
"""
