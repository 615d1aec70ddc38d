"""Output folders: rodcad replaces only what it wrote, and a failed or killed run leaves
nothing behind."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from rodcad.cli import main
from rodcad.outdir import MARKER, OutputFolderError, check_output_folder, staged_output

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = str(ROOT / "examples" / "catenary.yaml")


def _build(out, capsys) -> tuple[int, str]:
    code = main(["build", EXAMPLE, "-o", str(out), "--no-cad", "-q"])
    return code, capsys.readouterr().err


def test_an_existing_file_is_never_replaced(tmp_path, capsys):
    out = tmp_path / "out"
    out.write_text("my notes")
    code, err = _build(out, capsys)
    assert code == 2 and "exists and is not a folder" in err and "Traceback" not in err
    assert out.read_text() == "my notes"


def test_a_folder_rodcad_did_not_write_is_never_replaced(tmp_path, capsys):
    out = tmp_path / "photos"
    out.mkdir()
    (out / "cat.jpg").write_bytes(b"\xff\xd8")
    code, err = _build(out, capsys)
    assert code == 2 and "rodcad did not write" in err
    assert [p.name for p in out.iterdir()] == ["cat.jpg"]


def test_an_earlier_output_is_replaced_and_marked(tmp_path, capsys):
    out = tmp_path / "out"
    assert _build(out, capsys)[0] == 0
    assert (out / MARKER).is_file() and (out / "design.json").is_file()
    (out / "stale.txt").write_text("from an older run")
    assert _build(out, capsys)[0] == 0
    assert not (out / "stale.txt").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no staging left


@pytest.mark.parametrize("bad", [".", "..", "in/a/file", "x" * 300, "/proc/rodcad"])
def test_impossible_destinations_are_bad_input(tmp_path, monkeypatch, capsys, bad):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "in").write_text("a file, not a folder")
    before = sorted(p.name for p in tmp_path.iterdir())
    code, err = _build(bad, capsys)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    with pytest.raises(OutputFolderError):
        check_output_folder(bad)


def test_the_staging_folder_of_a_killed_run_is_removed_by_the_next(tmp_path):
    out = tmp_path / "out"
    dead = 2**22 + 12345  # above the default pid_max: no such process
    stale = tmp_path / f".out.tmp-{dead}-abc"
    stale.mkdir()
    (stale / "design.json").write_text("{}")
    mine = tmp_path / f".out.tmp-{os.getpid()}-keep"  # a live process's staging folder stays
    mine.mkdir()
    with staged_output(out) as tmp:
        (tmp / "design.json").write_text("{}")
    assert not stale.exists() and mine.exists() and (out / "design.json").exists()


def test_a_failed_run_removes_its_staging_folder(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(RuntimeError):
        with staged_output(out) as tmp:
            (tmp / "design.json").write_text("{}")
            raise RuntimeError("boom")
    assert sorted(p.name for p in tmp_path.iterdir()) == []
