"""README's first command with every step's wall time and the CPU time of the whole process
tree (this process, the worker forkserver and its workers): run it in a fresh clone with an
empty HOME for cold caches.

    git clone -q REPO /tmp/fb && cd /tmp/fb && rm -rf outputs && \\
        HOME=$(mktemp -d) PYTHONPATH=. python benchmarks/bench_first_build.py build examples/semicircle.yaml

The arguments are `rodcad`'s. The table goes to stderr after the command's own output;
"(between steps)" is time outside the steps (the first one: the imports and loading the design).
"""

from __future__ import annotations

import os
import sys
import time
from contextlib import contextmanager

import psutil

ME = psutil.Process()


def tree_cpu() -> float:
    """CPU seconds of this process and every descendant (live, or ended and waited for)."""
    t = ME.cpu_times()
    total = t.user + t.system + t.children_user + t.children_system
    for child in ME.children(recursive=True):
        try:
            c = child.cpu_times()
        except psutil.Error:
            continue
        total += c.user + c.system + c.children_user + c.children_system
    return total


def main(argv: list[str]) -> int:
    import rodcad.progress as progress

    rows: list[tuple[str, float, float]] = []
    last = [time.time(), tree_cpu()]
    rows.append(("start (interpreter)", last[0] - ME.create_time(), last[1]))
    step = progress.Progress.step

    @contextmanager
    def timed(self, name):
        w0, c0 = time.time(), tree_cpu()
        if w0 - last[0] > 0.05:
            rows.append(("(between steps)", w0 - last[0], c0 - last[1]))
        with step(self, name) as st:
            yield st
        w1, c1 = time.time(), tree_cpu()
        rows.append((name[:60], w1 - w0, c1 - c0))
        last[:] = [w1, c1]

    progress.Progress.step = timed
    from rodcad.cli import main as rodcad

    code = rodcad(argv)
    w1, c1 = time.time(), tree_cpu()
    rows.append(("(after the last step)", w1 - last[0], c1 - last[1]))
    print(f"\n{'step':62s} {'wall s':>7s} {'cpu s':>7s}", file=sys.stderr)
    for name, wall, cpu in rows:
        print(f"{name:62s} {wall:7.2f} {cpu:7.2f}", file=sys.stderr)
    print(f"{'total (since the process started)':62s} {w1 - ME.create_time():7.2f} {c1:7.2f}   "
          f"load {os.getloadavg()[0]:.2f}", file=sys.stderr)
    return code


if __name__ == "__main__":  # the forkserver imports this module as __mp_main__: run nothing there
    sys.exit(main(sys.argv[1:]))
