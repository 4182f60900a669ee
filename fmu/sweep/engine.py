"""Where a sweep's runs execute: in this process, on a dask LocalCluster, or on any dask.distributed cluster.

The runs go out in chunks (`chunk_size_for`); every chunk is one dask task that takes
the FMU archive as a dependency, so the bytes reach each worker through dask's own
transfers (no shared file system) and the archive task is recomputed if the worker
holding it dies. A task lost with its worker is recomputed by dask; a chunk that still
fails (dask gives up on it) becomes rows with ok = False and the reason. The progress
bar (fmu.terminal.progress) shows runs done, runs per second and failures.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import queue
import threading
import time
import uuid
from collections.abc import Iterator, Sequence
from typing import Any

from modelsrc.errors import ModelInputError

from ..terminal.progress import progress_bar
from .worker import Job, Run, release_instances, run_chunk

# Chunks per worker thread: enough that the last chunks balance the load and a lost
# worker costs little, few enough that dask's ~1 ms per task stays small against a chunk.
CHUNKS_PER_WORKER = 8
MAX_CHUNK = 256
WORKER_CHECK_S = 2.0  # how often a waiting client checks that the cluster still has workers
NO_WORKERS_TIMEOUT_S = 120.0  # a cluster left without workers this long ends the sweep (no hang)
# Connecting to a scheduler, its handshake included (s): distributed's own connect timeout
# bounds only the TCP connection, so a peer that accepts and says nothing would hang
# Client() forever (`scheduler_handshake` bounds the whole exchange).
CONNECT_TIMEOUT_S = 20.0
# Worker processes of a LocalCluster per core at most: more only compete for the cores
# (each is a Python process of ~100 MB), and a typo such as --workers 1000000 would
# exhaust the memory before any worker starts (docs/user_guide.md §3.1).
MAX_WORKERS_PER_CORE = 4
# Where a LocalCluster listens: loopback only, so that neither its scheduler nor its
# dashboard (which shows the tasks and lets anyone see the cluster) is reachable from
# other machines; `--dashboard ADDR` chooses another address for the dashboard.
LOCAL_HOST = "127.0.0.1"
DEFAULT_DASHBOARD = f"{LOCAL_HOST}:0"  # port 0: a free one (several clusters may run on one machine)


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C (SIGINT) during a sweep's runs: `rows` holds the rows of the chunks completed
    before it, `table` (set by fmu.sweep.api.sweep) their table, so that a caller can keep
    them; a KeyboardInterrupt still, for callers that do not."""

    def __init__(self, rows: list[dict[str, Any]]):
        super().__init__(f"sweep interrupted after {len(rows)} completed runs")
        self.rows = rows
        self.table: Any = None


def chunk_size_for(n_runs: int, n_workers: int) -> int:
    """Runs per chunk for n_runs over n_workers worker threads (CHUNKS_PER_WORKER each)."""
    return max(1, min(MAX_CHUNK, math.ceil(n_runs / (CHUNKS_PER_WORKER * max(1, n_workers)))))


def split(runs: Sequence[Run], size: int) -> list[list[Run]]:
    """Consecutive chunks of `size` runs (the last one shorter)."""
    if size < 1:
        raise ModelInputError(f"chunk size must be >= 1, got {size}")
    return [list(runs[i : i + size]) for i in range(0, len(runs), size)]


