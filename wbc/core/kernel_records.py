"""Named numbers and named work arrays for compiled kernels, each one array crossing the call.

A kernel's parameters and scratch arrays are read by name (``params.foot_radius_m``,
``work.rotation``), never by position in a vector or at an offset into a buffer. They are
held in a one-element NumPy structured array (a record), whose fields NumPy lays out by name:
numba reads a field at a fixed offset it computes, and the whole group crosses into compiled
code as one array. (A ``NamedTuple`` of floats or of arrays is unboxed field by field on
every call: measured at about 20 ns a float and 30 to 80 ns an array, over a microsecond a
tick for an estimator's 23 numbers and 30 work arrays; a record costs one array's.)

Allocated once, at construction; a kernel takes ``record[0]`` and reads its fields.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np


def parameter_record(values: Mapping[str, float | bool]) -> np.ndarray:
    """A record of named numbers: a float64 field per number, a bool field per bool.

    Args:
        values: Field name -> value (an int becomes a float: every number is float64, so
            the kernel compiles once whatever the config held).

    Returns:
        A one-element structured array (aligned fields), the values filled in.
    """
    dtype = np.dtype([(name, np.bool_ if isinstance(value, (bool, np.bool_)) else np.float64)
                      for name, value in values.items()], align=True)
    record = np.zeros(1, dtype=dtype)
    for name, value in values.items():
        record[0][name] = value
    return record


def work_record(shapes: Mapping[str, tuple[int, ...]]) -> np.ndarray:
    """A record of named float64 work arrays, zeroed: ``shapes`` maps each name to its shape.

    Returns:
        A one-element structured array (aligned fields): ``record[0].name`` is a view of
        that shape, in compiled code as in Python.
    """
    dtype = np.dtype([(name, np.float64, shape) for name, shape in shapes.items()], align=True)
    return np.zeros(1, dtype=dtype)
