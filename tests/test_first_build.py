"""What makes a first build quick without changing it: worker processes kept between the tables
of reachable masses and the rods (a type's tasks in one worker), solids sent back from the
workers exactly, the tables' row alternates found with the tables."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from rodcad.catalog.cache import DiskCache
from rodcad.catalog.loader import load_catalog
from rodcad.parallel import cached_map, kept_workers


def _pid(item: int) -> tuple[int, int]:
    return item, os.getpid()


class _Memory:
    def __init__(self) -> None:
        self.values: dict[tuple[str, str], object] = {}

    def get(self, kind: str, key: str) -> object:
        return self.values.get((kind, key))

    def put(self, kind: str, key: str, value: object) -> None:
        self.values[(kind, key)] = value


def test_kept_workers_run_a_homes_tasks_in_the_same_worker() -> None:
    homes = ["a", "b", "a", "c", "b", "a"]
    with kept_workers(2):
        first = cached_map(_pid, list(range(6)), [f"k{i}" for i in range(6)], kind="t", cache=_Memory(),
                           homes=homes)
        again = cached_map(_pid, list(range(6)), [f"j{i}" for i in range(6)], kind="t", cache=_Memory(),
                           homes=homes)
    assert [i for i, _ in first] == list(range(6))  # results in item order
    where = {}
    for home, (_, pid) in zip(homes * 2, first + again):
        assert where.setdefault(home, pid) == pid
    assert len(set(where.values())) == 2


def test_a_portable_solid_comes_back_exactly() -> None:
    from rodcad.cad.solids import PortableSolid, is_valid_solid, mass_properties, type_solid

    rod = load_catalog("pla-parametric").rod("rod", 51.76, 0.01, scale=1.2)
    solid = type_solid(rod)
    back = PortableSolid(solid).restore()
    assert back.label == solid.label and is_valid_solid(back)
    assert mass_properties(back) == mass_properties(solid)


def test_the_row_alternates_come_with_a_computed_table(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from rodcad.fabrication.intervals import ROWS, chain_intervals, interval_table, row_alternates

    monkeypatch.setenv("RODCAD_SEED_CACHE", "0")  # computed here, not read from the suite's shipped tables

    rod = load_catalog("pla-parametric").rod("rod", 51.763608458837815, 0.009999489832780796,
                                             scale=1.270783016132191)
    cache = DiskCache(tmp_path)
    chain_intervals([rod], seed=0, jobs=1, cache=cache)
    table = interval_table(rod, 0, cache)
    assert table[ROWS]  # two rows of balls: their one-row alternates
    plain = {k: v for k, v in table.items() if k != ROWS}
    assert row_alternates(rod, 0, cache) == table[ROWS] == row_alternates(rod, 0, table=plain)


@pytest.mark.parametrize("argv, cpus, starts", [
    (["build", "d.yaml"], 2, True), (["build", "d.yaml", "--no-cad"], 2, False),
    (["build", "d.yaml", "--jobs", "1"], 2, False), (["build", "d.yaml", "--jobs=1"], 2, False),
    (["simulate", "d.yaml"], 2, False), (["build", "-h"], 2, False),
    (["build", "d.yaml"], 1, False), (["build", "d.yaml", "--jobs", "2"], 1, True)])
def test_the_workers_start_early_only_for_a_build_with_solids(argv: list[str], cpus: int, starts: bool,
                                                               monkeypatch: pytest.MonkeyPatch) -> None:
    """Where the run may use ``cpus`` CPUs (RODCAD_JOBS, or the machine's): with one, only an
    explicit ``--jobs`` above 1 starts them."""
    from rodcad.cli import _builds_solids

    monkeypatch.setattr("rodcad.parallel.default_jobs", lambda: cpus)
    assert _builds_solids(argv) == starts


def test_rodcad_jobs_caps_the_default_workers_and_a_bad_value_is_named(monkeypatch: pytest.MonkeyPatch,
                                                                      tmp_path: Path, capsys) -> None:
    from rodcad.cli import main
    from rodcad.errors import InputError
    from rodcad.parallel import JOBS_ENV, default_jobs

    monkeypatch.delenv(JOBS_ENV, raising=False)
    cpus = default_jobs()
    monkeypatch.setenv(JOBS_ENV, "1")
    assert default_jobs() == 1
    monkeypatch.setenv(JOBS_ENV, str(cpus + 3))
    assert default_jobs() == cpus  # a cap, never more than the CPUs
    design = tmp_path / "d.yaml"
    design.write_text((Path(__file__).resolve().parents[1] / "examples" / "semicircle.yaml").read_text())
    for bad in ("0", "two", "-1", "1.5"):
        monkeypatch.setenv(JOBS_ENV, bad)
        with pytest.raises(InputError):
            default_jobs()
        assert main(["build", str(design), "-o", str(tmp_path / "out"), "--no-cad", "-q"]) == 2
        err = capsys.readouterr().err
        assert f"{JOBS_ENV}={bad!r}" in err and "Traceback" not in err
        assert not (tmp_path / "out").exists()
