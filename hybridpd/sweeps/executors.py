"""Executors of a sweep: in-process, a process pool, or Dask -- never a home-made scheduler.

A sweep's chunks are independent tasks. ``"serial"`` runs them in the calling process;
``"processes"`` hands them to a :class:`concurrent.futures.ProcessPoolExecutor`; ``"dask"`` (or a
``distributed.Client``) to Dask, imported only when asked for (``pip install 'hybridpd[dask]'``);
a scheduler address (``"tcp://host:8786"``) to an existing ``dask.distributed`` cluster, whose
workers must import this package. The executor never changes the results: every chunk result
is placed by its index.

On a cluster each task carries its own chunk of points (nothing is scattered), so a worker
lost mid-run costs only the chunks it was running: the scheduler runs them again elsewhere.

Finished chunks are handed to a callback in the calling thread as they arrive (that is where
they are checked and written), the first failure is re-raised as :class:`ChunkError` after the
chunks still running were collected, and ``timeout`` bounds the wait for the next chunk.
"""

# The broad excepts are deliberate: each re-raises with context or cleans up before
# re-raising (BLE001).
# ruff: noqa: BLE001

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import os
import pickle
import queue
import sys
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["EXECUTORS", "ChunkError", "ExecutorSpec", "SchedulerUnreachable",
           "check_scheduler_address", "compute", "resolve_executor", "scheduler_from_env"]

#: Executor names accepted by :func:`hybridpd.sweeps.sweep.run_sweep` (besides instances).
EXECUTORS = ("serial", "processes", "dask")


#: Schemes of a ``dask.distributed`` scheduler address.
SCHEDULER_SCHEMES = ("tcp://", "tls://", "ws://", "wss://", "inproc://", "ucx://")
#: Environment variable naming the scheduler of an existing cluster (Dask's own name).
SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"


def check_scheduler_address(address: Any) -> str:
    """A scheduler address as Dask takes it (``host:port`` gets ``tcp://``).

    Parameters
    ----------
    address : str
        ``"tcp://10.0.0.5:8786"``, ``"127.0.0.1:8786"``, ...

    Returns
    -------
    str

    Raises
    ------
    ValueError
        Not a string of the form ``[scheme://]host:port`` with a scheme of
        :data:`SCHEDULER_SCHEMES` and an integer port.

    Examples
    --------
    >>> check_scheduler_address("127.0.0.1:8786")
    'tcp://127.0.0.1:8786'
    """
    if not isinstance(address, str) or not address.strip():
        raise ValueError(f"scheduler must be an address such as tcp://host:8786, got {address!r}")
    a = address.strip()
    if "://" not in a:
        a = "tcp://" + a
    scheme = a[: a.index("://") + 3]
    rest = a[len(scheme):]
    if scheme not in SCHEDULER_SCHEMES:
        raise ValueError(f"scheduler address must start with one of {', '.join(SCHEDULER_SCHEMES)}"
                         f", got {address!r}")
    if scheme != "inproc://":
        host, _, port = rest.rpartition(":")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise ValueError(f"scheduler address must be [scheme://]host:port with a port in "
                             f"[1, 65535], got {address!r}")
    return a


def scheduler_from_env(explicit: str | None = None) -> str | None:
    """The scheduler to use: `explicit`, else ``$DASK_SCHEDULER_ADDRESS``, else None."""
    value = explicit if explicit else os.environ.get(SCHEDULER_ENV, "").strip() or None
    return None if value is None else check_scheduler_address(value)


class ChunkError(RuntimeError):
    """A chunk's function call failed in a worker.

    The original exception is chained as ``__cause__`` (for the process pool it
    carries the remote traceback). Chunks finished before the failure are kept
    in the store, so rerunning with ``resume=True`` only computes the rest.

    Attributes
    ----------
    chunk_index : int
        Index of the failed chunk (0-based).
    start, stop : int
        The chunk covers points ``start:stop`` (original point order).
    """

    def __init__(self, chunk_index: int, start: int, stop: int, cause: BaseException):
        self.chunk_index = chunk_index
        self.start = start
        self.stop = stop
        super().__init__(f"sweep chunk {chunk_index} (points {start}:{stop}) failed: "
                         f"{type(cause).__name__}: {cause}")


