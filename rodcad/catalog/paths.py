"""Where the shipped catalogs live."""

from __future__ import annotations

from pathlib import Path

__all__ = ["default_catalog_dir", "shipped_catalogs"]


def default_catalog_dir() -> Path:
    """The folder of shipped catalogs (``catalogs/`` next to the package)."""
    return Path(__file__).resolve().parents[2] / "catalogs"


def shipped_catalogs(base_dir: str | Path | None = None) -> list[str]:
    """Names of the catalogs in ``base_dir`` (default: the shipped folder)."""
    folder = Path(base_dir) if base_dir is not None else default_catalog_dir()
    return sorted(p.stem for p in folder.glob("*.yaml"))
