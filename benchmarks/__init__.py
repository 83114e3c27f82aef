"""Benchmarks of the controller: QP timing and episode quality."""
