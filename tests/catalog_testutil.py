"""Helpers shared by the tests of rod catalogs (tests/test_catalog_*.py)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from rodcad.catalog.loader import load_catalog
from rodcad.catalog.model import Catalog
from rodcad.errors import InputError

#: A minimal valid catalog: one family of square-ended rods, 12 x 8 mm.
BASE = """\
catalog: 1
name: test
defaults:
  section: {height: 12, thickness: 8}
  joint: {pin_diameter: 1.75, knuckle_radius: 3.2, tongue_thickness: 2.8}
  material: {density: 1.24, min_wall: 1.2}
families:
  - name: sq
    length: 30
"""


def write(tmp_path: Path, text: str, name: str = "cat.yaml") -> Path:
    """Write (dedented) YAML text to tmp_path/name and return the path."""
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def load(tmp_path: Path, text: str) -> Catalog:
    return load_catalog(write(tmp_path, text))


def problems(tmp_path: Path, text: str) -> list[tuple[int, int, str, str]]:
    """Load a catalog that must be bad; return its problems as
    (line, column, key, message), checking they all name the file."""
    path = write(tmp_path, text)
    with pytest.raises(InputError) as info:
        load_catalog(path)
    assert all(p.file == str(path) for p in info.value.problems)
    return [(p.line, p.column, p.key, p.message) for p in info.value.problems]
