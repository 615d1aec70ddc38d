"""Output folders that change all at once or not at all.

Everything a command writes goes to a temporary folder next to the destination;
only when every file is written (and checked) is the folder renamed into place.
A run that fails, raises or is interrupted leaves the destination as it was.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["staged_output"]


@contextmanager
def staged_output(outdir: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a fresh temporary folder; on success it replaces ``outdir``.

    The temporary folder is a hidden sibling of ``outdir`` (same file system, so
    the final rename is atomic). An existing ``outdir`` is moved aside first and
    removed only after the new one is in place.

    Example:
        >>> with staged_output("outputs/heart") as tmp:  # doctest: +SKIP
        ...     (tmp / "design.json").write_text("{}")
    """
    out = Path(outdir)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    try:
        yield tmp
        old = None
        if out.exists() or out.is_symlink():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
            os.replace(out, old / out.name)
        os.replace(tmp, out)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
