"""Design files: validation with FILE:LINE:COL, every problem at once, the published schema."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rodcad.catalog.massrange import mass_info
from rodcad.design.loader import load_design
from rodcad.design.spec import design_schema
from rodcad.errors import InputError

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

GOOD = """\
design: 1
name: t
catalog: pla-pinned
anchors: [[0, 0], [200, 0]]
target: {form: arc, sag: 60}
"""


def problems(text: str, name: str = "d.yaml") -> list[str]:
    with pytest.raises(InputError) as err:
        load_design(name, text=text)
    return [str(p) for p in err.value.problems]


def test_good_design_loads_with_defaults():
    d = load_design("d.yaml", text=GOOD)
    assert d.name == "t" and d.catalog.name == "pla-pinned" and d.method == "refine" and d.seed == 0
    assert d.cad and d.tolerance is None and d.chain is None
    np.testing.assert_allclose(d.target_curve[[0, -1]], [[0, 0], [200, 0]])
    assert d.span == 200


def test_every_problem_is_reported_at_once_with_line_column_and_key():
    text = """\
design: 1
name: bad name
catalog: pla-pinned
anchors: [[0, 0], [200]]
target:
  form: semicircel
chain:
  - {type: free-3, mass: 2}
  - {type: free-30, mass: -1}
constraints:
  types: [straigth-30]
