"""Tests of wbc.core.compiled_call: a kernel bound to its arguments runs the dispatcher's code."""

import numba
import numpy as np

from wbc.core.compiled_call import bind_compiled


@numba.njit(cache=False)
def _scaled_sum(values, scale, out):
    out[0] = scale * values.sum()
    return out[0] > 0.0


def test_bound_call_returns_what_the_dispatcher_returns_and_sees_in_place_updates():
    values, out = np.array([1.0, 2.0, 3.0]), np.zeros(1)
    call = bind_compiled(_scaled_sum, values, 2.0, out)
    assert call() is True
    assert out[0] == 12.0
    values[:] = [-1.0, -2.0, 0.5]  # the bound array, updated in place
    assert call() is False
    assert out[0] == -5.0
    expected = np.zeros(1)
    assert _scaled_sum(values, 2.0, expected) is False
    assert expected[0] == out[0]


def test_bound_call_uses_the_overload_of_its_arguments_types():
    ints, out = np.array([1, 2], dtype=np.int64), np.zeros(1)
    bind_compiled(_scaled_sum, ints, 0.5, out)()
    assert out[0] == 1.5
    bind_compiled(_scaled_sum, np.array([1.0, 2.0]), 0.5, out)()
    signatures = {sig[0].dtype for sig in _scaled_sum.signatures}
    assert signatures == {numba.int64, numba.float64}
