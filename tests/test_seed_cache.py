"""The read-only seed layer of the disk cache and the shipped seed files.

Shipped catalogs come with ``catalogs/<name>.cache.json``: the joint limits,
mass ranges and achievable mass intervals (fabrication seed 0) precomputed by
``rodcad catalog precompute``. These tests check the layer itself, that the
shipped seeds hold every key the code asks for (a catalog or code-version
change makes them stale) and that a sample of their values is what the solids
give today.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from catalog_testutil import BASE, write

from rodcad.catalog import cache as cache_mod
from rodcad.catalog import limits, massrange
from rodcad.catalog.cache import DiskCache, register_seed
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.paths import default_catalog_dir, shipped_catalogs
from rodcad.cli import main
from rodcad.fabrication import intervals as fabricate

KEY = "ab" * 32


@pytest.fixture
def seeds(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Seeds on, an empty cache folder, no seed file registered (not even the
    shipped ones); returns the cache folder."""
    monkeypatch.setattr(cache_mod, "_seed_paths", [])
    monkeypatch.setattr(cache_mod, "_seed_data", {})
    monkeypatch.setattr(cache_mod, "_shipped_scanned", True)
    monkeypatch.setenv("RODCAD_SEED_CACHE", "1")
    folder = tmp_path / "cache"
    monkeypatch.setenv("RODCAD_CACHE_DIR", str(folder))
    return folder


def _seed_file(path: Path, entries: dict) -> Path:
    path.write_text(json.dumps({"rodcad_seed_cache": 1, "catalog": "t", "entries": entries}), encoding="utf-8")
    return path


def test_a_registered_seed_answers_misses(seeds: Path, tmp_path: Path) -> None:
    register_seed(_seed_file(tmp_path / "t.cache.json", {"limits": {KEY: {"lo": -1.5, "hi": 2.0}}}))
    c = DiskCache()
    assert c.get("limits", KEY) == {"lo": -1.5, "hi": 2.0}
    assert c.get("mass", KEY) is None and c.get("limits", "cd" * 32) is None
    c.get("limits", KEY)["lo"] = 99  # callers get their own copy
    assert c.get("limits", KEY)["lo"] == -1.5
    assert not seeds.exists()  # never copied to disk
    c.put("limits", KEY, {"lo": 0})  # the disk comes first
    assert c.get("limits", KEY) == {"lo": 0}