def _check_positive_int(value: Any, name: str) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    if value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _cpu_count() -> int:
    # sched_getaffinity honours CPU pinning (taskset, some containers);
    # os.cpu_count() counts the whole machine.
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def _slice(cols: Mapping[str, np.ndarray], start: int, stop: int) -> dict[str, np.ndarray]:
    # Copies, so every executor hands func fresh writable arrays (identical
    # behaviour in-process and across process boundaries).
    return {k: v[start:stop].copy() for k, v in cols.items()}

@dataclass(frozen=True)
class ExecutorSpec:
    """A validated executor choice (nothing is started by creating it).

    Attributes
    ----------
    kind : {"serial", "processes", "dask", "executor", "client", "scheduler"}
        ``"executor"`` is a user-supplied :class:`concurrent.futures.Executor`,
        ``"client"`` a user-supplied ``distributed.Client``, ``"scheduler"`` the
        address of an existing cluster (the sweep connects a client and closes it,
        never the cluster).
    instance : object or None
        The user-supplied executor or client (never closed by the sweep), or the
        scheduler address.
    max_workers : int
        Workers of a pool the sweep creates (all usable cores by default);
        1 for ``"serial"``; informational for supplied instances.
    """

    kind: str
    instance: Any = None
    max_workers: int = 1

    @property
    def label(self) -> str:
        """Short description, e.g. ``"processes[4]"``."""
        if self.kind in ("executor", "client"):
            return type(self.instance).__qualname__
        if self.kind == "scheduler":
            return f"dask[{self.instance}]"
        return self.kind if self.kind == "serial" else f"{self.kind}[{self.max_workers}]"


def _is_dask_client(obj: Any) -> bool:
    # If a Client exists, distributed is already imported: no import needed.
    mod = sys.modules.get("distributed")
    return mod is not None and isinstance(obj, getattr(mod, "Client", ()))


def resolve_executor(executor: Any = "processes", max_workers: int | None = None) -> ExecutorSpec:
    """Validate an executor choice for :func:`run_sweep`.

    Parameters
    ----------
    executor : {"processes", "serial", "dask"}, scheduler address, Executor or distributed.Client
        ``"processes"`` (default; ``None`` means the same): a
        ``ProcessPoolExecutor`` created and closed by the sweep.
        ``"serial"``: in the calling process, no pickling. ``"dask"``: the
        cluster of ``$DASK_SCHEDULER_ADDRESS`` if set, else a
        ``distributed.LocalCluster`` (processes, one thread each) created and
        closed by the sweep. A scheduler address (``"tcp://host:8786"``): an
        existing cluster. An ``Executor`` or ``Client`` instance is used
        as is and left open.
    max_workers : int, optional
        Worker count for pools the sweep creates; default: all usable cores.
        Ignored for ``"serial"`` and supplied instances. Never affects results.

    Returns
    -------
    ExecutorSpec

    Raises
    ------
    ValueError
        Unknown executor name or type, or non-positive `max_workers`.
    ImportError
        ``"dask"`` without the optional ``distributed`` package.

    Examples
    --------
    >>> resolve_executor("processes", 2).label
    'processes[2]'
    >>> resolve_executor("threads")
    Traceback (most recent call last):
    ...
    ValueError: executor must be one of 'serial', 'processes', 'dask', a scheduler address, a concurrent.futures.Executor or a distributed.Client; got 'threads'
    """
    workers = (_cpu_count() if max_workers is None
               else _check_positive_int(max_workers, "max_workers"))
    if executor is None:
        executor = "processes"
    if isinstance(executor, str):
        if executor == "serial":
            return ExecutorSpec("serial", None, 1)
        if executor == "processes":
            return ExecutorSpec("processes", None, workers)
        scheduler = None
        if "://" in executor:
            scheduler = check_scheduler_address(executor)
        elif executor == "dask":
            scheduler = scheduler_from_env()
        if executor == "dask" or scheduler is not None:
            import importlib.util

            if importlib.util.find_spec("distributed") is None:
                raise ImportError("executor='dask' needs the optional dependency: pip install "
                                  "'hybridpd[dask]'")
            if scheduler is not None:
                return ExecutorSpec("scheduler", scheduler, workers)
            return ExecutorSpec("dask", None, workers)
    elif isinstance(executor, cf.Executor):
        return ExecutorSpec("executor", executor, getattr(executor, "_max_workers", workers))
    elif _is_dask_client(executor):
        return ExecutorSpec("client", executor, workers)
    raise ValueError("executor must be one of 'serial', 'processes', 'dask', a scheduler address, "
                     f"a concurrent.futures.Executor or a distributed.Client; got {executor!r}")


