"""Every compiled kernel of the library takes a few named groups, not dozens of arguments."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re

import numpy as np
from numba.core.registry import CPUDispatcher

from wbc.core.kernel_records import parameter_record, work_record

#: The most arguments a compiled kernel may take (STYLE.md: named groups, as the QP kernel's).
MOST_ARGUMENTS = 16
PACKAGES = ("wbc", "tasks", "sim", "actions")


def compiled_kernels() -> dict[str, int]:
    """Every numba dispatcher defined in the library's modules: ``module.name`` -> its
    number of arguments."""
    kernels = {}
    for package in PACKAGES:
        root = importlib.import_module(package)
        for info in pkgutil.walk_packages(root.__path__, package + "."):
            if info.name.endswith("__main__"):  # runs the command line when imported
                continue
            module = importlib.import_module(info.name)
            for value in vars(module).values():
                if isinstance(value, CPUDispatcher):
                    function = value.py_func
                    name = f"{function.__module__}.{function.__qualname__}"
                    kernels[name] = len(inspect.signature(function).parameters)
    return kernels


def test_no_compiled_kernel_takes_more_than_16_arguments():
    kernels = compiled_kernels()
    # The walk finds the kernels (a broken walk would find none and pass).
    assert len(kernels) > 50
    assert "wbc.estimation.invariant_ekf_kernels._estimate" in kernels
    assert "sim.sensors._sample" in kernels
    wide = {name: count for name, count in kernels.items() if count > MOST_ARGUMENTS}
    assert not wide, f"kernels with more than {MOST_ARGUMENTS} arguments: {wide}"


def test_no_kernel_slices_a_scratch_buffer_or_reads_a_parameter_by_index():
    """The estimators', the sensors' and the shaper's kernels read their parameters and work
    arrays by name: no ``params[3]``, no ``work[12:15]`` (``[0]`` is the record itself)."""
    by_position = re.compile(r"\b(params|work)\[(?!0\])")
    for name in ("wbc.estimation.shared_kernels", "wbc.estimation.state_estimator_kernels",
                 "wbc.estimation.invariant_ekf_kernels", "wbc.estimation.invariant_ekf_group",
                 "sim.sensors", "wbc.controller.motor_command_shaper"):
        source = inspect.getsource(importlib.import_module(name))
        assert not by_position.findall(source), name
    assert by_position.findall("p = params[5]; w = work[12:15]; x = params[end - 1]") == [
        "params", "work", "params"]


def test_records_hold_named_numbers_and_arrays():
    params = parameter_record({"foot_radius_m": 2, "use_foot_force": True})
    assert params[0]["foot_radius_m"] == 2.0 and params.dtype["foot_radius_m"] == np.float64
    assert params[0]["use_foot_force"] and params.dtype["use_foot_force"] == np.bool_
    work = work_record({"rotation": (3, 3), "step": (4,)})
    assert work[0]["rotation"].shape == (3, 3) and work[0]["step"].shape == (4,)
    work[0]["step"][:] = 1.0  # a view: the record holds the values
    assert np.all(work[0]["step"] == 1.0) and np.all(work[0]["rotation"] == 0.0)
