"""One cached parallel sweep for every family of independent runs (EP maps, muscle function, batches).

Calls run through joblib (loky on this machine, dask.distributed on a cluster); with a cache folder each
result is kept on disk by ``joblib.Memory`` under the hash of its arguments, so an interrupted sweep resumes
and a repeated one computes nothing.  Arguments named in ``ignore`` travel to the worker but are not part of
the key: the caller puts what they depend on (content hashes) into the key arguments.
"""

from __future__ import annotations

import contextlib
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator, Sequence

from .errors import ArticError
from .validation import check_number


@contextlib.contextmanager
def parallel_backend(backend: str, jobs: int, scheduler: str | None) -> Iterator[None]:
    """joblib's backend for a sweep: loky processes here, or a dask.distributed cluster (a local one over
    loopback without ``scheduler``)."""
    from joblib import parallel_config

    check_number("--jobs", jobs, ge=1)
    if backend == "loky":
        if scheduler:
            raise ArticError("--scheduler needs --backend dask")
        with parallel_config(backend="loky", n_jobs=jobs):
            yield
        return
    if backend != "dask":
        raise ArticError(f"unknown --backend '{backend}'; valid: loky, dask")
    with dask_client(jobs, scheduler):
        with parallel_config(backend="dask", n_jobs=-1):
            yield


@contextlib.contextmanager
def dask_client(jobs: int, scheduler: str | None, hint: str = "or use --backend loky") -> Iterator:
    """A dask.distributed client: of the cluster at ``scheduler``, or of a LocalCluster of ``jobs`` worker
    processes (one thread each) over loopback; closed (the local cluster shut down) on the way out."""
    check_number("--jobs", jobs, ge=1)
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - distributed is a dependency
        raise ArticError("dask.distributed is missing; pip install distributed") from None
    cluster = None
    try:
        if scheduler:
            client = Client(scheduler, timeout="10s")
        else:
            # the workers' own log lines (a cancelled task on Ctrl-C, a restarted worker) at ERROR only: what a
            # user needs of them is in the caller's progress, errors and index
            cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, host="127.0.0.1",
                                   dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster)
    except (OSError, TimeoutError) as err:
        raise ArticError(f"cannot reach the dask scheduler at {scheduler}: {type(err).__name__}; start one "
                         f"('dask scheduler') {hint}") from None
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@dataclass(frozen=True)
class Sweep:
    """How to run a sweep: workers, backend, and where finished results are kept (None: not kept)."""

    jobs: int = 1
    backend: str = "loky"
    scheduler: str | None = None
    cache: Path | str | None = None
    progress: Callable[[int, int], None] | None = None


@dataclass
class SweepResult:
    results: list
    cached: int


def _indexed(i: int, fn, args: tuple):
    return i, fn(*args)


def run_sweep(fn: Callable, calls: Sequence[tuple], sweep: Sweep, ignore: Sequence[str] = (),
              phases: Sequence[Sequence[int]] | None = None) -> SweepResult:
    """``[fn(*args) for args in calls]`` in parallel, cached; ``phases`` run one after another (e.g. the rest
    postures before the runs that start from them)."""
    from joblib import Memory, Parallel, delayed

    if sweep.cache is not None:
        fn = Memory(Path(sweep.cache), verbose=0).cache(fn, ignore=list(ignore))
        cached = sum(bool(fn.check_call_in_cache(*a)) for a in calls)
    else:
        cached = 0
    results: list = [None] * len(calls)
    done = 0
    if sweep.progress is not None:
        sweep.progress(0, len(calls))
    with parallel_backend(sweep.backend, sweep.jobs, sweep.scheduler):
        for phase in (phases or [range(len(calls))]):
            gen = Parallel(return_as="generator_unordered")(delayed(_indexed)(i, fn, calls[i]) for i in phase)
            for i, res in gen:
                results[i] = res
                done += 1
                if sweep.progress is not None:
                    sweep.progress(done, len(calls))
    return SweepResult(results, cached)
