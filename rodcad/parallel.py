"""Worker processes for CAD-heavy work.

The OCCT kernel is not safe to ``fork`` once it has been used (a lock held by
one of its threads in the parent stays locked in the child), so workers come
from a *forkserver* that has imported the CAD modules (:mod:`rodcad.cad`) but never built
anything; where forkserver is missing, they are spawned.

A net's parts are tasks for Dask (:func:`task_runner`): on an existing scheduler (a cluster),
or on a ``distributed.LocalCluster`` (:func:`local_cluster`) whose worker processes come from
the same forkserver (never forked from this process), so that they start with the CAD kernel
imported instead of importing it each (spawned, each importing the same rodcad as this one,
where forkserver is missing).
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Protocol

__all__ = ["JOBS_ENV", "PARTS_PER_WORKER", "WORKER_PRELOAD", "KeptWorkers", "KeyValueStore", "cached_map",
           "default_jobs", "in_process", "kept", "kept_workers", "local_cluster", "start_workers", "task_runner",
           "worker_pool"]

#: A build starts a local Dask cluster by default where it has at least this many tasks per
#: worker (a distinct net part: 0.5-2 s of kernel work each), a worker per CPU it may use up to
#: one per that many tasks; fewer run in this process, where the cluster's start (2-4 s on 2
#: cores: the forkserver's import of the CAD kernel, each worker's of distributed) would cost
#: more than the parallel work saves. Measured on 2 cores, whole builds on 2 workers against
#: --jobs 1: the lampshade's 7 parts 12.6 against 14.3 s, the collar's 10 9.2 against 13.0 s.
PARTS_PER_WORKER = 3


#: The environment variable that caps the worker processes a run starts where it is not told
#: (``--jobs``): a shared machine's or a batch job's share of its CPUs. 1 runs everything in
#: the one process (no worker pool, no local Dask cluster).
JOBS_ENV = "RODCAD_JOBS"


def default_jobs() -> int:
    """Number of CPUs this process may use: those it may run on, at most :data:`JOBS_ENV`
    where that is set.

    Raises:
        InputError: :data:`JOBS_ENV` is set but is not a whole number of 1 or more.
    """
    try:
        cpus = max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        cpus = max(1, os.cpu_count() or 1)
    cap = os.environ.get(JOBS_ENV, "").strip()
    if not cap:
        return cpus
    if not cap.isdigit() or int(cap) < 1:
        from rodcad.errors import InputError, Problem

        raise InputError([Problem(JOBS_ENV, 0, 0, JOBS_ENV,
                                  f"the environment variable {JOBS_ENV}={cap!r} must be a whole number of 1 or "
                                  "more (the worker processes a run may start)")])
    return min(cpus, int(cap))


#: What the forkserver imports before it forks any worker: the CAD kernel and the modules
#: whose functions the workers run (the tables of reachable masses, the rods' solids, a net's
#: parts on a local Dask cluster).
WORKER_PRELOAD = ("rodcad.cad.solids", "rodcad.cad.collision", "rodcad.cad.export",
                  "rodcad.fabrication.intervals", "rodcad.cad.rods", "rodcad.cad.net.build")


def _context() -> multiprocessing.context.BaseContext:
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(list(WORKER_PRELOAD))
        return ctx
    return multiprocessing.get_context("spawn")  # pragma: no cover - Windows / macOS default


def worker_pool(jobs: int) -> ProcessPoolExecutor:
    """A process pool of ``jobs`` workers that may use the CAD kernel."""
    return ProcessPoolExecutor(max_workers=jobs, mp_context=_context())


def start_workers() -> None:
    """Start the forkserver the workers of :func:`worker_pool` come from now, so that its
    imports (:data:`WORKER_PRELOAD`: the CAD kernel, a few seconds) run beside the caller's
    own instead of when the first pool is made (no-op where it runs already or where workers
    are spawned)."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        from multiprocessing import forkserver

        _context()
        forkserver.ensure_running()


