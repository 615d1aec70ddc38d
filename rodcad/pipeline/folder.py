"""The output folder every kind of structure writes: staged (a failed or interrupted run leaves
it as it was, :func:`rodcad.outdir.staged_output`), with the progress it reports to, and its
design.json and report.md. (A build that misses its tolerance writes it to
:func:`rodcad.outdir.best_fit_folder` instead, :func:`rodcad.pipeline.run`.)
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from rodcad.outdir import staged_output
from rodcad.outputs.design_json import write_json
from rodcad.progress import Progress

__all__ = ["staged", "write_design"]


@contextmanager
def staged(outdir: str | Path, progress: Progress | None) -> Iterator[tuple[Path, Progress]]:
    """The temporary folder to write into, renamed to ``outdir`` at the end, and the
    progress to report to (silent when None)."""
    with staged_output(Path(outdir)) as tmp:
        yield tmp, progress or Progress(quiet=True)


def write_design(tmp: Path, data: dict[str, Any], report: str) -> None:
    """design.json (``data``) and report.md (``report``) into the staged folder ``tmp``."""
    write_json(tmp / "design.json", data)
    (tmp / "report.md").write_text(report, encoding="utf-8")