methd: refine
"""
    got = problems(text)
    assert "d.yaml:2:7: name: 'bad name' is not a name" in got[0]
    joined = "\n".join(got)
    assert "d.yaml:4:19: anchors[1]: expected at least 2 items" in joined
    assert "d.yaml:6:9: target.form: unknown value 'semicircel' (did you mean 'semicircle'?)" in joined
    assert "d.yaml:8:12: chain[0].type: unknown rod type 'free-3'" in joined
    assert "d.yaml:9:27: chain[1].mass: must be greater than 0 g" in joined
    assert "d.yaml:11:11: constraints.types[0]: unknown rod type 'straigth-30' in catalog 'pla-pinned' " \
           "(did you mean 'straight-30'?)" in joined
    assert "d.yaml:12:1: methd: unknown key 'methd' (did you mean 'method'?)" in joined
    # sorted by position
    lines = [int(p.split(":")[1]) for p in got]
    assert lines == sorted(lines)


def test_target_parameters_are_checked_against_the_form():
    got = problems(GOOD.replace("{form: arc, sag: 60}", "{form: triangle, sides: 4}"))
    assert any(":5:" in p and "target.sides: a triangle target takes no 'sides'" in p for p in got)
    assert any("target: a triangle target needs 'depth'" in p for p in got)
    got = problems(GOOD.replace("{form: arc, sag: 60}", "{form: function, y: 'x +* 2'}"))
    assert len(got) == 1 and "target.y: cannot make the function target" in got[0] and ":5:" in got[0]


def test_catalog_reference_is_resolved_next_to_the_design_and_reported_when_missing(tmp_path):
    cat = (ROOT / "catalogs" / "pla-pinned.yaml").read_text()
    (tmp_path / "mine.yaml").write_text(cat.replace("name: pla-pinned", "name: mine"))
    design = tmp_path / "d.yaml"
    design.write_text(GOOD.replace("catalog: pla-pinned", "catalog: mine.yaml"))
    assert load_design(design).catalog.name == "mine"
    got = problems(GOOD.replace("catalog: pla-pinned", "catalog: pla-pined"))
    assert len(got) == 1 and got[0].startswith("d.yaml:3:10: catalog: 'pla-pined'")
    assert "did you mean 'pla-pinned'" in got[0]


def test_problems_inside_the_catalog_point_into_the_catalog_file(tmp_path):
    cat = (ROOT / "catalogs" / "pla-pinned.yaml").read_text()
    (tmp_path / "broken.yaml").write_text(cat.replace("knuckle_radius: 3.2", "knuckle_radius: -3.2"))
    design = tmp_path / "d.yaml"
    design.write_text(GOOD.replace("catalog: pla-pinned", "catalog: broken.yaml"))
    with pytest.raises(InputError) as err:
        load_design(design)
    assert any("broken.yaml" in p.file and "knuckle_radius" in p.key for p in err.value.problems)


def test_explicit_chain_reach_and_fixed_rods_are_checked():
    chain = GOOD.replace("target: {form: arc, sag: 60}", "chain:\n  - {type: free-30}\n  - {type: free-40}")
    got = problems(chain)
    assert len(got) == 1 and "anchors: the anchors are 200 mm apart but the chain is only 70 mm long" in got[0]
    d = load_design("d.yaml", text=chain.replace("[200, 0]", "[60, 0]"))
    assert [r.type for r in d.chain] == ["free-30", "free-40"]
    assert d.chain[0].mass == pytest.approx(mass_info(d.catalog["free-30"]).solid_mass)
    fixed = GOOD + "constraints:\n  fixed:\n    - {index: 0, type: free-30, mass: 500}\n" \
                   "    - {index: 0, type: free-40}\n"
    got = "\n".join(problems(fixed))
    assert "constraints.fixed[0].mass: 500 g is outside what type 'free-30' can be made to weigh" in got
    assert "constraints.fixed[1].index: rod 0 is already fixed by constraints.fixed[0]" in got


def test_no_target_and_no_chain_is_explained():
    got = problems(GOOD.replace("target: {form: arc, sag: 60}\n", ""))
    assert got == ["d.yaml:1:1: give a 'target' to design a chain for, an explicit 'chain' to simulate, or a 'net'"]


def test_every_example_validates():
    files = sorted(EXAMPLES.glob("*.yaml"))
    assert len(files) >= 6
    for f in files:
        load_design(f)


def test_published_schema_matches_the_validator_and_accepts_the_examples():
    jsonschema = pytest.importorskip("jsonschema")
    import yaml

    schema = design_schema()
    published = json.loads((EXAMPLES / "design.schema.json").read_text())
    assert published == schema, "regenerate with: rodcad schema design -o examples/design.schema.json"
    for f in sorted(EXAMPLES.glob("*.yaml")):
        jsonschema.validate(yaml.safe_load(f.read_text()), schema)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(yaml.safe_load(GOOD.replace("design: 1", "design: 1\nmethd: x")), schema)


#: The installed ``rodcad`` command's entry point (pyproject's [project.scripts]), as its script runs it.
COMMAND = [sys.executable, "-c", "import sys; from rodcad.cli import console_main; sys.argv[0] = 'rodcad'; "
           "sys.exit(console_main())"]


@pytest.mark.parametrize("entry", [[sys.executable, "-m", "rodcad.cli"], COMMAND], ids=["module", "command"])
def test_cli_bad_input_exits_2_with_no_traceback(tmp_path, entry):
    bad = tmp_path / "bad.yaml"
    bad.write_text(GOOD.replace("sag: 60", "sag: 60, colour: red"))
    proc = subprocess.run([*entry, "build", str(bad), "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert f"{bad}:5:" in proc.stderr and "target.colour" in proc.stderr
    assert not (tmp_path / "out").exists()


def test_keys_a_chandelier_does_not_use_are_refused():
    ring = ("design: 1\nname: r\ncatalog: pla-pinned\nanchors: [[0, 0], [200, 0]]\n"
            "chandelier: {pattern: ring, count: 2, radius: 100, target: {form: catenary, length: 240},\n"
            "             chains: [{anchors: [[0, 0, 0], [1, 0, 0]]}, {}]}\n")
    got = problems(ring)
    assert any(p.startswith("d.yaml:4:10: anchors: a chandelier takes no top-level 'anchors'") for p in got), got
    assert any("chandelier.chains[0].anchors: a ring chandelier places its chains itself" in p for p in got), got


def test_a_name_too_long_for_a_folder_is_refused():
    got = problems(f"design: 1\nname: {'a' * 5000}\ncatalog: pla-pinned\nanchors: [[0, 0], [200, 0]]\n"
                   "target: {form: catenary, length: 300}\n")
    assert got == ["d.yaml:2:7: name: 5000 characters long; keep it under 101"]


def test_the_command_ends_with_its_exit_code_and_everything_it_printed():
    """The installed command ends without unloading its modules (rodcad.cli.console_main): what
    it printed to a pipe arrives whole (the design schema, about 20 kB), then its exit code."""
    proc = subprocess.run([*COMMAND, "schema", "design"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["title"]
    proc = subprocess.run([*COMMAND, "build", "no-such-design.yaml"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and "no such design file" in proc.stderr