def _run_chunk(func: Callable, chunk: dict[str, np.ndarray],
               kwargs: Mapping[str, Any]) -> tuple[dict, float]:
    """Worker side: call func on one chunk; return (outputs, seconds)."""
    t0 = time.perf_counter()
    out = func(chunk, **kwargs)
    dt = time.perf_counter() - t0
    if isinstance(out, Mapping):
        # Plain arrays pickle compactly; validation happens in the caller,
        # where the chunk index can be reported.
        out = {k: np.asarray(v) for k, v in out.items()}
    return out, dt


def _run_chunk_slice(func: Callable, cols: Mapping[str, np.ndarray], start: int, stop: int,
                     kwargs: Mapping[str, Any]):
    """Dask worker side: the full points are scattered once; slice here."""
    return _run_chunk(func, _slice(cols, start, stop), kwargs)


def _terminate_process_pool(pool: cf.ProcessPoolExecutor) -> None:
    """Stop a pool we own now, including chunks still running.

    ``shutdown(cancel_futures=True)`` only drops queued work; a running chunk
    would keep the interpreter alive until it finishes (exit joins the
    workers). On timeout or Ctrl-C we terminate the workers instead.
    """
    terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
    if terminate is not None:
        with contextlib.suppress(Exception):
            terminate()
        return
    procs = list(
        (getattr(pool, "_processes", None) or {}).values()
    )  # read before shutdown clears it
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        with contextlib.suppress(Exception):
            p.terminate()
    for p in procs:
        with contextlib.suppress(Exception):
            p.join(timeout=5)


class _PoolBackend:
    """A concurrent.futures executor: chunks are sliced here and pickled."""

    def __init__(self, executor: cf.Executor, owned: bool, func: Callable, cols: dict,
                 kwargs: dict):
        self.executor, self.owned = executor, owned
        self.func, self.cols, self.kwargs = func, cols, kwargs

    def submit(self, tasks: Sequence[tuple[int, int, int]]) -> list[cf.Future]:
        """Submit chunks ``(index, start, stop)``; one future per chunk."""
        return [self.executor.submit(_run_chunk, self.func, _slice(self.cols, start, stop),
                                     self.kwargs) for _, start, stop in tasks]

    def cancel(self, futures) -> set:
        # Queued chunks are dropped; running ones cannot be, so they are
        # returned for the caller to collect (and save) before re-raising.
        return {f for f in futures if not f.cancel()}

    def close(self, abort: bool, futures=()) -> None:
        for f in futures:
            f.cancel()
        if self.owned:
            if abort and isinstance(self.executor, cf.ProcessPoolExecutor):
                _terminate_process_pool(self.executor)
            else:
                self.executor.shutdown(wait=not abort, cancel_futures=True)


