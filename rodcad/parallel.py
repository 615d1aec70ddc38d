"""Worker processes for CAD-heavy work.

The OCCT kernel is not safe to ``fork`` once it has been used (a lock held by
one of its threads in the parent stays locked in the child), so workers come
from a *forkserver* that has imported the CAD modules (:mod:`rodcad.cad`) but never built
anything; where forkserver is missing, they are spawned.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Protocol

__all__ = ["KeyValueStore", "cached_map", "default_jobs", "worker_pool"]


def default_jobs() -> int:
    """Number of CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def worker_pool(jobs: int) -> ProcessPoolExecutor:
    """A process pool of ``jobs`` workers that may use the CAD kernel."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["rodcad.cad.solids", "rodcad.cad.collision", "rodcad.cad.export"])
    else:  # pragma: no cover - Windows / macOS default
        ctx = multiprocessing.get_context("spawn")
    return ProcessPoolExecutor(max_workers=jobs, mp_context=ctx)


class KeyValueStore(Protocol):
    """What :func:`cached_map` needs of a cache (:class:`rodcad.catalog.cache.DiskCache`)."""

    def get(self, kind: str, key: str) -> Any: ...

    def put(self, kind: str, key: str, value: Any) -> None: ...


def cached_map(fn: Callable[[Any], Any], items: Sequence[Any], keys: Sequence[str], *, kind: str,
               cache: KeyValueStore, jobs: int | None = None, progress: Callable[[int, int], None] | None = None,
               usable: Callable[[Any], bool] = lambda value: value is not None,
               computed: set[str] | None = None) -> list[Any]:
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

    Returns:
        The results in item order.
    """
    if len(keys) != len(items):
        raise ValueError(f"{len(keys)} keys for {len(items)} items")
    found: dict[str, Any] = {}
    todo: dict[str, Any] = {}
    for item, key in zip(items, keys):
        if key in found or key in todo:
            continue
        hit = cache.get(kind, key)
        if usable(hit):
            found[key] = hit
        else:
            todo[key] = item
    work = list(todo.items())
    jobs = max(1, min(jobs or default_jobs(), len(work))) if work else 1
    pool = worker_pool(jobs) if jobs > 1 else None
    try:
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
