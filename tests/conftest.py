"""Shared test set-up: one disk cache per test session, never the user's.

Joint limits and mass ranges computed from the B-rep are cached on disk; the
session cache keeps tests independent of ~/.cache/rodcad while computing each
catalog once per session. Modules that need a cold cache set their own.

The seed layer (precomputed ``catalogs/*.cache.json``) is switched off with
``RODCAD_SEED_CACHE=0``: the tests must exercise the real computations from
the solids, not read back their stored results (tests/test_seed_cache.py
checks the seeds themselves).
"""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session", autouse=True)
def session_cache(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rodcad-cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("RODCAD_CACHE_DIR", str(folder))
        mp.setenv("RODCAD_SEED_CACHE", "0")  # compute from the solids, never from shipped seeds
        yield folder
