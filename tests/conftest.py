"""Shared test set-up: one disk cache per test session, never the user's.

Joint limits and mass ranges computed from the B-rep are cached on disk; the
session cache keeps tests independent of ~/.cache/rodcad while computing each
catalog once per session. Modules that need a cold cache set their own.

The seed layer (precomputed ``catalogs/*.cache.json``: the shipped catalogs' joint
limits, mass ranges and achievable-mass tables) stays on, so that the tests that only
use a shipped catalog share those numbers instead of recomputing 2-3 minutes of B-rep
searches. The computations from the solids are still tested where they are the
subject: on the test catalogs of test_catalog_* (no seeds exist for them), on a sample
of pla-weighted's pairs with seeds off (test_catalog_weighted.py), seeds against a fresh
computation (test_seed_cache.py), and every pair of both shipped catalogs against the
fast joint-limit function (test_jointlimits.py).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

# the benchmarks' generators (random chains, drawn shapes) are shared with the tests
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from rodcad.cli import main

if os.environ.get("PYTEST_XDIST_WORKER"):
    # a worker per CPU already fills the machine: each on one BLAS thread (OpenBLAS's threads
    # spin while they wait, and two workers' would fight over two cores)
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1, user_api="blas")


@pytest.fixture(scope="session", autouse=True)
def session_cache(tmp_path_factory):
    if os.environ.get("PYTEST_XDIST_WORKER"):
        # pytest-xdist: the workers share one cache (writes are atomic), so each catalog's
        # numbers are computed once per run, not once per worker
        folder = tmp_path_factory.getbasetemp().parent / "rodcad-cache"
        folder.mkdir(exist_ok=True)
    else:
        folder = tmp_path_factory.mktemp("rodcad-cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("RODCAD_CACHE_DIR", str(folder))
        mp.setenv("RODCAD_SEED_CACHE", "1")
        yield folder


@pytest.fixture(scope="session")
def build_design(tmp_path_factory):
    """``rodcad build -q`` of a design given as text, into a fresh folder: call it with
    (text, name, *options); it returns (OUTDIR, design.json as read)."""
    def build(text: str, name: str, *options: str):
        root = tmp_path_factory.mktemp(name)
        design = root / f"{name}.yaml"
        design.write_text(text, encoding="utf-8")
        out = root / "built"
        assert main(["build", str(design), "-o", str(out), "-q", *options]) == 0
        return out, json.loads((out / "design.json").read_text())
    return build


def pytest_collection_modifyitems(config, items):
    """Tests marked ``slow`` (MuJoCo releases of the heart with pin friction, a few minutes
    each; ten more drawn shapes) run when ``RODCAD_SLOW=1``; the same checks run on smaller
    chains and on a drawn shape of every kind always."""
    if os.environ.get("RODCAD_SLOW", "0").strip() == "1":
        return
    skip = pytest.mark.skip(reason="slow: set RODCAD_SLOW=1 to run it")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)
