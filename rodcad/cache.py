"""A small on-disk JSON cache for results derived from rod geometry.

Entries are files ``<dir>/<kind>/<key[:2]>/<key>.json`` written atomically;
keys are hashes of every input parameter plus the version of the code that
computed them, so a change of either is a miss. A cache that cannot be read or
written is skipped silently: it only ever saves time.

The directory is ``$RODCAD_CACHE_DIR`` or ``~/.cache/rodcad``.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["DiskCache", "default_cache_dir", "make_key"]


def default_cache_dir() -> Path:
    """``$RODCAD_CACHE_DIR`` if set, else ``~/.cache/rodcad``."""
    env = os.environ.get("RODCAD_CACHE_DIR")
    if env:
        return Path(env).expanduser()
    return Path.home() / ".cache" / "rodcad"


def make_key(*parts: Any) -> str:
    """A stable hash of JSON-serialisable parts (floats by repr)."""
    text = json.dumps(parts, sort_keys=True, separators=(",", ":"), default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


class DiskCache:
    """JSON values stored by key on disk.

    Args:
        directory: cache root (default :func:`default_cache_dir`, read when
            the cache is created); None or ``enabled=False`` disables it.
        enabled: False makes every lookup a miss and every store a no-op.
    """

    def __init__(self, directory: str | os.PathLike[str] | None = None, *, enabled: bool = True) -> None:
        self.directory = Path(directory) if directory is not None else default_cache_dir()
        self.enabled = enabled

    def _path(self, kind: str, key: str) -> Path:
        return self.directory / kind / key[:2] / f"{key}.json"

    def get(self, kind: str, key: str) -> Any | None:
        """The stored value, or None when absent or unreadable."""
        if not self.enabled:
            return None
        try:
            with open(self._path(kind, key), encoding="utf-8") as fh:
                return json.load(fh)
        except (OSError, ValueError):
            return None

    def put(self, kind: str, key: str, value: Any) -> None:
        """Store a value (atomically; errors are ignored)."""
        if not self.enabled:
            return
        path = self._path(kind, key)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=".json")
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                json.dump(value, fh)
            os.replace(tmp, path)
        except OSError:
            try:
                os.unlink(tmp)  # type: ignore[possibly-undefined]
            except (OSError, NameError):
                pass
