"""The public Python API (README's "From Python"): ``import rodcad`` is light, and load,
design_from, build, write and run do what ``rodcad build`` does, for a chain and a net."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rodcad

ROOT = Path(__file__).resolve().parents[1]
ARC = {"design": 1, "name": "arc", "anchors": [[0, 0], [200, 0]], "target": {"form": "semicircle"}}


def test_import_rodcad_does_not_load_the_cad_kernel():
    out = subprocess.run([sys.executable, "-c", "import sys, rodcad; print('build123d' in sys.modules, "
                          "'OCP' in sys.modules)"], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert out.returncode == 0 and out.stdout.split() == ["False", "False"], out.stderr


def test_a_chain_from_python_objects_built_and_written(tmp_path):
    design = rodcad.design_from(ARC)
    assert isinstance(design, rodcad.Design) and rodcad.kind_of(design) == "chain"
    result = rodcad.build(design, cad=False)
    assert isinstance(result, rodcad.BuildResult) and result.ok
    pts = np.asarray(result.equilibrium.points)
    assert pts.shape == (result.n + 1, 2)
    np.testing.assert_allclose(pts[[0, -1]], [[0, 0], [200, 0]], atol=1e-9)
    data = rodcad.write(result, tmp_path / "arc")
    written = json.loads((tmp_path / "arc" / "design.json").read_text(encoding="utf-8"))
    assert written["simulated"]["points"] == data["simulated"]["points"]
    np.testing.assert_allclose(written["simulated"]["points"], pts, atol=1e-9)
    for name in ("report.md", "preview.png", "view.html", "assembly.glb"):
        assert (tmp_path / "arc" / name).is_file(), name


def test_run_is_build_then_write_as_the_command_line_does(tmp_path):
    design = rodcad.load(ROOT / "examples" / "semicircle.yaml")
    r = rodcad.run(design, tmp_path / "semi", cad=False)
    assert isinstance(r, rodcad.Run) and r.kind == "chain" and r.ok and r.outdir == tmp_path / "semi"
    from rodcad.cli import main

    assert main(["build", str(ROOT / "examples" / "semicircle.yaml"), "-o", str(tmp_path / "cli"), "--no-cad",
                 "-q"]) == 0
    ours = json.loads((tmp_path / "semi" / "design.json").read_text(encoding="utf-8"))
    theirs = json.loads((tmp_path / "cli" / "design.json").read_text(encoding="utf-8"))
    assert ours["simulated"]["points"] == theirs["simulated"]["points"]
    assert [rod["mass"] for rod in ours["rods"]] == [rod["mass"] for rod in theirs["rods"]]


def test_bad_python_input_names_the_key():
    with pytest.raises(rodcad.InputError) as err:
        rodcad.design_from({**ARC, "anchors": [[0, 0]]}, name="mine.yaml")
    text = str(err.value)
    assert re.search(r"mine\.yaml:\d+:\d+: anchors: ", text), text  # FILE:LINE:COL: key, as the CLI prints


def test_a_net_through_the_same_functions(tmp_path):
    net = {"design": 1, "name": "v", "net": {"nodes": [[0, 0, 0], [60, 0, -30], [120, 0, 0]],
                                               "edges": [[0, 1], [1, 2]], "anchored": [0, 2]}}
    design = rodcad.design_from(net)
    assert rodcad.kind_of(design) == "net"
    result = rodcad.build(design, cad=False)
    assert isinstance(result, rodcad.NetBuild)
    data = rodcad.write(result, tmp_path / "v")
    assert (tmp_path / "v" / "design.json").is_file() and "net" in data
    assert len(data["net"]["nodes"]) == 3
