"""The simulated GO2, its controller and goal clients as separate processes on a private DDS
domain: start them, wait on what they print, signal them, read their reports, never leak one.

Each process is ``sys.executable -m sim.cli ...`` (``go2-wbc bridge``, ``go2-wbc run --dds``,
``go2-wbc high-five --dds``, ``go2-wbc send-goal ... --dds``) in its own process group, its
standard output and error captured to a file of the run's directory::

    with DdsProcesses(workdir) as run:
        bridge = run.bridge()               # returns once it says "running until"
        controller = run.controller()       # once it says "controlling at"
        client = run.high_five(height_m=0.4, hold_s=2.0)
        assert client.wait(timeout_s=30.0) == 0
        controller.stop()                   # Ctrl-C: cancel, sit, damp, exit (130)
        bridge.stop()
        ticks, truth = controller.log_path, bridge.log_path

Synchronisation waits on conditions with a timeout (a line printed, an exit, a file, a truth
sample: :func:`wait_until`), never on a fixed sleep. Leaving the ``with`` block kills every
process group still alive (SIGKILL, stopped ones included); so does the interpreter's exit,
and on Linux, when ``setpriv`` is there, each child also gets SIGKILL when the thread that
started it dies (``--pdeathsig``): start processes from a thread that outlives them, the main
thread.

The outputs and reports these processes write are read by :mod:`benchmarks.dds_outputs`; the
simulator's exact state, live, by :class:`benchmarks.dds_outputs.TruthMonitor`.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import IO, TypeVar

from wbc.core.errors import ConfigurationError, WbcError

#: The repository's root: the working directory of every process (``-m sim.cli`` resolves).
ROOT = Path(__file__).resolve().parents[1]
#: Longest waits [s]: a process's start-up line, a stop (Ctrl-C to exit), a kill.
START_TIMEOUT_S, STOP_TIMEOUT_S, KILL_TIMEOUT_S = 30.0, 30.0, 5.0
#: How often a wait checks its condition [s].
POLL_S = 0.01
#: The first lines the commands print once they run.
BRIDGE_READY = r"^running until "
CONTROLLER_READY = r"^controlling at "
#: Domain ids :func:`private_domain_id` picks from (other tests and benchmarks use 150, 187,
#: 200 to 231).
PRIVATE_DOMAINS = range(160, 185)

T = TypeVar("T")


class ProcessWaitError(WbcError, TimeoutError):
    """A condition on a process did not come true in time, or the process exited first."""


def private_domain_id(offset: int = 0) -> int:
    """A DDS domain id in :data:`PRIVATE_DOMAINS` chosen by this process's id (concurrent
    runs stay apart), moved by ``offset``."""
    return PRIVATE_DOMAINS[(os.getpid() + offset) % len(PRIVATE_DOMAINS)]


def wait_until(condition: Callable[[], T | None], *, timeout_s: float, what: str,
               poll_s: float = POLL_S, context: Callable[[], str] | None = None) -> T:
    """Poll ``condition`` until it returns a value; return that.

    Args:
        condition: Checked at once, then every ``poll_s`` [s] until it returns something
            other than ``None``; may raise to give up early.
        timeout_s: Longest wait [s].
        what: What is awaited, for the error message.
        context: Called on a timeout for what the message should add (an output's tail).

    Raises:
        ProcessWaitError: ``timeout_s`` passed first.
    """
    deadline = time.monotonic() + timeout_s
    while True:
        value = condition()
        if value is not None:
            return value
        if time.monotonic() >= deadline:
            extra = "" if context is None else f"\n{context()}"
            raise ProcessWaitError(f"{what}: not within {timeout_s:g} s{extra}")
        time.sleep(poll_s)


class ManagedProcess:
    """One ``go2-wbc`` process: its own process group, its output in a file.

    Args:
        name: A label, unique in its :class:`DdsProcesses` (the output file's stem).
        argv: The command line.
        output_path: Where standard output and error go.
        env: The environment (``None``: this process's).
    """

    def __init__(self, name: str, argv: Sequence[str], *, output_path: Path,
                 env: dict[str, str] | None = None) -> None:
        self.name = name
        self.argv = list(argv)
        self.output_path = output_path
        self._files: dict[str, Path] = {}
        self._file: IO[bytes] = output_path.open("wb")
        prefix = ["setpriv", "--pdeathsig", "KILL"] if _HAS_SETPRIV else []
        #: When it was started [s] (``time.monotonic``).
        self.started_s = time.monotonic()
        self.popen = subprocess.Popen(prefix + self.argv, cwd=ROOT, env=env,
                                      stdin=subprocess.DEVNULL, stdout=self._file,
                                      stderr=subprocess.STDOUT, start_new_session=True)
        _LIVE.add(self)

    def __repr__(self) -> str:
        state = "running" if self.alive else f"exit {self.returncode}"
        return f"ManagedProcess({self.name!r}, pid {self.pid}, {state})"

    @property
    def report_path(self) -> Path:
        """The ``--report`` file it was told to write (it exists once the process has
        exited).

        Raises:
            ConfigurationError: It was started without ``--report``.
        """
        return self._file_for("report")

    @property
    def log_path(self) -> Path:
        """The ``--log`` file it was told to write (see :attr:`report_path`)."""
        return self._file_for("log")

    def _file_for(self, option: str) -> Path:
        if option not in self._files:
            raise ConfigurationError(f"{self.name}: started without --{option}")
        return self._files[option]

    @property
    def pid(self) -> int:
        """The process id (also its process group's)."""
        return self.popen.pid

    @property
    def returncode(self) -> int | None:
        """Its exit status (negative: the signal that ended it); ``None`` while it runs."""
        return self.popen.poll()

    @property
    def alive(self) -> bool:
        """It has not exited (a stopped process is alive)."""
        return self.popen.poll() is None

    def cpu_s(self) -> float | None:
        """CPU time [s] it has used so far (user + system, all its threads), from
        ``/proc``; ``None`` once it has exited or where there is no ``/proc``."""
        try:
            fields = Path(f"/proc/{self.pid}/stat").read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            return None
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    # -- output ------------------------------------------------------------------------------

    def output(self) -> str:
        """Everything it has printed so far."""
        return self.output_path.read_bytes().decode("utf-8", errors="replace")

    def mark(self) -> int:
        """The output's length now: give it as ``after`` to wait for a later line only."""
        return len(self.output())

    def tail(self, lines: int = 25) -> str:
        """Its last ``lines`` lines of output, labelled, for error messages."""
        text = "\n".join(self.output().splitlines()[-lines:])
        state = "running" if self.alive else f"exited with {self.returncode}"
        return f"--- {self.name} ({state}), last lines of {self.output_path}:\n{text}"

    def wait_for_line(self, pattern: str, *, timeout_s: float = START_TIMEOUT_S,
                      after: int = 0) -> re.Match[str]:
        """Wait until a line matching ``pattern`` (a regular expression, multiline: ``^`` is a
        line's start) is printed after character ``after``; return the match.

        Raises:
            ProcessWaitError: Not within ``timeout_s``, or the process exited without it.
        """
        regex = re.compile(pattern, re.MULTILINE)

        def found() -> re.Match[str] | None:
            exited = not self.alive  # read the output after the exit: nothing comes later
            match = regex.search(self.output(), after)
            if match is None and exited:
                raise ProcessWaitError(f"{self.name}: exited ({self.returncode}) without "
                                       f"printing /{pattern}/\n{self.tail()}")
            return match

        return wait_until(found, timeout_s=timeout_s, what=f"{self.name}: /{pattern}/",
                          context=self.tail)

    def wait(self, timeout_s: float) -> int:
        """Wait for its exit; its exit status.

        Raises:
            ProcessWaitError: Still running after ``timeout_s`` (it is left running).
        """
        try:
            return self.popen.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            raise ProcessWaitError(f"{self.name}: still running after {timeout_s:g} s\n"
                                   f"{self.tail()}") from None

    # -- signals -----------------------------------------------------------------------------

    def send(self, sig: int) -> None:
        """Send ``sig`` to its process group (as a terminal sends Ctrl-C); nothing if it has
        exited."""
        if self.alive:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.pid, sig)

    def interrupt(self) -> None:
        """SIGINT (Ctrl-C)."""
        self.send(signal.SIGINT)

    def pause(self) -> None:
        """SIGSTOP: frozen until :meth:`resume`."""
        self.send(signal.SIGSTOP)

    def resume(self) -> None:
        """SIGCONT."""
        self.send(signal.SIGCONT)

    def kill(self, timeout_s: float = KILL_TIMEOUT_S) -> int:
        """SIGKILL (``kill -9``) to its group; wait for the exit; its exit status."""
        self.send(signal.SIGKILL)
        return self.wait(timeout_s)

    def stop(self, timeout_s: float = STOP_TIMEOUT_S) -> int:
        """Ctrl-C and wait for the exit (the commands come to rest and write their reports
        first); its exit status.

        Raises:
            ProcessWaitError: It did not exit within ``timeout_s`` (it is then killed).
        """
        self.resume()  # a stopped process would not see the SIGINT
        self.interrupt()
        try:
            return self.wait(timeout_s)
        except ProcessWaitError:
            self.close()
            raise

    def close(self) -> None:
        """Kill its group if it is alive (SIGKILL), reap it, close the output file;
        idempotent."""
        if self.alive:
            self.send(signal.SIGKILL)
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.popen.wait(timeout=KILL_TIMEOUT_S)
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.pid, signal.SIGKILL)  # any child left in its group
        self._file.close()
        _LIVE.discard(self)


class DdsProcesses:
    """The ``go2-wbc`` processes of one run on a private domain: started, named, and killed
    when the block ends (a context manager; :meth:`close` otherwise).

    Args:
        workdir: Where outputs, reports and logs go (created).
        domain_id: The DDS domain (default: :func:`private_domain_id`).
        interface: Its network interface (default: ``lo``).
    """

    def __init__(self, workdir: Path | str, *, domain_id: int | None = None,
                 interface: str = "lo") -> None:
        self.workdir = Path(workdir)
        self.workdir.mkdir(parents=True, exist_ok=True)
        self.domain_id = private_domain_id() if domain_id is None else domain_id
        self.interface = interface
        #: Every process started, in order.
        self.processes: list[ManagedProcess] = []
        self._names: dict[str, int] = {}
        _restore_sigint()

    def __enter__(self) -> DdsProcesses:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Kill every process still alive, the newest first (clients, then controllers, then
        bridges)."""
        for process in reversed(self.processes):
            process.close()

    def path(self, name: str) -> Path:
        """A file of the run's directory."""
        return self.workdir / name

    def start(self, name: str, *args: str) -> ManagedProcess:
        """Start ``go2-wbc ARGS`` (no domain options added) as ``name`` (``name-2``, ... when
        taken), its output in ``NAME.out``."""
        count = self._names[name] = self._names.get(name, 0) + 1
        label = name if count == 1 else f"{name}-{count}"
        argv = [sys.executable, "-m", "sim.cli", *args]
        env = os.environ | {"PYTHONUNBUFFERED": "1"}
        process = ManagedProcess(label, argv, output_path=self.path(f"{label}.out"), env=env)
        self.processes.append(process)
        return process

    def _dds(self) -> list[str]:
        return ["--domain", str(self.domain_id), "--interface", self.interface]

    def bridge(self, *args: str, rate_hz: int = 500, log: bool = True, report: bool = True,
               wait: bool = True) -> ManagedProcess:
        """``go2-wbc bridge`` (extra ``args`` appended), with ``--log NAME.npz`` and
        ``--report NAME.json`` unless told not; returns once it runs (``wait``)."""
        return self._start_with_files("bridge", ["bridge", *self._dds(), "--rate",
                                                 str(rate_hz), *args],
                                      log=log, report=report, ready=BRIDGE_READY if wait else None)

    def controller(self, *args: str, rate_hz: int = 500, log: bool = True, report: bool = True,
                   wait: bool = True) -> ManagedProcess:
        """``go2-wbc run --dds`` (extra ``args`` appended), with ``--log``/``--report`` files
        unless told not; returns once it controls (``wait``; a bridge must be running)."""
        return self._start_with_files(
            "controller", ["run", "--dds", *self._dds(), "--control-rate", str(rate_hz), *args],
            log=log, report=report, ready=CONTROLLER_READY if wait else None)

    def high_five(self, *, height_m: float = 0.4, hold_s: float = 2.0,
                  feedback: bool = False) -> ManagedProcess:
        """``go2-wbc high-five --dds`` (every feedback message printed with ``feedback``;
        otherwise one line a phase); does not wait."""
        args = ["high-five", "--dds", *self._dds(), "--height", f"{height_m:g}",
                "--hold", f"{hold_s:g}"]
        return self.start("client", *args, *(["--feedback"] if feedback else []))

    def send_goal(self, action: str, goal: str, *args: str) -> ManagedProcess:
        """``go2-wbc send-goal ACTION GOAL --dds`` (``goal`` in YAML); does not wait."""
        return self.start("client", "send-goal", action, goal, "--dds", *self._dds(), *args)

    def _start_with_files(self, name: str, args: list[str], *, log: bool, report: bool,
                          ready: str | None) -> ManagedProcess:
        count = self._names.get(name, 0) + 1
        stem = name if count == 1 else f"{name}-{count}"
        log_path, report_path = self.path(f"{stem}.npz"), self.path(f"{stem}.json")
        for wanted, path in ((log, log_path), (report, report_path)):
            if wanted:
                path.unlink(missing_ok=True)  # the file appears when the process writes it
        files = [*(["--log", str(log_path)] if log else []),
                 *(["--report", str(report_path)] if report else [])]
        process = self.start(name, *args, *files)
        if log:
            process._files["log"] = log_path
        if report:
            process._files["report"] = report_path
        if ready is not None:
            try:
                process.wait_for_line(ready)
            except ProcessWaitError:
                process.close()
                raise
        return process


def wait_for_file(path: Path, *, timeout_s: float, what: str | None = None) -> Path:
    """Wait until ``path`` exists and is not empty; return it."""
    return wait_until(lambda: path if path.is_file() and path.stat().st_size > 0 else None,
                      timeout_s=timeout_s, what=what or f"the file {path}")


def _restore_sigint() -> None:
    """Let children see Ctrl-C: a shell's background job starts with SIGINT ignored, which a
    child inherits (a ``go2-wbc`` goal client then never sees the SIGINT it is sent). On the
    main thread only (Python's rule for signal handlers)."""
    if (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) is signal.SIG_IGN):
        signal.signal(signal.SIGINT, signal.default_int_handler)


def _kill_leftovers() -> None:
    for process in list(_LIVE):
        process.close()


#: Whether each child can be told to die with the thread that started it.
_HAS_SETPRIV = sys.platform.startswith("linux") and shutil.which("setpriv") is not None
#: Every process not closed yet: killed at the interpreter's exit.
_LIVE: set[ManagedProcess] = set()
atexit.register(_kill_leftovers)
