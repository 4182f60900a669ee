"""Where a sweep's runs execute: in this process, on a dask LocalCluster, or on any dask.distributed cluster.

The runs go out in chunks (`chunk_size_for`); every chunk is one dask task that takes
the FMU archive as a dependency, so the bytes reach each worker through dask's own
transfers (no shared file system) and the archive task is recomputed if the worker
holding it dies. A task lost with its worker is recomputed by dask; a chunk that still
fails (dask gives up on it) becomes rows with ok = False and the reason. The progress
bar (fmu.progress) shows runs done, runs per second and failures.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import queue
import time
import uuid
from collections.abc import Iterator, Sequence
from typing import Any

from modelsrc.errors import ModelInputError

from ..progress import progress_bar
from .worker import Job, Run, release_instances, run_chunk

# Chunks per worker thread: enough that the last chunks balance the load and a lost
# worker costs little, few enough that dask's ~1 ms per task stays small against a chunk.
CHUNKS_PER_WORKER = 8
MAX_CHUNK = 256
WORKER_CHECK_S = 2.0  # how often a waiting client checks that the cluster still has workers
NO_WORKERS_TIMEOUT_S = 120.0  # a cluster left without workers this long ends the sweep (no hang)
CONNECT_TIMEOUT = "20s"


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


@contextlib.contextmanager
def cluster_client(scheduler: str | None = None, workers: int | None = None) -> Iterator[Any]:
    """A dask Client: of the scheduler at `scheduler` (e.g. tcp://host:8786), else of a
    LocalCluster of `workers` single-threaded processes (default: one per core). Closed
    (and the LocalCluster shut down) on exit."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, ValueError, TypeError) as exc:
            raise ModelInputError(
                f"--scheduler {scheduler}: cannot connect to a dask scheduler there ({exc})"
            ) from None
        try:
            yield client
        finally:
            client.close()
        return
    n = local_cores() if workers is None else workers
    if n < 1:
        raise ModelInputError(f"--workers must be >= 1 for a cluster (0 runs in this process), got {n}")
    # dashboard on a free port: several clusters (and other users') may run on one machine
    cluster = LocalCluster(
        n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.ERROR
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
    finally:
        bar.close()
        for f in pending:
            f.cancel()
        archive.release()
    return rows