def local_cores() -> int:
    """The cores this process may run on (one LocalCluster worker process each)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def max_workers() -> int:
    """The most LocalCluster worker processes a sweep starts: MAX_WORKERS_PER_CORE per core."""
    return MAX_WORKERS_PER_CORE * local_cores()


def check_workers(workers: int | None) -> None:
    """ModelInputError unless `workers` is None (one per core), 0 (this process) or a
    whole number up to max_workers()."""
    if workers is None:
        return
    if isinstance(workers, bool) or int(workers) != workers or workers < 0:
        raise ModelInputError(f"--workers must be >= 0, a whole number (0: run in this process), got {workers}")
    if workers > max_workers():
        raise ModelInputError(
            f"--workers {workers}: at most {max_workers()} worker processes ({MAX_WORKERS_PER_CORE} per core, "
            f"{local_cores()} cores here); more only compete for the cores (use --scheduler for a larger cluster)"
        )


def check_dashboard(address: str) -> str:
    """`address` as HOST:PORT (PORT 0: a free one), else a ModelInputError."""
    host, sep, port = address.rpartition(":")
    if not sep or not host.strip() or not port.isdigit() or int(port) > 65535:
        raise ModelInputError(
            f"--dashboard {address!r}: give HOST:PORT, e.g. {LOCAL_HOST}:8787 (PORT 0: a free port; the default "
            f"{DEFAULT_DASHBOARD} listens on this machine only)"
        )
    return address


def scheduler_handshake(scheduler: str, timeout_s: float) -> None:
    """Connect to the dask scheduler at `scheduler` and exchange distributed's handshake
    within timeout_s (s), else a ModelInputError saying what failed: no such address,
    nobody listening, or a peer that accepted but did not answer as a scheduler does
    (it sends its handshake on accepting: distributed.comm.core.Listener.on_connection)."""
    import asyncio

    from distributed.comm import connect

    async def probe() -> None:
        comm = await asyncio.wait_for(connect(scheduler, timeout=timeout_s), timeout_s)
        await comm.close()

    outcome: list[BaseException | None] = []

    def attempt() -> None:  # in its own thread: the caller may already run an event loop
        try:
            asyncio.run(probe())
            outcome.append(None)
        except BaseException as exc:  # reported to the caller below
            outcome.append(exc)

    thread = threading.Thread(target=attempt, name="rbfmu-scheduler-probe", daemon=True)
    thread.start()
    thread.join(timeout_s + 5.0)  # wait_for ends the probe at timeout_s; the margin is for the loop's exit
    exc = outcome[0] if outcome else TimeoutError()
    if exc is None:
        return
    if isinstance(exc, (TimeoutError, asyncio.TimeoutError)):
        why = (
            f"no dask handshake within {timeout_s:g} s (something accepted the connection but did not answer "
            "as a dask scheduler does)"
        )
    elif isinstance(exc, ValueError):
        why = f"not a dask address ({exc}); give e.g. tcp://host:8786"
    else:
        why = f"{type(exc).__name__}: {exc}"
    raise ModelInputError(f"--scheduler {scheduler}: cannot connect to a dask scheduler there: {why}")


@contextlib.contextmanager
def cluster_client(
    scheduler: str | None = None, workers: int | None = None, dashboard: str | None = None
) -> Iterator[Any]:
    """A dask Client: of the scheduler at `scheduler` (e.g. tcp://host:8786; its handshake
    bounded by CONNECT_TIMEOUT_S), else of a LocalCluster of `workers` single-threaded
    processes (default: one per core, at most max_workers()) listening on 127.0.0.1 only,
    its dashboard at `dashboard` (HOST:PORT; default 127.0.0.1 on a free port). Closed
    (and the LocalCluster shut down) on exit."""
    from distributed import Client, LocalCluster

    if scheduler:
        if dashboard is not None:
            raise ModelInputError(
                "--dashboard sets the dashboard of a local cluster; a cluster at --scheduler has its own "
                "(docs/user_guide.md §3.1 says how to reach it safely)"
            )
        scheduler_handshake(scheduler, CONNECT_TIMEOUT_S)
        try:
            client = Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s")
        except (OSError, ValueError, TypeError) as exc:
            raise ModelInputError(
                f"--scheduler {scheduler}: cannot connect to a dask scheduler there ({exc})"
            ) from None
        try:
            yield client
        finally:
            client.close()
        return
    check_workers(workers)
    n = local_cores() if workers is None else workers
    if n < 1:
        raise ModelInputError(f"--workers must be >= 1 for a cluster (0 runs in this process), got {n}")
    cluster = LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        host=LOCAL_HOST,
        dashboard_address=check_dashboard(dashboard) if dashboard is not None else DEFAULT_DASHBOARD,
        silence_logs=logging.ERROR,
    )
    client = Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()


def worker_threads(client: Any) -> int:
    """Worker threads of the cluster (after waiting up to a minute for the first worker)."""
    try:
        client.wait_for_workers(1, timeout=60)
    except TimeoutError:
        raise ModelInputError(f"no dask worker joined the scheduler {client.scheduler.address} within 60 s") from None
    return max(1, sum(client.nthreads().values()))


def _failed_rows(chunk: Sequence[Run], job: Job, reason: str) -> list[dict[str, Any]]:
    return [{"run": n, **dict(zip(job.columns, vals)), "ok": False, "error": reason} for n, vals in chunk]


class _Progress:
    """The bar of a sweep: runs done, runs per second (tqdm's rate), failures."""

    def __init__(self, total: int, show: bool):
        self.bar = progress_bar(total, desc="sweep", unit="run") if show else None
        self.failed = 0

    def add(self, rows: Sequence[dict[str, Any]]) -> None:
        self.failed += sum(1 for r in rows if not r["ok"])
        if self.bar is not None:
            self.bar.set_postfix_str(f"failed={self.failed}")
            self.bar.update(len(rows))

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run_here(
    fmu_bytes: bytes, job: Job, chunks: Sequence[Sequence[Run]], progress: bool = True
) -> list[dict[str, Any]]:
    """Every chunk in this process, one after the other, on one reused instance."""
    bar = _Progress(sum(len(c) for c in chunks), progress)
    rows: list[dict[str, Any]] = []
    try:
        for chunk in chunks:
            done = run_chunk(fmu_bytes, job, chunk)
            bar.add(done)
            rows += done
    except KeyboardInterrupt:
        raise SweepInterrupted(rows) from None
    finally:
        bar.close()
        release_instances()
    return rows


def _archive(fmu_bytes: bytes) -> bytes:
    """The dask task that holds the archive on a worker (recomputable, unlike scattered data)."""
    return fmu_bytes


def run_on_cluster(
    client: Any, fmu_bytes: bytes, job: Job, chunks: Sequence[Sequence[Run]], progress: bool = True
) -> list[dict[str, Any]]:
    """Every chunk as a dask task on `client`'s cluster; rows as they come back."""
    from distributed import Future

    archive = client.submit(_archive, fmu_bytes, key=f"rbfmu-fmu-{job.fmu_key}", pure=True)
    token = uuid.uuid4().hex[:12]
    futures: dict[Future, Sequence[Run]] = {
        client.submit(run_chunk, archive, job, list(chunk), key=f"rbfmu-chunk-{token}-{i}", pure=False): chunk
        for i, chunk in enumerate(chunks)
    }
    bar = _Progress(sum(len(c) for c in chunks), progress)
    rows: list[dict[str, Any]] = []
    pending = set(futures)
    last_worker_seen = time.monotonic()
    # woken by each chunk as it finishes (its future's callback), not by a polling period:
    # a poll of 50 ms cost up to 50 ms at the end of every sweep, 10 % of a 0.5 s sweep on
    # two workers. A callback, not distributed.wait: that waits on the default client's
    # event loop, another client's when the caller holds several.
    finished: queue.Queue[Future] = queue.Queue()
    for f in futures:
        f.add_done_callback(finished.put)
    try:
        while pending:
            done = []
            with contextlib.suppress(queue.Empty):
                done.append(finished.get(timeout=WORKER_CHECK_S))
                while True:
                    done.append(finished.get_nowait())
            if not done:
                now = time.monotonic()  # a cluster without workers would wait forever
                if client.nthreads():
                    last_worker_seen = now
                elif now - last_worker_seen > NO_WORKERS_TIMEOUT_S:
                    for f in pending:
                        rows += _failed_rows(futures[f], job, "no dask worker left on the cluster")
                    break
                continue
            for f in done:
                if f not in pending:  # a second report of a chunk already taken is ignored
                    continue
                pending.discard(f)
                if f.status == "finished":
                    got = f.result()
                else:  # dask gave up on it (e.g. its workers kept dying), or it was cancelled
                    try:
                        exc = f.exception()
                    except Exception as cancelled:  # a cancelled future has no exception to give
                        exc = cancelled
                    got = _failed_rows(futures[f], job, f"chunk failed on the cluster: {type(exc).__name__}: {exc}")
                f.release()
                bar.add(got)
                rows += got
    except KeyboardInterrupt:
        raise SweepInterrupted(rows) from None
    finally:
        bar.close()
        for f in pending:
            f.cancel()
        archive.release()
    return rows
