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

__all__ = ["MARKER", "OutputFolderError", "best_fit_folder", "check_output_folder", "staged_output", "write_atomic"]

#: The file every output folder carries, so a later run knows it may replace the folder.
MARKER = ".rodcad-output"

#: Longest file name most file systems take (bytes).
NAME_MAX = 255

#: Places no output folder goes (the kernel's virtual file systems).
_FORBIDDEN = ("/proc", "/sys", "/dev")


class OutputFolderError(ValueError):
    """An output folder that cannot or must not be written (the message says why)."""


def _is_rodcad_output(folder: Path) -> bool:
    """An earlier rodcad output folder: it has the marker, or (older runs) a design.json
    written by rodcad, or a demo's equilibrium.json."""
    if (folder / MARKER).is_file():
        return True
    try:
        head = (folder / "design.json").read_text(encoding="utf-8")[:4096]
    except (OSError, UnicodeDecodeError):
        head = ""
    return '"rodcad":' in head or (folder / "equilibrium.json").is_file()


def check_output_folder(outdir: str | os.PathLike[str]) -> Path:
    """Whether ``outdir`` may become an output folder: a new path whose parents are
    folders (or can be made), or an earlier rodcad output folder (it is replaced).

    Returns:
        The folder as an absolute path.

    Raises:
        OutputFolderError: anything else (a file, a folder of other things, the current
            folder or one of its parents, a name too long, a system folder).
    """
    raw = os.fspath(outdir)
    if not raw.strip():
        raise OutputFolderError("the output folder name is empty")
    out = Path(raw).expanduser().absolute()
    too_long = [p.name for p in (out, *out.parents) if len(p.name.encode()) + 32 > NAME_MAX]
    if too_long:  # room for the staging folder's prefix and suffix
        raise OutputFolderError(f"a folder name in the output path is {len(too_long[0])} characters long; keep "
                                f"each under {NAME_MAX - 32}")
    try:
        return _check(raw, out)
    except OSError as err:
        raise OutputFolderError(f"{raw}: {err.strerror or err}") from None


def _check(raw: str, out: Path) -> Path:
    resolved = out.resolve()
    if any(str(resolved) == f or str(resolved).startswith(f + "/") for f in _FORBIDDEN):
        raise OutputFolderError(f"{raw}: rodcad does not write under /{resolved.parts[1]}")
    cwd = Path.cwd().resolve()
    if resolved == cwd or resolved in cwd.parents:
        raise OutputFolderError(f"{raw} is the current folder or one of its parents; name a new folder")
    for parent in out.parents:
        if parent.exists() and not parent.is_dir():
            raise OutputFolderError(f"{raw}: {parent} is a file, not a folder")
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        raise OutputFolderError(f"{raw} exists and is not a folder; rodcad replaces only its own output folders "
                                "(move it away or name another folder)")
    if out.is_dir() and any(out.iterdir()) and not _is_rodcad_output(out):
        raise OutputFolderError(f"{raw} is a folder rodcad did not write; rodcad replaces only its own output "
                                "folders (empty it, move it away or name another folder)")
    return out


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
    out = check_output_folder(outdir)
    out.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale(out)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-{os.getpid()}-", dir=out.parent))
    try:
        yield tmp
        (tmp / MARKER).write_text("written by rodcad; a later run may replace this folder\n", encoding="utf-8")
        old = None
        if out.exists() or out.is_symlink():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-{os.getpid()}-", dir=out.parent))
            os.replace(out, old / out.name)
        os.replace(tmp, out)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def _remove_stale(out: Path) -> None:
    """Staging folders of runs that died (killed before they could clean up) next to ``out``."""
    for p in out.parent.glob(f".{glob_escape(out.name)}.*-*-*"):
        parts = p.name[len(out.name) + 2:].split("-")
        if len(parts) < 3 or parts[0] not in ("tmp", "old") or not parts[1].isdigit():
            continue
        pid = int(parts[1])
        if pid == os.getpid() or _alive(pid):
            continue
        shutil.rmtree(p, ignore_errors=True)


def glob_escape(name: str) -> str:
    """``name`` with glob's special characters taken literally."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in name)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - another user's process
        return True
    return True


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


def best_fit_folder(outdir: Path) -> Path:
    """OUTDIR.best-fit, beside OUTDIR (where a design that misses its tolerance goes)."""
    return outdir.resolve().with_name(outdir.resolve().name + ".best-fit") if not outdir.name else \
        outdir.with_name(outdir.name + ".best-fit")
