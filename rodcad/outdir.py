"""Output folders and files that change all at once or not at all.

Everything a command writes goes to a temporary folder next to the destination;
only when every file is written (and checked) is the folder renamed into place.
A run that fails, raises or is interrupted leaves the destination as it was.
Single files go the same way (:func:`write_atomic`).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["staged_output", "write_atomic"]


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


def write_atomic(path: str | os.PathLike[str], text: str, *, mode: int | None = None) -> None:
    """Write ``text`` to ``path`` all at once: into a hidden temporary sibling, renamed
    into place, so readers never see a half-written file. ``mode`` sets the file's
    permissions (temporary files are private). The folder must exist.

    Raises:
        OSError: the file cannot be written (the temporary file is removed).
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        if mode is not None:
            os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
