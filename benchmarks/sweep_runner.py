"""Where a sweep's episodes run: Ray (local or a cluster), a local process pool, or in turn.

Every episode is one task, and a deterministic one (simulated time, fixed seeds): the three
executors give the same results. Ray is an optional extra (``pip install 'go2-wbc[scale]'``);
without it, ``auto`` runs a process pool of the standard library and says how to get Ray.
"""

from __future__ import annotations

import importlib.util
import logging
import os
import signal
import socket
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, wait
from typing import Any

from benchmarks.robustness import process_pool
from benchmarks.sweep_spec import EpisodeSpec
from wbc.core.errors import ConfigurationError

#: ``auto``: Ray when installed, else the process pool.
EXECUTORS = ("auto", "ray", "process", "serial")
#: How to get Ray.
RAY_INSTALL = (
    "pip install 'go2-wbc[scale]' (in a clone of the repository: pip install -e '.[scale]')")
#: Tasks queued per worker beyond the running one: keeps workers busy between results while
#: an interrupted sweep has few tasks to cancel.
QUEUED_PER_WORKER = 1
#: How long [s] a cluster's HOST:PORT may take to accept a connection (Ray itself retries
#: for minutes).
CONNECT_TIMEOUT_S = 5.0
#: Object store of a local Ray instance [bytes]: the tasks pass a few kilobytes each.
LOCAL_OBJECT_STORE_BYTES = 200 * 2**20

#: Called with each episode and what its task returned, in the driver, as results arrive.
OnDone = Callable[[EpisodeSpec, dict[str, Any]], None]


def ray_installed() -> bool:
    """Whether Ray can be imported here (checked without importing it)."""
    return importlib.util.find_spec("ray") is not None