class _DaskBackend:
    """A distributed.Client: points are scattered once, workers slice them."""

    def __init__(self, client: Any, owned_cluster: Any, func: Callable, cols: dict, kwargs: dict):
        self.client, self.cluster = client, owned_cluster
        self.func, self.kwargs = func, kwargs
        self.token = uuid.uuid4().hex[:12]  # unique task keys per run on a shared client
        self.cols_future = client.scatter([cols], hash=False)[0]

    def submit(self, tasks: Sequence[tuple[int, int, int]]) -> list:
        """Submit chunks ``(index, start, stop)``; one future per chunk."""
        if not tasks:
            return []
        index, start, stop = (list(t) for t in zip(*tasks))
        # One client.map call instead of a submit per chunk: a single message
        # to the scheduler, which matters with thousands of chunks.
        n = len(tasks)
        return self.client.map(_run_chunk_slice, [self.func] * n, [self.cols_future] * n, start,
                               stop, [self.kwargs] * n,
                               key=[f"hybridpd-sweep-{self.token}-{i}" for i in index],
                               pure=False, retries=0)

    def cancel(self, futures) -> set:
        futures = list(futures)
        if futures:
            with contextlib.suppress(Exception):
                self.client.cancel(futures)
        return set()  # dask cancels running tasks too: nothing left to collect

    def close(self, abort: bool, futures=()) -> None:
        if abort:
            self.cancel(futures)
        with contextlib.suppress(Exception):
            self.client.cancel([self.cols_future])
        if self.cluster is not None:  # we created both: close both
            with contextlib.suppress(Exception):
                self.client.close()
            with contextlib.suppress(Exception):
                self.cluster.close()


class _ClusterBackend(_DaskBackend):
    """An existing cluster: a client of our own, each task carries its chunk of points.

    Nothing is scattered, so no task depends on data held by one worker: when a worker is
    lost, the scheduler reruns its chunks on the others from the task alone.
    """

    def __init__(self, client: Any, func: Callable, cols: dict, kwargs: dict):
        self.client, self.cluster = client, None
        self.func, self.kwargs, self.cols = func, kwargs, cols
        self.token = uuid.uuid4().hex[:12]

    def submit(self, tasks: Sequence[tuple[int, int, int]]) -> list:
        if not tasks:
            return []
        n = len(tasks)
        return self.client.map(_run_chunk, [self.func] * n,
                               [_slice(self.cols, start, stop) for _, start, stop in tasks],
                               [self.kwargs] * n,
                               key=[f"hybridpd-sweep-{self.token}-{i}" for i, _, _ in tasks],
                               pure=False, retries=0)

    def close(self, abort: bool, futures=()) -> None:
        if abort:
            self.cancel(futures)
        with contextlib.suppress(Exception):
            self.client.close()


class SchedulerUnreachable(ConnectionError, ValueError):
    """No Dask scheduler answers at the address given (a ValueError too: the command line
    reports it in one line, like any unusable argument)."""


def _connect(address: str):
    from distributed import Client

    try:
        return Client(address, timeout="20s", set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise SchedulerUnreachable(
            f"scheduler: no Dask scheduler answers at {address} ({type(exc).__name__}); "
            "start one with 'dask scheduler' and workers with 'dask worker ADDRESS'") from None


def _open_backend(spec: ExecutorSpec, n_tasks: int, func: Callable, cols: dict, kwargs: dict):
    # Never start more workers than there are chunks left (saves start-up
    # time on short or mostly-resumed sweeps; results are unaffected).
    n = max(1, min(spec.max_workers, n_tasks))
    if spec.kind == "processes":
        return _PoolBackend(cf.ProcessPoolExecutor(max_workers=n), True, func, cols, kwargs)
    if spec.kind == "executor":
        return _PoolBackend(spec.instance, False, func, cols, kwargs)
    if spec.kind == "client":
        return _DaskBackend(spec.instance, None, func, cols, kwargs)
    if spec.kind == "scheduler":
        client = _connect(spec.instance)
        try:
            return _ClusterBackend(client, func, cols, kwargs)
        except BaseException:
            client.close()
            raise
    if spec.kind == "dask":
        try:
            from distributed import Client, LocalCluster
        except ImportError as exc:  # pragma: no cover - checked by resolve_executor
            raise ImportError("executor='dask' needs the optional dependency: pip install "
                              "'hybridpd[dask]'") from exc
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               dashboard_address=":0")
        try:
            client = Client(cluster)
        except BaseException:
            cluster.close()
            raise
        try:
            return _DaskBackend(client, cluster, func, cols, kwargs)
        except BaseException:
            client.close()
            cluster.close()
            raise
    raise AssertionError(spec.kind)  # pragma: no cover


