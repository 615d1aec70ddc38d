"""A small on-disk JSON cache for results derived from rod geometry.

Entries are files ``<dir>/<kind>/<key[:2]>/<key>.json`` written atomically;
keys are hashes of every input parameter plus the version of the code that
computed them, so a change of either is a miss. A cache that cannot be read or
written is skipped silently: it only ever saves time.

The directory is ``$RODCAD_CACHE_DIR`` or ``~/.cache/rodcad``.

Below it sits a read-only *seed* layer: precomputed entries shipped as JSON
files ``{"rodcad_seed_cache": 1, "catalog": NAME, "entries": {kind: {key:
value}}}`` (written by ``rodcad catalog precompute``). A miss on disk is looked
up in every ``*.cache.json`` of the shipped catalog folder and in the files
given to :func:`register_seed` (:func:`rodcad.catalog.loader.load_catalog` registers
``<stem>.cache.json`` next to a catalog file). Seeds are never copied to disk;
``RODCAD_SEED_CACHE=0`` or a disabled :class:`DiskCache` turns them off.
"""

from __future__ import annotations

import copy
import hashlib
import json
import os
from pathlib import Path
from typing import Any

from rodcad.outdir import write_atomic

__all__ = ['default_cache_dir', 'make_key', 'register_seed', 'seeds_enabled', 'DiskCache']


#: Seed files to look in, in registration order (resolved paths).
_seed_paths: list[Path] = []


#: Loaded entries per seed file ({} when missing or unreadable).
_seed_data: dict[Path, dict[str, Any]] = {}


#: Whether the shipped catalog folder has been scanned for seed files.
_shipped_scanned = False


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


def register_seed(path: str | os.PathLike[str]) -> None:
    """Look up misses in this seed file too (read on first use; a missing or
    unreadable file is skipped)."""
    p = Path(path).expanduser().resolve()
    if p not in _seed_paths:
        _seed_paths.append(p)


def seeds_enabled() -> bool:
    """False when ``$RODCAD_SEED_CACHE`` is ``0``."""
    return os.environ.get("RODCAD_SEED_CACHE", "1").strip() != "0"


def _load_seed(path: Path) -> dict[str, Any]:
    if path not in _seed_data:
        entries: dict[str, Any] = {}
        try:
            with open(path, encoding="utf-8") as fh:
                data = json.load(fh)
            if isinstance(data, dict) and data.get("rodcad_seed_cache") == 1 and isinstance(data.get("entries"), dict):
                entries = data["entries"]
        except (OSError, ValueError):
            pass
        _seed_data[path] = entries
    return _seed_data[path]


def _seed_get(kind: str, key: str) -> Any | None:
    """The value of (kind, key) in a seed file, or None."""
    global _shipped_scanned
    if not seeds_enabled():
        return None
    if not _shipped_scanned:
        _shipped_scanned = True
        from rodcad.catalog.paths import default_catalog_dir

        try:
            for p in sorted(default_catalog_dir().glob("*.cache.json")):
                register_seed(p)
        except OSError:
            pass
    for path in _seed_paths:
        table = _load_seed(path).get(kind)
        if isinstance(table, dict) and key in table:
            return copy.deepcopy(table[key])  # callers get their own copy, as from disk
    return None


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
        """The stored value (else the seed files' value), or None when absent
        or unreadable."""
        if not self.enabled:
            return None
        try:
            with open(self._path(kind, key), encoding="utf-8") as fh:
                return json.load(fh)
        except (OSError, ValueError):
            return _seed_get(kind, key)

    def put(self, kind: str, key: str, value: Any) -> None:
        """Store a value (atomically; errors are ignored)."""
        if not self.enabled:
            return
        path = self._path(kind, key)
        text = json.dumps(value)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            write_atomic(path, text)
        except OSError:
            pass