def execute(episode: EpisodeSpec) -> dict[str, Any]:
    """Run one episode, in a worker; returns ``result`` or ``error``, ``wall_s`` and ``worker``.

    An episode that raises is reported, not propagated: one bad episode does not end a sweep
    of thousands (its record says what it raised, and a resumed sweep runs it again).
    """
    started = time.perf_counter()
    try:
        outcome: dict[str, Any] = {"result": episode.run()}
    except Exception as err:  # noqa: BLE001  (reported in the episode's record)
        outcome = {"error": f"{type(err).__name__}: {err}"}
    outcome["wall_s"] = round(time.perf_counter() - started, 3)
    outcome["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    return outcome


class SweepRunner:
    """Runs episodes with one executor and hands each result over as it arrives.

    Args:
        executor: ``auto`` (Ray when installed, else ``process``), ``ray``, ``process`` (a
            local pool of the standard library) or ``serial`` (in this process, in turn).
        jobs: Episodes at once: the local Ray instance's CPUs or the pool's processes
            (default: every core); with ``address``, a cap on the tasks in flight (default:
            the cluster's CPUs).
        address: A Ray cluster to connect to (``auto``, ``HOST:6379``, ``ray://HOST:10001``);
            ``None`` starts a local instance.

    Raises:
        ConfigurationError: An unknown executor, ``jobs`` below 1, ``address`` without Ray
            or where nothing listens, or ``ray`` asked for where it is not installed (the
            message says how to get it).
    """

    def __init__(self, executor: str = "auto", *, jobs: int | None = None,
                 address: str | None = None) -> None:
        if executor not in EXECUTORS:
            raise ConfigurationError(
                f"executor: expected one of {', '.join(EXECUTORS)}, received {executor!r}")
        if jobs is not None and (isinstance(jobs, bool) or not isinstance(jobs, int)
                                 or jobs < 1):
            raise ConfigurationError(f"jobs: expected a whole number >= 1, received {jobs!r}")
        if address is not None and executor not in ("auto", "ray"):
            raise ConfigurationError(
                f"address: a Ray cluster's address needs the ray executor, received executor "
                f"{executor!r} with address {address!r}")
        #: Why ``auto`` did not pick Ray (``None`` when it did, or was not asked to pick).
        self.note: str | None = None
        if executor in ("auto", "ray") and not ray_installed():
            if executor == "ray" or address is not None:
                wanted = "executor 'ray'" if executor == "ray" else f"address {address!r}"
                raise ConfigurationError(
                    f"{'executor' if executor == 'ray' else 'address'}: {wanted} needs Ray, "
                    f"which is not installed here; {RAY_INSTALL}, or run executor 'process'")
            executor = "process"
            self.note = (f"Ray is not installed: the episodes run in a local process pool. "
                         f"For Ray (every core, or a cluster with --address): {RAY_INSTALL}")
        elif executor == "auto":
            executor = "ray"
        if address is not None:
            _check_listening(address)
        self.executor = executor
        self.jobs = jobs
        self.address = address
        #: How the last run went, for the report: ``Ray (local instance, 2 CPUs)``...
        self.description = executor

    def run(self, episodes: Iterable[EpisodeSpec], on_done: OnDone) -> None:
        """Run ``episodes``; ``on_done`` gets each one's outcome as it arrives.

        An interrupt (``KeyboardInterrupt``) cancels what has not finished and propagates;
        the outcomes handed over until then stand.
        """
        episodes = list(episodes)
        if self.executor == "serial":
            self.description = "serial (this process)"
            for episode in episodes:
                on_done(episode, execute(episode))
        elif self.executor == "process":
            self._run_pool(episodes, on_done)
        else:
            self._run_ray(episodes, on_done)

    # ------------------------------------------------------------------ the process pool

    def _run_pool(self, episodes: list[EpisodeSpec], on_done: OnDone) -> None:
        workers = self.jobs or os.cpu_count() or 1
        self.description = f"process pool ({workers} processes)"
        if not episodes:
            return
        # Workers forked from a clean server that has imported the episode code once.
        pool = process_pool(workers, preload=["benchmarks.sweep_runner"])
        waiting = iter(episodes)
        running: dict[Future[dict[str, Any]], EpisodeSpec] = {}

        def submit() -> None:
            episode = next(waiting, None)
            if episode is not None:
                running[pool.submit(execute, episode)] = episode

        try:
            for _ in range(workers * (1 + QUEUED_PER_WORKER)):
                submit()
            while running:
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                for future in done:
                    episode = running.pop(future)
                    on_done(episode, future.result())
                    submit()
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown()

    # ------------------------------------------------------------------ Ray

    def _run_ray(self, episodes: list[EpisodeSpec], on_done: OnDone) -> None:
        local = self.address is None
        if local:
            # Ray's single-machine switch: the local instance's processes talk over
            # 127.0.0.1, not over the machine's network address.
            os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
        os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
        import ray

        started_here = not ray.is_initialized()
        on_term = signal.getsignal(signal.SIGTERM)
        if started_here and local:
            ray.init(num_cpus=self.jobs or os.cpu_count() or 1, include_dashboard=False,
                     log_to_driver=False, logging_level=logging.ERROR,
                     object_store_memory=LOCAL_OBJECT_STORE_BYTES)
        elif started_here:
            try:
                ray.init(address=self.address, log_to_driver=False,
                         logging_level=logging.ERROR)
            except (ConnectionError, RuntimeError, ValueError) as err:
                reason = str(err).strip().splitlines()[0] if str(err).strip() else repr(err)
                raise ConfigurationError(
                    f"address: cannot connect to a Ray cluster at {self.address!r} ({reason}); "
                    f"expected the address of a running cluster: auto on one of its nodes, "
                    f"HOST:6379, or ray://HOST:10001") from err
        if callable(on_term) and threading.current_thread() is threading.main_thread():
            # Ray's driver replaces the SIGTERM handler; the caller's (a clean stop) comes back.
            signal.signal(signal.SIGTERM, on_term)
        try:
            cpus = int(ray.cluster_resources().get("CPU", 1))
            where = "local instance" if local else f"cluster at {self.address}"
            self.description = f"Ray ({where}, {cpus} CPUs)"
            slots = self.jobs or cpus
            task = ray.remote(num_cpus=1)(execute)
            self._ray_loop(ray, task, iter(episodes), slots, on_done)
        finally:
            if started_here:
                ray.shutdown()

    @staticmethod
    def _ray_loop(ray: Any, task: Any, waiting: Iterator[EpisodeSpec], slots: int,
                  on_done: OnDone) -> None:
        running: dict[Any, EpisodeSpec] = {}

        def submit() -> None:
            episode = next(waiting, None)
            if episode is not None:
                running[task.remote(episode)] = episode

        try:
            for _ in range(slots * (1 + QUEUED_PER_WORKER)):
                submit()
            while running:
                ready, _ = ray.wait(list(running), num_returns=1)
                for ref in ready:
                    episode = running.pop(ref)
                    try:
                        outcome = ray.get(ref)
                    except ray.exceptions.RayError as err:  # the worker died (after retries)
                        outcome = {"error": f"{type(err).__name__}: {err}", "wall_s": None,
                                   "worker": None}
                    on_done(episode, outcome)
                    submit()
        except BaseException:
            for ref in running:
                ray.cancel(ref, force=True)
            raise


def _check_listening(address: str) -> None:
    """Fail at once when nothing accepts connections at a ``HOST:PORT`` address.

    ``auto`` and ``ray://`` addresses are left to Ray.

    Raises:
        ConfigurationError: No connection within :data:`CONNECT_TIMEOUT_S`.
    """
    host, sep, port = address.rpartition(":")
    if "://" in address or not sep or not port.isdigit():
        return
    try:
        socket.create_connection((host.strip("[]"), int(port)), CONNECT_TIMEOUT_S).close()
    except OSError as err:
        raise ConfigurationError(
            f"address: cannot connect to a Ray cluster at {address!r} "
            f"({err.strerror or err}); expected the address of a running cluster: auto on one "
            f"of its nodes, HOST:6379, or ray://HOST:10001") from None