def _check_picklable(func: Callable, kwargs: Mapping[str, Any]) -> None:
    try:
        pickle.dumps(func)
    except Exception as exc:
        raise ValueError(f"func {getattr(func, '__qualname__', func)!r} cannot be pickled for a "
                         f"process pool ({exc}); define it at module level (not a lambda or "
                         "nested function) or use executor='serial'") from None
    try:
        pickle.dumps(dict(kwargs))
    except Exception as exc:
        raise ValueError(f"func_kwargs cannot be pickled for a process pool ({exc})") from None


def _compute_serial(func, cols, kwargs, bounds, pending, on_result) -> None:
    for i in pending:
        start, stop = bounds(i)
        try:
            out, dt = _run_chunk(func, _slice(cols, start, stop), kwargs)
        except Exception as exc:
            raise ChunkError(i, start, stop, exc) from exc
        on_result(i, out, dt)


def _compute_futures(backend, bounds, pending, on_result, timeout) -> None:
    # Completion order is collected through done-callbacks into a queue rather
    # than with as_completed(): as_completed's timeout bounds the *whole*
    # sweep, while here `timeout` bounds the wait for the *next* chunk, which
    # with busy workers is at most the longest chunk's run time. Scheduling
    # itself stays entirely with the executor.
    done: queue.SimpleQueue = queue.SimpleQueue()
    index_of: dict[Any, int] = {}
    failed = True
    try:
        futures = backend.submit([(i, *bounds(i)) for i in pending])
        for i, f in zip(pending, futures):
            index_of[f] = i
        for f in futures:
            f.add_done_callback(done.put)
        first_error: ChunkError | None = None
        while index_of:
            try:
                f = done.get(timeout=timeout)
            except queue.Empty:
                if first_error is not None:
                    break  # draining after a failure: report the failure itself
                left = sorted(index_of.values())
                more = f" (+{len(left) - 10} more)" if len(left) > 10 else ""
                raise TimeoutError(f"no sweep chunk finished within timeout={timeout} s; pending "
                                   f"chunks {left[:10]}{more}. Finished chunks are saved; "
                                   "increase timeout or use smaller chunks") from None
            i = index_of.pop(f, None)
            if i is None or f.cancelled():
                continue
            try:
                out, dt = f.result()
            except Exception as exc:
                if first_error is None:
                    first_error = ChunkError(i, *bounds(i), exc)
                    first_error.__cause__ = exc
                    # Drop queued chunks; keep collecting the running ones so
                    # their results are saved before the error propagates.
                    keep = backend.cancel(list(index_of))
                    index_of = {g: j for g, j in index_of.items() if g in keep}
                continue
            on_result(i, out, dt)
        if first_error is not None:
            raise first_error
        failed = False
    finally:
        backend.close(abort=failed, futures=list(index_of))


def compute(spec: ExecutorSpec, func: Callable, cols: dict, kwargs: dict, pending: Sequence[int],
            bounds: Callable[[int], tuple[int, int]], on_result: Callable,
            timeout: float | None) -> None:
    """Run chunks `pending` (points ``bounds(i)``) on `spec`; ``on_result(i, out, seconds)``.

    `on_result` is called in the calling thread, once per finished chunk, in completion order.
    Raises :class:`ChunkError` for the first failing chunk (after collecting the chunks still
    running) and ``TimeoutError`` when no chunk finishes within `timeout` seconds.
    """
    if not pending:
        return
    if spec.kind == "serial":
        _compute_serial(func, cols, kwargs, bounds, pending, on_result)
    else:
        backend = _open_backend(spec, len(pending), func, cols, kwargs)
        _compute_futures(backend, bounds, pending, on_result, timeout)
