"""The reachable-mass tables the suite's CAD builds need, and the joint limits its plans ask
for, shipped as a seed file (issue 34).

A CAD build first computes, for each distinct rod type it prints to order, the masses its
cavities and balls can reach (:func:`rodcad.fabrication.intervals.compute_table`, 1-3 s of
CPU a type). The suite's CAD builds need about fifteen such tables, the same on every run:
they are shipped in :data:`SEED` (the seed-cache format of ``rodcad catalog precompute``,
:mod:`rodcad.catalog.cache`), which tests/conftest.py registers for the session. A table is
found by a key of the rod's geometry, material, balls, seed and the fabrication code's
versions, so a changed rod, catalog or algorithm version misses and computes as before (the
suite is slower, never wrong); the computation itself stays tested where it is the subject
(tests/test_fabricate.py, tests/test_seed_cache.py, tests/test_buildable.py on their own
caches or with seeds off). The joint limits are keyed by both rods' geometry and
:data:`rodcad.catalog.keptlimits.JOINT_LIMITS_VERSION`; tests/test_seed_cache.py checks that
the seed holds the limits a design of the suite asks for and that they are what the outlines
give today (a changed computation that keeps its version fails there).

Regenerate after changing what a CAD test builds or the fabrication code's versions:

    RODCAD_SUITE_TABLES=write python -m pytest -q

(the seed is then left out, every table is computed into the session cache, and the
tables computed are written to :data:`SEED` when the session ends.)
"""

from __future__ import annotations

import json
import os
from pathlib import Path

__all__ = ["KINDS", "SEED", "collect", "writing"]

#: The seed file.
SEED = Path(__file__).resolve().parent / "data" / "suite-tables.cache.json"

#: The cache kinds it holds: the tables of reachable masses, their one-row alternates, and the
#: joint limits the planner finds from the rods' outlines
#: (:func:`rodcad.catalog.keptlimits.kept_joint_limits`: 20-100 ms a pair, a fifth of the
#: time of the suite's chain plans).
KINDS = ("fabint", "fabrow", "jointlimits")


def writing() -> bool:
    """Whether this session regenerates :data:`SEED` (``RODCAD_SUITE_TABLES=write``)."""
    return os.environ.get("RODCAD_SUITE_TABLES", "").strip() == "write"


def collect(cache_dir: Path, out: Path = SEED) -> int:
    """Write the entries of :data:`KINDS` found in a session's disk cache to ``out`` (keys
    sorted, so the file changes only where a table does); returns how many."""
    entries: dict[str, dict] = {}
    for kind in KINDS:
        table = entries[kind] = {}
        for path in sorted((Path(cache_dir) / kind).glob("*/*.json")):
            table[path.stem] = json.loads(path.read_text(encoding="utf-8"))
    out.parent.mkdir(parents=True, exist_ok=True)
    part = out.with_name(f"{out.name}.{os.getpid()}")  # written whole, then renamed over
    part.write_text(json.dumps({"rodcad_seed_cache": 1, "catalog": "the test suite's CAD builds",
                                "entries": entries}, sort_keys=True) + "\n", encoding="utf-8")
    part.replace(out)
    return sum(len(t) for t in entries.values())