class KeptWorkers:
    """Worker processes kept from one step to the next (:func:`kept_workers`): a task with a
    home (a rod type's name) runs in the worker that ran that home's tasks before, so that what
    the worker keeps in memory (the type's solid, its cavity pools and dart throws) serves it
    again. A task whose home has no worker yet goes to the first idle one."""

    def __init__(self, jobs: int) -> None:
        self.jobs = jobs
        self._pools: list[ProcessPoolExecutor | None] = [None] * jobs
        self._home: dict[str, int] = {}

    def _pool(self, w: int) -> ProcessPoolExecutor:
        pool = self._pools[w]
        if pool is None:
            pool = self._pools[w] = worker_pool(1)
        return pool

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any], homes: Sequence[str]) -> Iterator[Any]:
        """``fn(item)`` for every item, each in its home's worker; results in item order."""
        from concurrent.futures import FIRST_COMPLETED, wait

        results: dict[int, Any] = {}
        queue = list(range(len(items)))
        running: dict[Any, tuple[int, int]] = {}  # future -> (item, worker)
        nxt = 0
        while queue or running:
            busy = {w for _, w in running.values()}
            for w in range(self.jobs):
                if w in busy:
                    continue
                pick = next((i for i in queue if self._home.get(homes[i]) == w), None)
                if pick is None:
                    pick = next((i for i in queue if homes[i] not in self._home), None)
                if pick is None:
                    continue
                queue.remove(pick)
                self._home[homes[pick]] = w
                running[self._pool(w).submit(fn, items[pick])] = (pick, w)
            finished, _ = wait(list(running), return_when=FIRST_COMPLETED)
            for fut in finished:
                i, _ = running.pop(fut)
                results[i] = fut.result()
            while nxt in results:
                yield results.pop(nxt)
                nxt += 1

    def shutdown(self) -> None:
        for pool in self._pools:
            if pool is not None:
                pool.shutdown(cancel_futures=True)
        self._pools = [None] * self.jobs


#: The workers :func:`kept_workers` keeps, while it does.
_KEPT: list[KeptWorkers] = []


@contextmanager
def kept_workers(jobs: int | None = None) -> Iterator[KeptWorkers | None]:
    """Within this context, :func:`cached_map` calls given ``homes`` and the rods'
    fabrication (:func:`rodcad.cad.rods.fabricate_chain`) run their tasks in the same ``jobs``
    worker processes (none with one), each rod type's in the worker that
    computed its table of reachable masses. By default one worker more than the CPUs: a few
    tasks of unequal length (a chain's rod types) then end together, the CPUs shared among them.
    Nested contexts share the outer one's workers."""
    if _KEPT:
        yield _KEPT[-1]
        return
    n = jobs or (default_jobs() + 1 if default_jobs() > 1 else 1)
    if n <= 1:
        yield None
        return
    workers = KeptWorkers(n)
    _KEPT.append(workers)
    try:
        yield workers
    finally:
        _KEPT.remove(workers)
        workers.shutdown()


def kept() -> KeptWorkers | None:
    """The workers of the innermost :func:`kept_workers`, or None outside one."""
    return _KEPT[-1] if _KEPT else None


class KeyValueStore(Protocol):
    """What :func:`cached_map` needs of a cache (:class:`rodcad.catalog.cache.DiskCache`)."""

    def get(self, kind: str, key: str) -> Any: ...

    def put(self, kind: str, key: str, value: Any) -> None: ...


def cached_map(fn: Callable[[Any], Any], items: Sequence[Any], keys: Sequence[str], *, kind: str,
               cache: KeyValueStore, jobs: int | None = None, progress: Callable[[int, int], None] | None = None,
               usable: Callable[[Any], bool] = lambda value: value is not None,
               computed: set[str] | None = None, homes: Sequence[str] | None = None) -> list[Any]:
    """``fn(item)`` for every item, from the cache where it has a usable value.

    Items without one are computed once per distinct key, in ``jobs`` worker
    processes (default: the CPUs; in this process when one is enough), stored under
    ``(kind, key)`` as they arrive, and reported as ``progress(done, total)``.

    Args:
        fn: a top-level function (worker processes pickle it) of one item; its result
            must be JSON-serialisable for the disk cache.
        items: the work.
        keys: one cache key per item; equal keys mean equal results.
        kind: the cache's namespace.
        cache: where results are kept.
        jobs: worker processes.
        progress: called after each computed item.
        usable: whether a cached value can be used (an older format is recomputed).
        computed: if given, the keys computed (not read from the cache) are added to it.
        homes: one per item: where it runs within :func:`kept_workers` (items of one home
            in the same worker); without, or outside one, in a pool of its own.

    Returns:
        The results in item order.
    """
    if len(keys) != len(items):
        raise ValueError(f"{len(keys)} keys for {len(items)} items")
    found: dict[str, Any] = {}
    todo: dict[str, Any] = {}
    home: dict[str, str] = {}
    for n, (item, key) in enumerate(zip(items, keys)):
        if key in found or key in todo:
            continue
        hit = cache.get(kind, key)
        if usable(hit):
            found[key] = hit
        else:
            todo[key] = item
            home[key] = homes[n] if homes is not None else key
    work = list(todo.items())
    workers = kept() if homes is not None else None  # (their number is the default there)
    jobs = max(1, min(jobs or (workers.jobs if workers is not None else default_jobs()), len(work))) if work else 1
    workers = workers if jobs > 1 else None
    pool = worker_pool(jobs) if jobs > 1 and workers is None else None
    try:
        if workers is not None:
            results: Any = workers.map(fn, [item for _, item in work], [home[key] for key, _ in work])
        else:
            results = (pool.map(fn, [item for _, item in work], chunksize=1) if pool is not None
                       else map(fn, [item for _, item in work]))
        for i, ((key, _), value) in enumerate(zip(work, results)):
            cache.put(kind, key, value)
            found[key] = value
            if computed is not None:
                computed.add(key)
            if progress:
                progress(i + 1, len(work))
    finally:
        if pool is not None:
            pool.shutdown()
    return [found[key] for key in keys]


