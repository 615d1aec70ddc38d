"""Worker processes for CAD-heavy work.

The OCCT kernel is not safe to ``fork`` once it has been used (a lock held by
one of its threads in the parent stays locked in the child), so workers come
from a *forkserver* that has imported the CAD modules (:mod:`rodcad.cad`) but never built
anything; where forkserver is missing, they are spawned.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor

__all__ = ["default_jobs", "worker_pool"]


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
