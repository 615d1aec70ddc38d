"""Progress for long steps, on stderr (stdout stays clean for --json).

Each step prints its name, then ``done (1.2 s)``; steps that process many items
update a counter in place on a terminal and print every tenth in a log.

Example:
    >>> p = Progress(quiet=True)
    >>> with p.step("joint limits") as st:
    ...     st.count(3, 10)
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO

__all__ = ["Progress", "Step"]


class Step:
    """One running step; :meth:`count` reports ``done`` of ``total`` items, :meth:`note` what
    it is doing now."""

    def __init__(self, progress: Progress, name: str) -> None:
        self.progress = progress
        self.name = name
        self.t0 = time.perf_counter()
        self._last_tenth = -1

    def count(self, done: int, total: int) -> None:
        p = self.progress
        if p.quiet or total <= 0:
            return
        if p.tty:
            p.stream.write(f"\r  {self.name} ... {done}/{total}")
            p.stream.flush()
            return
        tenth = int(10 * done / total)
        if tenth != self._last_tenth:
            self._last_tenth = tenth
            p.stream.write(f"  {self.name} ... {done}/{total}\n")
            p.stream.flush()


    def note(self, text: str) -> None:
        """Say what the step is doing now (in place on a terminal, a line in a log)."""
        p = self.progress
        if p.quiet:
            return
        if p.tty:
            p.stream.write(f"\r\033[K  {self.name} ... {text}")
        else:
            p.stream.write(f"  {self.name} ... {text}\n")
        p.stream.flush()


class Progress:
    """Reports steps on a stream.

    Args:
        stream: where to write (default stderr).
        quiet: write nothing.
    """

    def __init__(self, stream: TextIO | None = None, *, quiet: bool = False) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.quiet = quiet
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.times: list[tuple[str, float]] = []

    @contextmanager
    def step(self, name: str) -> Iterator[Step]:
        """Time a step and report it."""
        st = Step(self, name)
        if not self.quiet and self.tty:
            self.stream.write(f"  {name} ... ")
            self.stream.flush()
        yield st
        dt = time.perf_counter() - st.t0
        self.times.append((name, dt))
        if not self.quiet:
            prefix = f"\r  {name} ... " if self.tty else f"  {name}: "
            self.stream.write(f"{prefix}done ({dt:.1f} s)\n")
            self.stream.flush()
