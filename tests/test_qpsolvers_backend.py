"""qpsolvers_backend: the optional quadprog (extra ``solvers``) reported as not installed."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from wbc.backends.qpsolvers_backend import EXTRAS, SOLVERS, missing_reason

ROOT = Path(__file__).resolve().parents[1]
NOT_INSTALLED = ("quadprog is not installed (GPL-2.0-or-later, an optional extra): "
                 "pip install 'go2-wbc[solvers]'")


def test_quadprog_is_an_optional_extra_not_a_dependency():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert not [d for d in project["dependencies"] if d.startswith("quadprog")]
    assert project["optional-dependencies"]["solvers"] == ["quadprog==0.1.14"]
    assert EXTRAS == {"quadprog": ("solvers", "GPL-2.0-or-later")}
    # make (scripts/setup.sh) installs it, so the benchmark and its tests keep quadprog's row.
    assert "'.[test,scale,solvers]'" in (ROOT / "scripts" / "setup.sh").read_text()


def test_missing_reason_names_the_extra():
    assert missing_reason("quadprog") == NOT_INSTALLED
    assert missing_reason("ecos") == "qpsolvers does not see solver 'ecos' on this machine"
    assert set(EXTRAS) <= set(SOLVERS)


# Without quadprog (its import blocked, as on an install without the extra): the backend and
# the benchmark's report each say so in one line naming the extra.
_WITHOUT_QUADPROG = """
import sys
sys.modules["quadprog"] = None
from wbc.backends import make_backend, missing_backends
from wbc.core.errors import UnknownNameError
try:
    make_backend("qpsolvers:quadprog")
except UnknownNameError as err:
    print("ERROR", err)
from benchmarks.qp_timing_report import backend_line
for name, reason in missing_backends().items():
    if "quadprog" in name:
        print(backend_line({"name": name, "skipped": reason}))
"""


@pytest.mark.slow
def test_without_quadprog_backend_and_benchmark_say_not_installed():
    out = subprocess.run([sys.executable, "-c", _WITHOUT_QUADPROG], cwd=ROOT, check=True,
                         capture_output=True, text=True, timeout=120).stdout.splitlines()
    assert out[0].startswith("ERROR unknown backend 'qpsolvers:quadprog' (" + NOT_INSTALLED + ")")
    assert f"{'qpsolvers:quadprog':<22}skipped: {NOT_INSTALLED}" in out[1:]
