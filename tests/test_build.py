"""`rodcad build` and `rodcad simulate` end to end (without CAD; CAD is in test_build_cad.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from optimize import solve_equilibrium
from rodcad import pipeline
from rodcad.catalog.massrange import mass_info
from rodcad.cli import main
from expected_exits import EXPECTED_EXIT, built_folder
from rodcad.design.loader import load_design
from rodcad.outdir import MARKER

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted(p for p in (ROOT / "examples").glob("*.yaml") if p.stem not in ("chain", "chandelier")
                  and "\nnet:" not in p.read_text())  # nets: tests/test_net_build.py


def check_contract(data: dict, n_rods: int | None = None) -> None:
    """design.json has contract.md's keys and shapes, and its numbers agree with each other."""
    for key in ("name", "units", "method", "seed", "time_s", "anchors", "target", "rods", "simulated", "error",
                "anchor_limits_deg", "curve", "print", "bill_of_materials"):
        assert key in data, key
    assert data["print"]["infill"] == 1.0 and data["print"]["density"] > 0
    assert data["units"]["length"] == "mm" and data["units"]["mass"] == "g"
    n = len(data["rods"])
    if n_rods is not None:
        assert n == n_rods
    assert len(data["target"]["points"]) == n + 1 and len(data["simulated"]["points"]) == n + 1
    for i, rod in enumerate(data["rods"]):
        assert rod["index"] == i and set(rod) >= {"type", "length", "mass", "com", "limits_deg", "curvature", "params"}
        assert rod["params"]["length"] == rod["length"] and rod["params"]["curvature"] == rod["curvature"]
        assert (rod["limits_deg"] is None) == (i == n - 1)
    sim = data["simulated"]
    assert len(sim["angles_deg"]) == n and len(sim["reaction"]) == 2
    assert isinstance(sim["stable"], bool) and sim["kkt_residual"] < 1e-8
    pts = np.array(sim["points"])
    np.testing.assert_allclose(pts[[0, -1]], data["anchors"], atol=1e-8)
    # rods have their lengths in the simulated shape
    np.testing.assert_allclose(np.hypot(*np.diff(pts, axis=0).T), [r["length"] for r in data["rods"]],
                               rtol=1e-9)
    err = np.hypot(*(pts - np.array(data["target"]["points"])).T)
    assert data["error"]["max_mm"] == pytest.approx(err.max(), rel=1e-9, abs=1e-12)
    assert data["error"]["mean_mm"] == pytest.approx(err.mean(), rel=1e-9, abs=1e-12)
    span = math.dist(*data["anchors"])
    assert data["error"]["max_rel_span"] == pytest.approx(err.max() / span, rel=1e-9, abs=1e-15)
    curve = data["curve"]
    assert curve["rel_span"] == pytest.approx(curve["max_mm"] / span, rel=1e-9)
    if not any(r["curvature"] for r in data["rods"]):  # straight rods: the centreline is the chain
        assert curve["max_mm"] == pytest.approx(data["discretisation"]["hanging_curve_error_mm"], rel=1e-9)


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
def test_every_example_builds_without_cad(example, build_store):
    # the build is shared with tests/test_determinism.py (once per session)
    code, out, summary = build_store.cli_build(example, "--no-cad", "-q")
    assert code == EXPECTED_EXIT.get(example.stem, 0)
    out = built_folder(out, code)
    assert {p.name for p in out.iterdir()} == {"design.json", "report.md", "preview.png", "preview.svg", "assembly.glb",
                                               "view.html", MARKER}
    data = json.loads((out / "design.json").read_text())
    check_contract(data)
    # the simulated shape is the equilibrium of the rods listed, re-solved independently
    d = load_design(example)
    rods = data["rods"]
    lim = np.array([[-np.inf if r["limits_deg"][0] is None else math.radians(r["limits_deg"][0]),
                     np.inf if r["limits_deg"][1] is None else math.radians(r["limits_deg"][1])]
                    for r in rods[:-1]]).reshape(-1, 2)
    ends = np.array([[-np.inf, np.inf] if e is None else
                     [-np.inf if e[0] is None else math.radians(e[0]), np.inf if e[1] is None else math.radians(e[1])]
                     for e in data["anchor_limits_deg"]])  # the anchor fixture's stops (the heart)
    eq = solve_equilibrium([r["length"] for r in rods], [r["mass"] for r in rods], *d.anchors,
                           com=[r.get("com_rod_frame", r["com"]) for r in rods],  # rods[].com: the hole frame
                           limits=lim if len(rods) > 1 else None, end_limits=ends)
    np.testing.assert_allclose(eq.points, data["simulated"]["points"], atol=1e-6 * d.span)
    # masses are within what each rod can be made to weigh (a catalog type's range, or a rod
    # printed to order's own)
    for r in rods:
        lo, hi = r["mass_range"]
        assert lo * (1 - 1e-9) <= r["mass"] <= hi * (1 + 1e-9)
        if r["type"] in d.catalog:  # a type's range, shifted by the joint hardware that hangs on the rod
            hw = r.get("hardware") or {}
            shift = r["mass"] - hw["printed_mass"] if hw else 0.0  # its metal
            rng = np.asarray(mass_info(d.catalog[r["type"]]).mass_range)
            assert lo - rng[0] == pytest.approx(hi - rng[1], abs=1e-9)  # one shift for both ends
            assert shift - 0.5 <= lo - rng[0] <= shift + 0.5  # its metal, and its holes' plastic
    report = (out / "report.md").read_text()
    for heading in ("## Inputs", "## Result", "## Rods", "## Bill of materials", "## Print settings",
                    "## Printing and assembly"):
        assert heading in report
    assert (out / "preview.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "<svg" in (out / "preview.svg").read_text()[:500]
    assert "shape error" in summary and str(out) in summary


def test_reachable_catenary_example_is_exact():
    d = load_design(ROOT / "examples" / "catenary.yaml")
    r = pipeline.build(d, cad=False)
    assert r.distance.max_rel_span < 1e-6 and r.chain_design.result.exact
    assert r.equilibrium.stable and r.unique


def test_same_seed_same_design_json(tmp_path):
    ex = ROOT / "examples" / "semicircle-menu.yaml"
    outs = []
    for k in range(2):
        out = tmp_path / f"o{k}"
        assert main(["build", str(ex), "-o", str(out), "--no-cad", "-q", "--method", "pso", "--seed", "3"]) == 0
        data = json.loads((out / "design.json").read_text())
        data.pop("time_s")
        data["inverse"].pop("time_s")
        outs.append(data)
    assert outs[0] == outs[1]
    assert outs[0]["method"] == "pso" and outs[0]["seed"] == 3


def test_failed_run_leaves_outdir_as_it_was(tmp_path, monkeypatch, capsys):
    ex = ROOT / "examples" / "semicircle-menu.yaml"
    out = tmp_path / "out"
    assert main(["build", str(ex), "-o", str(out), "--no-cad", "-q"]) == 0  # an earlier output
    (out / "mine.txt").write_text("keep me")
    before = sorted(p.name for p in out.iterdir())

    def boom(*a, **k):
        raise RuntimeError("disk full")

    monkeypatch.setattr("rodcad.pipeline.chain.plot_chain", boom)
    assert main(["build", str(ex), "-o", str(out), "--no-cad", "-q"]) == 1  # one line, no traceback
    assert "internal error (RuntimeError: disk full)" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no temporary folder left behind
    monkeypatch.undo()
    assert main(["build", str(ex), "-o", str(out), "--no-cad", "-q"]) == 0  # an earlier output: replaced
    assert not (out / "mine.txt").exists() and (out / "design.json").exists()


def test_missed_tolerance_exits_1_and_keeps_outdir(tmp_path, capsys):
    """A design file's ``tolerance`` overrides the default: the fixed menu's semicircle hangs
    1.8 % off (its straight rods cut the circle), within its own 2 % but not within 0.5 %:
    exit 1, OUTDIR untouched, the best fit beside it and one line saying what limits it."""
    design = tmp_path / "d.yaml"
    design.write_text((ROOT / "examples" / "semicircle-menu.yaml").read_text().replace("tolerance: 0.02",
                                                                                        "tolerance: 0.005"))
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--no-cad", "-q"]) == 1
    assert not out.exists()
    best = tmp_path / "out.best-fit"
    data = json.loads((best / "design.json").read_text())
    assert data["meets_tolerance"] is False and data["tolerance"] == 0.005
    assert data["curve"]["rel_size"] > 0.005
    err = capsys.readouterr().err
    assert "(tolerance 0.5 %)" in err and "miss the curve" in err and "shorter rods" in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_the_default_tolerance_is_one_percent_of_the_targets_size(tmp_path, capsys):
    """No ``tolerance``: rods hanging more than 1 % of the target's size off its curve exit 1;
    the example's own 2 % lets the same design through."""
    text = (ROOT / "examples" / "semicircle-menu.yaml").read_text()
    design = tmp_path / "d.yaml"
    design.write_text(text.replace("tolerance: 0.02\n", ""))
    out = tmp_path / "out"
    assert main(["build", str(design), "-o", str(out), "--no-cad", "-q"]) == 1
    data = json.loads((tmp_path / "out.best-fit" / "design.json").read_text())
    assert data["tolerance"] == 0.01 and 0.01 < data["curve"]["rel_size"] < 0.02
    assert "tolerance 1 %" in capsys.readouterr().err
    design.write_text(text)
    assert main(["build", str(design), "-o", str(out), "--no-cad", "-q"]) == 0
    assert json.loads((out / "design.json").read_text())["meets_tolerance"] is True


def test_rod_count_constraint_and_fixed_rod(tmp_path):
    base = (ROOT / "examples" / "semicircle-menu.yaml").read_text().replace("pla-weighted", "pla-pinned")
    d = load_design(tmp_path / "d.yaml", text=base + "constraints:\n  lengths: [30]\n"
                    "  fixed:\n    - {index: 2, type: free-30, mass: 3.0}\n")
    r = pipeline.build(d, cad=False)
    assert set(r.lengths) == {30.0}
    # the fixed mass is the rod's own (its type's, without the joint hardware that hangs on it)
    assert r.type_names[2] == "free-30" and r.printed_masses[2] == pytest.approx(3.0, rel=1e-6)
    assert r.masses[2] > 3.0
    with pytest.raises(Exception) as err:
        pipeline.build(load_design(tmp_path / "d.yaml", text=base + "constraints:\n  rods: 3\n"), cad=False)
    assert "constraints.rods" in str(err.value) and "not 3" in str(err.value)


def test_simulate_json_matches_the_solver(capsys):
    ex = ROOT / "examples" / "chain.yaml"
    assert main(["simulate", str(ex), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    d = load_design(ex)
    assert [r["type"] for r in data["rods"]] == [r.type for r in d.chain]
    pts = np.array(data["simulated"]["points"])
    np.testing.assert_allclose(pts[[0, -1]], d.anchors, atol=1e-9)
    # joints 3 and 4 (between straight-30 rods) rest on their straight stops (computed from the
    # solids to 0.005 deg): the middle hangs as one bar
    ang = np.array(data["simulated"]["angles_deg"])
    for j in (3, 4):
        hi = data["rods"][j]["limits_deg"][1]
        assert abs(hi) < 0.01 and ang[j + 1] - ang[j] == pytest.approx(hi, abs=1e-7)
    assert data["simulated"]["stable"]


def test_simulate_table_and_build_needs_a_target(tmp_path, capsys):
    ex = ROOT / "examples" / "chain.yaml"
    assert main(["simulate", str(ex)]) == 0
    assert "straight-30" in capsys.readouterr().out
    assert main(["build", str(ex), "-o", str(tmp_path / "o")]) == 2
    assert "no 'target'" in capsys.readouterr().err


def test_chandelier_example_builds_without_cad(build_store):
    # the session's build (tests/test_preview.py inspects its figures)
    code, out, summary = build_store.cli_build(ROOT / "examples" / "chandelier.yaml", "--no-cad", "-q")
    assert code == 0
    data = json.loads((out / "design.json").read_text())
    assert len(data["chains"]) >= 6 and all(len(c["rods"]) >= 12 for c in data["chains"])
    for ch in data["chains"]:
        pts3 = np.array(ch["simulated"]["points_3d"])
        a3, b3 = np.array(ch["anchors_3d"])
        np.testing.assert_allclose(pts3[[0, -1]], [a3, b3], atol=1e-6)
        # every joint lies in the vertical plane through the anchors
        n = np.cross(b3 - a3, [0, 0, 1.0])
        assert np.max(np.abs((pts3 - a3) @ (n / np.linalg.norm(n)))) < 1e-9
        assert ch["error"]["max_rel_span"] < 1e-3
    assert data["bill_of_materials"]["n_rods"] == sum(len(c["rods"]) for c in data["chains"])
    assert (out / "preview.png").exists() and "chain_06" in summary


def test_chandelier_with_a_target_per_chain_and_its_validation(tmp_path):
    text = """\
design: 1
name: two
catalog: pla-pinned
chandelier:
  pattern: explicit
  chains:
    - anchors: [[0, 0, 0], [150, 0, 0]]
      target: {form: arc, sag: 50}
    - anchors: [[0, 50, 0], [0, 200, 20]]
      target: {form: catenary, length: 220}
"""
    d = load_design(tmp_path / "d.yaml", text=text)
    b = pipeline.build_chandelier(d, cad=False)
    assert [c.name for c in b.result.chains] == ["chain_01", "chain_02"]
    assert b.result.chains[1].distance.max_rel_span < 1e-6  # a catenary is reachable
    from rodcad.errors import InputError

    bad = text.replace("{form: arc, sag: 50}", "{form: arc, sags: 50}").replace("[0, 200, 20]", "[0, 50, 90]")
    with pytest.raises(InputError) as err:
        load_design(tmp_path / "d.yaml", text=bad)
    got = "\n".join(map(str, err.value.problems))
    assert "d.yaml:8:27: chandelier.chains[0].target.sags: unknown key 'sags' (did you mean 'sag'?)" in got
    with pytest.raises(InputError) as err:  # anchors straight above each other: no vertical plane
        load_design(tmp_path / "d.yaml", text=text.replace("[0, 200, 20]", "[0, 50, 90]"))
    (p,) = err.value.problems
    assert p.key == "chandelier" and p.line == 5 and "above" in p.message


def test_readme_first_example_is_the_default_catalogs_semicircle(tmp_path):
    """README's first command: the paper's semicircle from the default catalog (rods printed to
    order, each an arc of the circle), within 0.1 % of its span of the circle."""
    ex = ROOT / "examples" / "semicircle.yaml"
    assert "catalog:" not in ex.read_text()  # the default catalog
    assert "rodcad build examples/semicircle.yaml" in (ROOT / "README.md").read_text()
    out = tmp_path / "semi"
    assert main(["build", str(ex), "-o", str(out), "--no-cad", "-q"]) == 0
    data = json.loads((out / "design.json").read_text())
    assert data["catalog"] == "pla-parametric"
    assert all(r["curvature"] == pytest.approx(1 / 100, rel=1e-3) for r in data["rods"])  # arcs of the circle
    assert data["curve"]["rel_span"] < 1e-3
    report = (out / "report.md").read_text()
    assert "pla-parametric" in report and "hang freely" in report


def test_semicircle_menu_example_rests_on_curve_stops_and_says_so(tmp_path):
    out = tmp_path / "semi"
    assert main(["build", str(ROOT / "examples" / "semicircle-menu.yaml"), "-o", str(out), "--no-cad", "-q"]) == 0
    data = json.loads((out / "design.json").read_text())
    disc = data["discretisation"]
    assert disc["added_stops"] and all(15.0 <= s["deg"] <= 25.0 for s in disc["added_stops"])
    assert data["error"]["max_rel_span"] < 1e-9  # exact on its (refitted) joints
    assert disc["hanging_curve_error_mm"] == pytest.approx(disc["curve_error_mm"], abs=1e-6)
    assert disc["hanging_curve_error_mm"] < 5.0
    report = (out / "report.md").read_text()
    assert "rest on stops" in report and "hangs within" in report


CHANDELIER_CONSTRAINED = """\
design: 1
name: two
catalog: pla-pinned
chandelier:
  pattern: explicit
  chains:
    - anchors: [[0, 0, 0], [150, 0, 0]]
    - anchors: [[0, 50, 0], [0, 180, 20]]
  target: {form: catenary, length: 220}
constraints:
  lengths: [20]
  rods: RODS
  fixed: [{index: INDEX, type: free-20, mass: MASS}]
"""


def _free20_mass() -> float:
    lo, hi = mass_info(load_design(ROOT / "examples" / "chandelier.yaml").catalog["free-20"]).mass_range
    return round(0.5 * (lo + hi), 4)


def test_chandelier_chains_honour_rod_count_and_fixed_rods(tmp_path):
    m = _free20_mass()
    text = CHANDELIER_CONSTRAINED.replace("RODS", "11").replace("INDEX", "3").replace("MASS", str(m))
    b = pipeline.build_chandelier(load_design(tmp_path / "d.yaml", text=text), cad=False)
    assert len(b.result.chains) == 2
    for ch, r in zip(b.result.chains, b.chains):  # every chain: 11 rods, rod 3 a free-20 of the given mass
        assert len(ch.type_names) == 11 and ch.type_names[3] == "free-20"
        # the fixed mass is the rod's own, without the joint hardware that hangs on it
        assert r.printed_masses[3] == pytest.approx(m, rel=1e-8)
        assert ch.masses[3] == pytest.approx(m + r.attached[3].sum(), rel=1e-8)
        assert any("fixed by the design" in n for n in ch.design.plan.notes)
        assert ch.equilibrium.success and ch.distance.max_rel_span < 0.05


def test_chandelier_constraints_that_cannot_apply_point_at_the_key(tmp_path, capsys):
    m = str(_free20_mass())
    bad_count = CHANDELIER_CONSTRAINED.replace("RODS", "7").replace("INDEX", "3").replace("MASS", m)
    path = tmp_path / "d.yaml"
    path.write_text(bad_count)
    assert main(["build", str(path), "-o", str(tmp_path / "out"), "--no-cad", "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{path}:12:9: constraints.rods: chain_01: the allowed rod lengths lay 11 rods" in err
    assert "Traceback" not in err and not (tmp_path / "out").exists()
    bad_index = CHANDELIER_CONSTRAINED.replace("  rods: RODS\n", "").replace("INDEX", "30").replace("MASS", m)
    path.write_text(bad_index)
    assert main(["build", str(path), "-o", str(tmp_path / "out"), "--no-cad", "-q"]) == 2
    err = capsys.readouterr().err
    for name in ("chain_01", "chain_02"):  # every chain's problem, at once
        assert f"{path}:12:19: constraints.fixed[0].index: {name}: the chain has 11 rods" in err