#: ``runner(fn, items, progress=None) -> results`` in item order; ``progress(done, total)``
#: hears each result as it arrives.
Runner = Callable[..., list[Any]]


def in_process(fn: Callable[[Any], Any], items: Sequence[Any],
                progress: Callable[[int, int], None] | None = None) -> list[Any]:
    """The runner of :func:`task_runner` that runs every item here, one after the other."""
    out = []
    for x in items:
        out.append(fn(x))
        if progress is not None:
            progress(len(out), len(items))
    return out


@contextmanager
def task_runner(tasks: int, *, jobs: int | None = None, scheduler: str | None = None
                ) -> Iterator[tuple[Runner, str]]:
    """Where ``tasks`` independent tasks run: yields (``runner(fn, items) -> results`` in item
    order, a phrase saying where).

    Args:
        tasks: how many tasks there are.
        jobs: worker processes of a local Dask cluster (1: in this process); default: one per
            :data:`PARTS_PER_WORKER` tasks, at most the CPUs; in this process where that is one.
        scheduler: an existing Dask scheduler's address (``tcp://host:8786``): its workers run
            the tasks (they must import the same rodcad).
    """
    if scheduler:
        from distributed import Client

        from rodcad.errors import InputError, Problem

        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError, TypeError) as err:
            raise InputError([Problem("--scheduler", 0, 0, "--scheduler",
                                      f"no Dask scheduler answers at {scheduler!r}: {err}")]) from None
        with client:
            yield _dask(client), f"on the Dask scheduler at {scheduler}"
        return
    cpus = default_jobs()
    n = jobs if jobs is not None else min(cpus, tasks // PARTS_PER_WORKER)
    n = max(1, min(int(n), tasks))
    if n == 1:
        yield in_process, "in this process"
        return
    from distributed import Client

    with local_cluster(n) as cluster, Client(cluster) as client:
        yield _dask(client), f"{n} Dask worker processes"


@contextmanager
def local_cluster(n: int) -> Iterator[Any]:
    """A ``distributed.LocalCluster`` of ``n`` single-threaded worker processes, forked by
    their nannies from the forkserver of :func:`start_workers` (the CAD kernel imported, never
    used), or spawned where forkserver is missing, each importing the rodcad this one runs.

    Spawned, each worker imported the CAD kernel on its own: about 8 s of CPU a worker, the
    most of a small net's parallel build on 2 cores."""
    import logging

    import dask
    from distributed import LocalCluster

    import rodcad

    start_workers()
    method = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
    root = str(Path(rodcad.__file__).resolve().parents[1])  # spawned workers import this rodcad
    path = os.pathsep.join([root] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])
    # (forked, the workers' BLAS was loaded by the forkserver before these are set, as for the
    # worker_pool's processes: they run the kernel, not large matrix products)
    env = {"PYTHONPATH": path, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    with dask.config.set({"distributed.worker.multiprocessing-method": method}), \
            LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                         silence_logs=logging.ERROR, env=env) as cluster:
        yield cluster


def _dask(client) -> Runner:
    """A runner submitting each item as a task to ``client``; results gathered in item order."""

    def run(fn: Callable[[Any], Any], items: Sequence[Any],
            progress: Callable[[int, int], None] | None = None) -> list[Any]:
        from distributed import as_completed

        futures = client.map(fn, list(items), pure=False)
        if progress is not None:  # counted as they finish, in any order
            for done, _ in enumerate(as_completed(futures), 1):
                progress(done, len(futures))
        return list(client.gather(futures))

    return run
