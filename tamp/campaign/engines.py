"""Where a campaign's runs happen: Ray (a local Ray started here, or a cluster) or this
process, one run after the other (the reference Ray's overhead is measured against).

Both take the same `Job`s, call the same `tamp.campaign.run.execute` and hand each
`RunRecord` to ``on_done`` as soon as it exists, in completion order. Both enforce the
per-run wall-time limit: Ray force-cancels the task (its worker process is killed, the
campaign goes on with a fresh one); in-process, a SIGALRM interrupts the run between two
Python steps (a hang inside one C++ call that never returns cannot be interrupted there:
use Ray for such scenarios).
"""

from __future__ import annotations

import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Sequence
from contextlib import contextmanager

from tamp.campaign.run import Job, RunRecord, crashed, execute, timed_out
from tamp.errors import InputError

OnDone = Callable[[RunRecord], None]


class LocalEngine:
    """Runs every job in this process, in seed order (``--workers 0``)."""

    name = "local"
    address: str | None = None
    workers = 0

    def __enter__(self) -> LocalEngine:
        return self

    def __exit__(self, *exc) -> None:
        return None

    def run(self, jobs: Sequence[Job], time_limit: float, on_done: OnDone) -> None:
        for job in jobs:
            t0 = time.perf_counter()
            try:
                with _alarm(time_limit):
                    rec = execute(job)
            except _Hung:
                rec = timed_out(job.seed, time_limit, time.perf_counter() - t0)
            on_done(rec)


class _Hung(BaseException):
    """Raised by the alarm; a BaseException so that a runner's ``except Exception`` cannot
    swallow it."""


@contextmanager
def _alarm(seconds: float):
    """Raise `_Hung` in this (main) thread after ``seconds`` of wall time."""
    if threading.current_thread() is not threading.main_thread():
        logging.getLogger("tamp").warning("in-process runs off the main thread have no time limit")
        yield
        return

    def hung(_signum, _frame):
        raise _Hung

    previous = signal.signal(signal.SIGALRM, hung)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def import_ray():
    """The ``ray`` module, or `tamp.extras.MissingExtra` (exit 2) naming the campaign extra."""
    try:
        import ray
    except ImportError:
        from tamp.extras import BY_NAME, MissingExtra

        why = "running seeds on workers (--workers >= 1)"
        raise MissingExtra(BY_NAME["campaign"], "ray", why) from None
    return ray


def check_reachable(address: str, timeout: float = 5.0) -> None:
    """Refuse (`InputError` naming ``--address``) a ``host:port`` / ``ray://host:port`` that
    nothing answers on: Ray itself would retry for minutes. ``auto`` and other forms are
    left to Ray."""
    import socket

    text = address.removeprefix("ray://")
    host, sep, port = text.rpartition(":")
    if not sep or not port.isdigit():
        return
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except OSError as exc:
        raise InputError(
            f"no Ray cluster answers at {address} ({exc})", field="--address"
        ) from None


class RayEngine:
    """Runs jobs as Ray tasks, at most ``workers`` at a time.

    ``address`` (or ``RAY_ADDRESS``): connect to that cluster; otherwise a local Ray with
    ``workers`` CPUs is started here (no dashboard) and shut down afterwards. A Ray already
    initialised in this process (a notebook, a test session) is used as it is. Each task
    asks for one CPU and is never retried (a retry would hide a crash). Keeping only
    ``workers`` tasks in flight means a task starts when it is submitted, so its deadline is
    counted from then (the worker's start-up and imports included).
    """

    name = "ray"

    def __init__(self, address: str | None = None, workers: int | None = None):
        self.ray = import_ray()
        self.requested_address = address or os.environ.get("RAY_ADDRESS") or None
        self.requested_workers = workers
        self.address: str | None = None
        self.workers = 0
        self.init_time = 0.0
        self._started = False

    def __enter__(self) -> RayEngine:
        ray = self.ray
        t0 = time.perf_counter()
        if not ray.is_initialized():
            opts = {"logging_level": logging.WARNING, "log_to_driver": False}
            if self.requested_address:
                check_reachable(self.requested_address)
                ray.init(address=self.requested_address, **opts)
            else:
                ray.init(
                    num_cpus=self.requested_workers or os.cpu_count() or 1,
                    include_dashboard=False,
                    object_store_memory=256 * 1024 * 1024,
                    **opts,
                )
            self._started = True
        self.init_time = time.perf_counter() - t0
        self.address = ray.get_runtime_context().gcs_address
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self.workers = max(1, min(self.requested_workers or cpus, cpus))
        return self

    def __exit__(self, *exc) -> None:
        if self._started:
            self.ray.shutdown()
            self._started = False

    def run(self, jobs: Sequence[Job], time_limit: float, on_done: OnDone) -> None:
        ray = self.ray
        remote = ray.remote(num_cpus=1, max_retries=0)(execute)
        queue = list(reversed(jobs))
        inflight: dict = {}  # ref -> (job, submitted at)
        while queue or inflight:
            while queue and len(inflight) < self.workers:
                job = queue.pop()
                inflight[remote.remote(job)] = (job, time.perf_counter())
            now = time.perf_counter()
            next_deadline = min(t + time_limit for _, t in inflight.values())
            ready, _ = ray.wait(
                list(inflight), num_returns=1, timeout=max(0.0, min(next_deadline - now, 1.0))
            )
            for ref in ready:
                job, t0 = inflight.pop(ref)
                on_done(self._get(ref, job, time.perf_counter() - t0))
            now = time.perf_counter()
            for ref, (job, t0) in list(inflight.items()):
                if now - t0 >= time_limit:
                    ray.cancel(ref, force=True)
                    del inflight[ref]
                    on_done(timed_out(job.seed, time_limit, now - t0))

    def _get(self, ref, job: Job, elapsed: float) -> RunRecord:
        """The task's record, or a crash record when its worker died (or Ray failed it)."""
        try:
            return self.ray.get(ref)
        except Exception as exc:  # WorkerCrashedError, OutOfMemoryError, RayTaskError, ...
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
            return crashed(job.seed, f"{type(exc).__name__}: {first}", elapsed)


def make_engine(engine: str, *, address: str | None = None, workers: int | None = None):
    """``"local"`` (in-process) or ``"ray"`` (local Ray or the cluster at ``address``)."""
    if engine == "local":
        return LocalEngine()
    if engine == "ray":
        return RayEngine(address, workers)
    raise InputError(f"unknown engine {engine!r} (known: local, ray)", field="--engine")
