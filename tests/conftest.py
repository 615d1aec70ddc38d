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

import contextlib
import fcntl
import hashlib
import io
import json
import os
import pickle
import sys
from pathlib import Path

import pytest

# the benchmarks' generators (random chains, drawn shapes) are shared with the tests
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import suite_tables  # noqa: E402 - tests/ is on sys.path
from figure_clip import saved_figures  # noqa: E402
from rodcad.catalog.cache import register_seed  # noqa: E402
from rodcad.cli import main

if os.environ.get("PYTEST_XDIST_WORKER"):
    # a worker per CPU already fills the machine: each on one BLAS thread (OpenBLAS's threads
    # spin while they wait, and two workers' would fight over two cores)
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1, user_api="blas")
    # and rodcad's own worker processes (rodcad.parallel.JOBS_ENV): a build's default pool or
    # local Dask cluster would only share the same CPUs, after importing the CAD kernel again in
    # each of its processes. The tests of those paths ask for them (--jobs 2, jobs=2, --scheduler).
    os.environ["RODCAD_JOBS"] = "1"


def _session_folder(tmp_path_factory, name: str) -> Path:
    """A folder of this test session that every pytest-xdist worker shares (the workers'
    base temp folders sit side by side in the session's); without xdist, the process's own."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        folder = tmp_path_factory.getbasetemp().parent / name
        folder.mkdir(exist_ok=True)
        return folder
    return tmp_path_factory.mktemp(name)


@pytest.fixture(scope="session", autouse=True)
def session_cache(tmp_path_factory):
    # pytest-xdist: the workers share one cache (writes are atomic), so each catalog's
    # numbers are computed once per run, not once per worker
    folder = _session_folder(tmp_path_factory, "rodcad-cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("RODCAD_CACHE_DIR", str(folder))
        mp.setenv("RODCAD_SEED_CACHE", "1")
        if not suite_tables.writing():  # the tables the CAD builds need (tests/suite_tables.py)
            register_seed(suite_tables.SEED)
        yield folder
    if suite_tables.writing():  # each worker as it ends: the last one writes every table
        suite_tables.collect(folder)


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


_ROOT = Path(__file__).resolve().parents[1]


def _code_version() -> str:
    """A hash of the code and data a build reads (rodcad/, optimize/, catalogs/)."""
    h = hashlib.sha256()
    for top in ("rodcad", "optimize", "catalogs"):
        for path in sorted((_ROOT / top).rglob("*")):
            if path.is_file() and path.suffix in (".py", ".yaml", ".json"):
                h.update(str(path.relative_to(_ROOT)).encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


class BuildStore:
    """Builds that several test modules make of the same design, made once per test session
    and shared by every pytest-xdist worker (a module's fixtures would each build their own).

    An entry is a folder ``<root>/<key>`` keyed by everything the build reads: the design's
    path and text, the options and the code version (:func:`_code_version`). The first
    worker to want it builds it under an exclusive file lock (``<key>.lock``) while the
    others wait on the lock, then read it; a build that fails leaves no entry (the next one
    to want it tries again). Callers read the outputs and never change them.
    """

    def __init__(self, root: Path) -> None:
        self.root = root
        self._code: str | None = None

    def _entry(self, kind: str, *parts: str) -> Path:
        if self._code is None:
            self._code = _code_version()
        key = hashlib.sha256(json.dumps([kind, self._code, *parts]).encode()).hexdigest()[:24]
        return self.root / key

    @contextlib.contextmanager
    def _locked(self, entry: Path):
        with open(entry.with_suffix(".lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)

    def _cli_entry(self, design: Path | str, options: tuple[str, ...], text: str | None,
                   patches: tuple[tuple[str, str, object], ...]) -> tuple[Path, Path]:
        if text is None:
            design = Path(design).resolve()
            text = design.read_text(encoding="utf-8")
        entry = self._entry("cli", str(design), text, repr(patches), *options)
        return entry, (Path(design) if Path(design).is_absolute() else entry / str(design))

    def cli_build(self, design: Path | str, *options: str, text: str | None = None,
                  patches: tuple[tuple[str, str, object], ...] = ()) -> tuple[int, Path, str]:
        """``rodcad build DESIGN -o OUT *options`` run once per session: (exit code, OUT, what
        it printed on stdout). With ``text``, DESIGN is a file name and the design is that
        text (written into the store); ``patches`` are (module, attribute, value) set while
        it builds (and part of the key)."""
        import importlib

        from rodcad.pipeline import kinds

        entry, path = self._cli_entry(design, options, text, patches)
        done = entry / "done.json"
        with self._locked(entry):
            if not done.is_file():
                entry.mkdir(exist_ok=True)
                if text is not None:
                    path.write_text(text, encoding="utf-8")
                printed = io.StringIO()
                build = kinds.build

                def kept(*args, **kwargs):  # what the command built, for result()
                    out = build(*args, **kwargs)
                    if set(options) == {"--no-cad", "-q"} and not patches:
                        with contextlib.suppress(pickle.PicklingError, TypeError, AttributeError, RecursionError):
                            (entry / "result.pickle").write_bytes(pickle.dumps(out))
                    return out

                with (pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(printed),
                      saved_figures() as figures):
                    for module, name, value in patches:
                        mp.setattr(importlib.import_module(module), name, value)
                    mp.setattr(kinds, "build", kept)
                    code = main(["build", str(path), "-o", str(entry / "out"), *options])
                done.write_text(json.dumps({"code": code, "stdout": printed.getvalue(), "figures": figures}),
                                encoding="utf-8")
        record = json.loads(done.read_text(encoding="utf-8"))
        return record["code"], entry / "out", record["stdout"]

    def figures(self, design: Path, *options: str) -> list[tuple[str, list[str]]]:
        """The figures :meth:`cli_build` saved with these arguments: (path, what of it lay
        outside its canvas, tests/figure_clip.py)."""
        self.cli_build(design, *options)
        entry, _ = self._cli_entry(design, options, None, ())
        return [tuple(f) for f in json.loads((entry / "done.json").read_text(encoding="utf-8"))["figures"]]

    def result(self, design: Path | str, *, text: str | None = None):
        """``pipeline.build(load_design(DESIGN), cad=False)`` run once per session (each
        caller gets its own copy, unpickled): for a design file, what ``rodcad build DESIGN
        --no-cad -q`` (:meth:`cli_build`) built, which is that; with ``text``, DESIGN is a
        file name and the design is that text (written into the store)."""
        from rodcad import pipeline
        from rodcad.design.loader import load_design

        if text is None:
            design = Path(design).resolve()
            # the command's build without CAD is this one (same design, defaults): share it
            self.cli_build(design, "--no-cad", "-q")
            kept = self._cli_entry(design, ("--no-cad", "-q"), None, ())[0] / "result.pickle"
            if kept.is_file():
                return pickle.loads(kept.read_bytes())
            entry = self._entry("result", str(design), design.read_text(encoding="utf-8"))
        else:
            entry = self._entry("result-text", str(design), text)
        done = entry / "result.pickle"
        with self._locked(entry):
            if not done.is_file():
                entry.mkdir(exist_ok=True)
                if text is not None:
                    design = entry / str(design)
                    design.write_text(text, encoding="utf-8")
                data = pickle.dumps(pipeline.build(load_design(design), cad=False))
                (entry / "partial.pickle").write_bytes(data)
                (entry / "partial.pickle").replace(done)
        return pickle.loads(done.read_bytes())


@pytest.fixture(scope="session")
def build_store(tmp_path_factory) -> BuildStore:
    """The session's :class:`BuildStore` (shared by the pytest-xdist workers)."""
    return BuildStore(_session_folder(tmp_path_factory, "rodcad-builds"))


#: Test modules that read the same :class:`BuildStore` build with CAD run on one
#: pytest-xdist worker, one after the other (on two workers at once one would wait, idle, for
#: the other's build): module -> the module whose worker runs it too.
SAME_WORKER = {"tests/test_build_cad.py": "tests/test_asprinted.py",  # the semicircle with CAD
               "tests/test_view.py": "tests/test_asprinted.py",  # its view
               "tests/test_netprint.py": "tests/test_net_build.py",  # the V net with CAD
               "tests/test_view_net_cad.py": "tests/test_net_build.py"}  # its view


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadscope`` with the modules of :data:`SAME_WORKER` in one scope."""
    if config.getvalue("dist") != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class SharedBuildScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            scope = super()._split_scope(nodeid)
            return SAME_WORKER.get(scope, scope)

    return SharedBuildScheduling(config, log)


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