def test_seeds_off(seeds: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    register_seed(_seed_file(tmp_path / "t.cache.json", {"mass": {KEY: 1}}))
    assert DiskCache(enabled=False).get("mass", KEY) is None
    monkeypatch.setenv("RODCAD_SEED_CACHE", "0")  # read at lookup time
    assert DiskCache().get("mass", KEY) is None
    monkeypatch.setenv("RODCAD_SEED_CACHE", "1")
    assert DiskCache().get("mass", KEY) == 1


def test_bad_seed_files_are_skipped(seeds: Path, tmp_path: Path) -> None:
    (tmp_path / "corrupt.cache.json").write_text('{"rodcad_seed_cache": 1, "entr', encoding="utf-8")
    (tmp_path / "other.cache.json").write_text('{"entries": {"mass": {"%s": 2}}}' % KEY, encoding="utf-8")
    for name in ("missing", "corrupt", "other"):
        register_seed(tmp_path / f"{name}.cache.json")
    assert DiskCache().get("mass", KEY) is None
    register_seed(_seed_file(tmp_path / "good.cache.json", {"mass": {KEY: 3}}))
    assert DiskCache().get("mass", KEY) == 3


def test_load_catalog_registers_its_seed_and_shipped_seeds_are_found(seeds: Path, tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    path = write(tmp_path, BASE)
    seed = _seed_file(tmp_path / "cat.cache.json", {})
    load_catalog(path)
    assert cache_mod._seed_paths == [seed.resolve()]
    # the shipped folder is scanned on the first lookup
    monkeypatch.setattr(cache_mod, "_shipped_scanned", False)
    rod = load_catalog("pla-pinned").types[0]
    assert DiskCache().get("mass", massrange._key(rod)) is not None
    assert massrange.is_cached(rod, DiskCache()) and not seeds.exists()


@pytest.mark.parametrize("name", shipped_catalogs())
def test_shipped_seeds_are_current(name: str) -> None:
    hint = f"run `rodcad catalog precompute {name}` to refresh catalogs/{name}.cache.json"
    path = default_catalog_dir() / f"{name}.cache.json"
    assert path.is_file(), f"catalog {name!r} has no seed file: {hint}"
    data = json.loads(path.read_text(encoding="utf-8"))
    assert data["rodcad_seed_cache"] == 1
    entries = data["entries"]
    catalog = load_catalog(name)
    assert data["catalog"] == catalog.name
    wanted = {
        "mass": {t.name: massrange._key(t) for t in catalog},
        "limits": {f"{a.name} -> {b.name}": limits._cache_key(a.geometry, b.geometry, limits._wall(a, b))
                   for a, b in catalog.pairs()},
        # rods with a shot fill reach their whole range: no table of achievable masses
        "fabint": {t.name: fabricate.intervals_key(t, 0) for t in catalog if t.fill is None},
    }
    for kind, keys in wanted.items():
        missing = [what for what, key in keys.items() if key not in entries.get(kind, {})]
        assert not missing, f"catalog {name!r}: stale seed, no {kind} for {missing[:5]} ({len(missing)} missing): {hint}"


def test_seed_values_match_the_solids(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RODCAD_SEED_CACHE", "0")
    entries = json.loads((default_catalog_dir() / "pla-weighted.cache.json").read_text(encoding="utf-8"))["entries"]
    catalog = load_catalog("pla-weighted")
    left, right = catalog["free-30"], catalog["curve20-30"]
    wall = limits._wall(left, right)
    stored = entries["limits"][limits._cache_key(left.geometry, right.geometry, wall)]
    fresh = limits.compute_pair_limits(left.geometry, right.geometry, wall)
    assert stored["assemblable"] == fresh["assemblable"]
    assert [stored["lo"], stored["hi"]] == pytest.approx([fresh["lo"], fresh["hi"]], rel=1e-6, abs=1e-9)
    rod = catalog["free-30"]
    stored = entries["mass"][massrange._key(rod)]
    fresh = massrange.compute_mass_info(rod).to_json()
    assert stored.keys() == fresh.keys()
    for k, v in fresh.items():  # numbers, pairs and the per-ball-kind (count, m_max) pairs
        flat = [float(x) for x in np.ravel(np.asarray(stored[k], dtype=float))]
        assert flat == pytest.approx([float(x) for x in np.ravel(np.asarray(v, dtype=float))], rel=1e-6, abs=1e-9), k


def test_precompute_writes_a_seed_that_later_runs_read(seeds: Path, tmp_path: Path,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, BASE)
    assert main(["catalog", "precompute", str(path), "--jobs", "1"]) == 0
    seed = tmp_path / "cat.cache.json"
    out = capsys.readouterr().out
    assert out.startswith("catalog test: 1 limits, 1 mass, 1 fabint entries in ") and str(seed) in out
    data = json.loads(seed.read_text(encoding="utf-8"))
    assert data["catalog"] == "test" and set(data["entries"]) == {"limits", "mass", "fabint"}
    assert not seeds.exists()  # computed in a temporary cache ...
    assert os.environ["RODCAD_CACHE_DIR"] == str(seeds) and os.environ["RODCAD_SEED_CACHE"] == "1"  # ... restored
    rod = load_catalog(path).types[0]  # registers the seed
    assert limits.is_cached(rod, rod, DiskCache()) and massrange.is_cached(rod, DiskCache())
    table = data["entries"]["fabint"][fabricate.intervals_key(rod, 0)]
    assert fabricate.achievable_intervals(rod) == [tuple(i) for i in table["intervals"]]
    assert not seeds.exists()


def test_the_suite_seed_holds_the_joint_limits_a_plan_asks_for_as_the_outlines_give_them(monkeypatch):
    """tests/data/suite-tables.cache.json ships the joint limits the suite's plans ask for
    (tests/suite_tables.py): those the semicircle's plan asks are there, and each is what
    :func:`joint_limits` computes today (a changed computation that does not raise
    JOINT_LIMITS_VERSION fails here instead of planning the suite on old limits)."""
    import suite_tables

    from rodcad import pipeline
    from rodcad.catalog import jointlimits, keptlimits
    from rodcad.design import laying
    from rodcad.design.loader import load_design

    if suite_tables.writing():
        pytest.skip("the seed is being written")
    asked = []

    def kept(left, right):
        asked.append((left, right))
        return jointlimits.joint_limits(left, right)

    monkeypatch.setattr(laying, "kept_joint_limits", kept)
    pipeline.build(load_design(Path(__file__).resolve().parents[1] / "examples" / "semicircle.yaml"), cad=False)
    assert asked
    hint = "stale: regenerate with RODCAD_SUITE_TABLES=write python -m pytest -q (tests/suite_tables.py)"
    for left, right in dict.fromkeys(asked):
        seeded = cache_mod._seed_get(keptlimits.CACHE_KIND, keptlimits.limits_key(left, right))
        assert seeded is not None, hint
        fresh = jointlimits.joint_limits(left, right)
        for got, want in zip((seeded["lo"], seeded["hi"]), fresh):  # to the bisection's bracket
            assert (got is None) == (want is None) and (want is None or got == pytest.approx(
                want, abs=2 * jointlimits.BISECT_DEG)), hint

