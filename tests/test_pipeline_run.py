"""``rodcad.pipeline.run``: every kind of design (a chain, a chandelier, a net) through the
same two steps, build then write, into OUTDIR or, when the build misses its tolerance,
OUTDIR.best-fit beside it; ``rodcad build`` calls it (tests/test_build.py, test_net_build.py
and test_chandelier.py check what the command prints and writes)."""

from __future__ import annotations

import json
from pathlib import Path

from rodcad import pipeline
from rodcad.design.loader import load_design
from rodcad.pipeline.net import NetBuild
from rodcad.results import BuildResult, ChandelierBuild

ROOT = Path(__file__).resolve().parents[1]

V_NET = ("design: 1\nname: v\nnet:\n  nodes: [[0, 0, 0], [45, 0, -50], [95, 0, 0]]\n"
         "  edges: [[0, 1], [1, 2]]\n  anchored: [0, 2]\n")

#: Two chains on a frame, one of them a catenary they can reach exactly.
CHANDELIER = ("design: 1\nname: two\ncatalog: pla-pinned\nchandelier: {pattern: explicit, chains: [\n"
              "  {anchors: [[0, 0, 0], [150, 0, 0]], target: {form: arc, sag: 50}},\n"
              "  {anchors: [[0, 50, 0], [0, 200, 20]], target: {form: catenary, length: 220}}]}\n")


def _written(run: pipeline.Run) -> dict:
    return json.loads((run.outdir / "design.json").read_text(encoding="utf-8"))


def test_a_chain_goes_to_outdir_or_to_its_best_fit(tmp_path):
    """The fixed menu's semicircle hangs 1.8 % off its circle: within its own 2 % it goes to
    OUTDIR; within 0.5 % it misses and goes to OUTDIR.best-fit, OUTDIR left alone."""
    text = (ROOT / "examples" / "semicircle-menu.yaml").read_text(encoding="utf-8")
    out = tmp_path / "out"
    r = pipeline.run(load_design(tmp_path / "d.yaml", text=text), out, cad=False)
    assert r.kind == "chain" and r.ok and r.outdir == out and isinstance(r.result, BuildResult)
    assert _written(r) == json.loads(json.dumps(r.data)) and (out / "report.md").is_file()
    miss = pipeline.run(load_design(tmp_path / "d.yaml", text=text.replace("tolerance: 0.02", "tolerance: 0.005")),
                        tmp_path / "miss", cad=False)
    assert miss.kind == "chain" and not miss.ok and not (tmp_path / "miss").exists()
    assert miss.outdir == tmp_path / "miss.best-fit" and _written(miss)["meets_tolerance"] is False


def test_a_chandelier_and_a_net_take_the_same_steps(tmp_path):
    d = load_design(tmp_path / "two.yaml", text=CHANDELIER)
    assert pipeline.kind_of(d) == "chandelier"
    r = pipeline.run(d, tmp_path / "two", cad=False)
    assert r.kind == "chandelier" and isinstance(r.result, ChandelierBuild)
    assert r.ok == r.result.meets_tolerance == _written(r)["meets_tolerance"]
    assert r.outdir == tmp_path / ("two" if r.ok else "two.best-fit")
    assert [c["name"] for c in _written(r)["chains"]] == ["chain_01", "chain_02"]
    d = load_design(tmp_path / "v.yaml", text=V_NET)
    assert pipeline.kind_of(d) == "net"
    r = pipeline.run(d, tmp_path / "v", cad=False)
    assert r.kind == "net" and r.ok and isinstance(r.result, NetBuild) and r.result.solids is None
    assert r.outdir == tmp_path / "v" and len(_written(r)["net"]["rods"]) == 2
    assert sorted(p.name for p in r.outdir.iterdir()) == [".rodcad-output", "assembly.glb", "design.json", "preview.png", "report.md", "view.html"]


#: A chain the pinned catalog hangs exactly: a few seconds to design.
CHAIN = ("design: 1\nname: arc\ncatalog: pla-pinned\nanchors: [[0, 0], [150, 0]]\n"
         "target: {form: catenary, length: 200}\n")


def test_a_design_without_cad_never_loads_the_cad_kernel(tmp_path):
    """``rodcad build design.yaml --no-cad`` imports neither build123d nor OCP (several seconds
    on 2 cores: a small net's design takes less) for a net, a chain or a chandelier: the
    pipeline package imports each kind's module when first asked, each imports the kernel only
    where it builds solids, and the design, report and 3D view need no kernel."""
    import subprocess
    import sys

    (tmp_path / "v.yaml").write_text(V_NET, encoding="utf-8")
    (tmp_path / "arc.yaml").write_text(CHAIN, encoding="utf-8")
    code = ("import sys\nfrom rodcad.cli import main\n"
            f"for name in ('v', 'arc'):\n"
            f"    rc = main(['build', {str(tmp_path)!r} + '/' + name + '.yaml', '--no-cad', '-q', '-o', "
            f"{str(tmp_path)!r} + '/out-' + name])\n"
            "    print('loaded:', rc, 'build123d' in sys.modules, 'OCP' in sys.modules)\n"
            "import rodcad.pipeline.chandelier\n"
            "print('loaded:', 'build123d' in sys.modules, 'OCP' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    loaded = [line.split()[1:] for line in out.stdout.splitlines() if line.startswith("loaded:")]
    assert loaded == [["0", "False", "False"]] * 2 + [["False", "False"]], out.stdout + out.stderr
    for name in ("v", "arc"):
        assert (tmp_path / f"out-{name}" / "design.json").is_file() and (tmp_path / f"out-{name}" / "view.html").is_file()
