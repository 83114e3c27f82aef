"""The notice before a first run's compilation: printed when numba's cache is cold only."""

from __future__ import annotations

import importlib
import io
import os
import sys
from pathlib import Path

import pytest

from sim.kernel_cache import LOOP_KERNEL_MODULES, NOTICE, cold_modules, notice_if_cold

KERNEL_SOURCE = '''
import numba


@numba.njit(cache=True)
def twice(x):
    return {factor} * x
'''


@pytest.fixture
def kernel_module(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """A module of one cached kernel, in a fresh directory (its cache starts cold)."""
    (tmp_path / "fresh_kernels.py").write_text(KERNEL_SOURCE.format(factor=2.0))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "fresh_kernels", raising=False)
    return "fresh_kernels"


@pytest.mark.slow  # compiles a kernel: about 2 s
def test_a_cold_module_is_named_until_its_kernel_is_compiled(kernel_module: str) -> None:
    assert cold_modules([kernel_module]) == [kernel_module]
    stream = io.StringIO()
    assert notice_if_cold(stream, [kernel_module])
    assert stream.getvalue() == f"go2-wbc: {NOTICE}\n"
    assert NOTICE.startswith("compiling the controller's kernels once, about a minute")
    assert importlib.import_module(kernel_module).twice(3.0) == 6.0  # compiled and cached
    assert cold_modules([kernel_module]) == []
    stream = io.StringIO()
    assert not notice_if_cold(stream, [kernel_module])
    assert stream.getvalue() == ""


@pytest.mark.slow  # compiles a kernel
def test_a_changed_kernel_is_cold_again(kernel_module: str, tmp_path: Path) -> None:
    importlib.import_module(kernel_module).twice(1.0)
    assert cold_modules([kernel_module]) == []
    path = tmp_path / "fresh_kernels.py"
    path.write_text(KERNEL_SOURCE.format(factor=3.0))
    stat = path.stat()  # numba's index is keyed on the source's mtime and size
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))
    del sys.modules[kernel_module]
    assert cold_modules([kernel_module]) == [kernel_module]


def test_the_loop_s_kernel_modules_have_cached_kernels() -> None:
    """The modules checked hold cached kernels (a renamed module would make the check
    silently vacuous)."""
    from numba.core.registry import CPUDispatcher

    for name in LOOP_KERNEL_MODULES:
        module = importlib.import_module(name)
        cached = [value for value in vars(module).values()
                  if isinstance(value, CPUDispatcher) and value._cache.__class__.__name__
                  == "FunctionCache"]
        assert cached, f"{name}: no kernel compiled with cache=True"
