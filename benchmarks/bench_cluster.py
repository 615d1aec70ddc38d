"""Benchmark of a local Dask cluster's start (issue 33's ``--jobs N`` on a net), printing a table.

Each row runs in a fresh process: start a 2-worker ``distributed.LocalCluster`` the way
:func:`rodcad.parallel.local_cluster` does (its workers forked from the forkserver that has the
CAD kernel loaded), or with Dask's default (each worker spawned, importing the kernel itself),
then run a first task on every worker that uses rodcad's CAD modules (a net's part builder).
It reports the wall time to the cluster's start, to the first tasks' end, and the CPU of the
whole process tree (this process, the forkserver, the workers), read from /proc/stat around
the run (the machine otherwise idle).

Usage:
    python benchmarks/bench_cluster.py [--repeat 2] [--workers 2]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, logging, os, sys, time
t0 = time.perf_counter()


def first_task(_):
    import rodcad.cad.net.build  # what a net's part task needs
    return os.getpid()


if __name__ == "__main__":
    how, n = sys.argv[1], int(sys.argv[2])
    from distributed import Client
    if how == "rodcad":
        from rodcad.parallel import local_cluster
        cluster = local_cluster(n)
    else:
        from distributed import LocalCluster
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=logging.ERROR)
    with cluster as c:
        with Client(c) as client:
            t1 = time.perf_counter()
            pids = set(client.gather(client.map(first_task, range(2 * n), pure=False)))
            t2 = time.perf_counter()
    print(json.dumps({"start": t1 - t0, "first": t2 - t1, "workers": len(pids)}))
"""


def _cpu() -> float:
    """The machine's user + nice + system CPU seconds so far (all processes)."""
    fields = Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:4]
    return sum(int(x) for x in fields) / os.sysconf("SC_CLK_TCK")


def run(how: str, workers: int) -> dict:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    c0, t0 = _cpu(), time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CHILD, how, str(workers)], capture_output=True, text=True,
                          env=env, timeout=600, check=True)
    wall, cpu = time.perf_counter() - t0, _cpu() - c0
    return {**json.loads(done.stdout.strip().splitlines()[-1]), "wall": wall, "cpu": cpu}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    print(f"# local Dask cluster of {a.workers} workers: {platform.node()}, {os.cpu_count()} CPUs, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}\n")
    print("| workers | run | to the cluster's start s | first tasks s | whole process s | CPU of all processes s |")
    print("|---|---:|---:|---:|---:|---:|")
    for k in range(a.repeat):
        for how, label in (("rodcad", "forked (rodcad.parallel.local_cluster)"), ("spawn", "spawned (Dask's default)")):
            r = run(how, a.workers)
            print(f"| {label} | {k + 1} | {r['start']:.2f} | {r['first']:.2f} | {r['wall']:.2f} | {r['cpu']:.1f} |",
                  flush=True)


if __name__ == "__main__":
    main()
