"""Loading and validating rod catalogs: the shipped ones, the data model, and
one test per kind of mistake (exact message and position)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import jsonschema
import pytest
import yaml
from catalog_testutil import BASE, load, problems, write

from rodcad.catalog.loader import catalog_from_text, load_catalog, resolve_catalog
from rodcad.catalog.model import Catalog
from rodcad.catalog.paths import default_catalog_dir, shipped_catalogs
from rodcad.catalog.spec import catalog_schema
from rodcad.commands.catalog import schema_text
from rodcad.errors import InputError

SHIPPED = sorted(default_catalog_dir().glob("*.yaml"))


# --------------------------------------------------------------------------- shipped


def test_a_pla_catalog_is_shipped() -> None:
    assert "pla-pinned" in shipped_catalogs()
    cat = load_catalog("pla-pinned")
    assert cat.name == "pla-pinned"
    assert all(t.material.name == "PLA" and t.material.density == pytest.approx(1.24) for t in cat)
    assert cat.printer is not None and cat.printer.nozzle == 0.4


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_catalogs_load(path: Path) -> None:
    cat = load_catalog(path)
    assert len(cat) >= 1
    assert len(set(cat.names)) == len(cat.names)


def test_shipped_pla_types_and_pairs() -> None:
    cat = load_catalog("pla-pinned")
    assert cat.names[:3] == ["free-20", "free-30", "free-40"]
    assert {t.family for t in cat} >= {"free", "straight", "concave20", "concave40", "arc"}
    # One hinge layout for all: every ordered pair joins.
    assert len(cat.pairs()) == len(cat) ** 2
    arc = cat["arc-30"]
    assert arc.curvature == pytest.approx(0.02) and arc.geometry.half_angle_deg == pytest.approx(
        math.degrees(math.asin(0.3)))


def test_resolve_catalog_by_name_and_path(tmp_path: Path) -> None:
    shipped = default_catalog_dir() / "pla-pinned.yaml"
    assert resolve_catalog("pla-pinned") == shipped
    assert resolve_catalog("pla-pinned.yaml") == shipped
    own = write(tmp_path, BASE, "mine.yaml")
    assert resolve_catalog(own) == own
    assert resolve_catalog("mine", tmp_path) == tmp_path / "mine.yaml"
    with pytest.raises(InputError) as info:
        resolve_catalog("pla-pinne")
    assert str(info.value) == "pla-pinne:0:0: no such catalog file or shipped catalog (did you mean 'pla-pinned'?)"


# --------------------------------------------------------------------------- schema


def test_schema_file_is_up_to_date() -> None:
    path = default_catalog_dir() / "catalog.schema.json"
    assert path.read_text(encoding="utf-8") == schema_text(), (
        "catalogs/catalog.schema.json is stale: run `rodcad catalog schema -o catalogs/catalog.schema.json`")


def test_schema_is_valid_and_accepts_shipped_catalogs() -> None:
    schema = catalog_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    for path in SHIPPED:
        jsonschema.validate(yaml.safe_load(path.read_text()), schema, cls=jsonschema.Draft202012Validator)


@pytest.mark.parametrize(
    "edit",
    [
        lambda d: d["families"][0].update(colour="red"),
        lambda d: d["families"][0].update(length="thirty"),
        lambda d: d["defaults"]["joint"].update(layout="sideways"),
        lambda d: d["defaults"]["section"].update(height=-1),
        lambda d: d.pop("families"),
    ],
    ids=["unknown-key", "wrong-type", "bad-choice", "out-of-range", "missing-key"],
)
def test_schema_and_validator_reject_the_same_mistakes(tmp_path: Path, edit) -> None:
    doc = yaml.safe_load(BASE)
    edit(doc)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(doc, catalog_schema(), cls=jsonschema.Draft202012Validator)
    with pytest.raises(InputError):
        catalog_from_text(yaml.safe_dump(doc))


# --------------------------------------------------------------------------- model


def test_defaults_merge_key_by_key(tmp_path: Path) -> None:
    cat = load(tmp_path, BASE + """\
  - name: other
    length: 20
    section: {height: 10}
    joint: {knuckle_radius: 2.5}
    ends: {top_chamfer: 30, second: {bottom_chamfer: 45}}
""")
    sq, other = cat["sq-30"], cat["other-20"]
    assert sq.geometry.height == 12 and other.geometry.height == 10
    assert other.geometry.thickness == 8  # from defaults
    assert other.geometry.hinge.knuckle_radius == 2.5 and other.geometry.hinge.pin_diameter == 1.75
    assert other.geometry.first.top_chamfer == 30 and other.geometry.second.top_chamfer == 30
    assert other.geometry.first.bottom_chamfer == 0 and other.geometry.second.bottom_chamfer == 45
    # Built-in defaults.
    assert sq.scale == 1 and sq.curvature == 0 and sq.balls is None
    assert sq.geometry.hinge.layout == "tongue-fork"
    assert sq.geometry.first.setback == pytest.approx(0.2)
    assert sq.geometry.hinge.hole_diameter == pytest.approx(2.0)


def test_lists_expand_into_named_types(tmp_path: Path) -> None:
    cat = load(tmp_path, BASE.replace("    length: 30\n", """\
    length: [20, 25.5]
    scale: [1, 1.25]
    curvature: [0, -0.01]
"""))
    assert cat.names == [
        "sq-20-s1-k0", "sq-20-s1-k-0.01", "sq-20-s1.25-k0", "sq-20-s1.25-k-0.01",
        "sq-25.5-s1-k0", "sq-25.5-s1-k-0.01", "sq-25.5-s1.25-k0", "sq-25.5-s1.25-k-0.01",
    ]
    big = cat["sq-20-s1.25-k0"]
    assert big.geometry.height == 15 and big.geometry.thickness == 10
    assert big.geometry.hinge.knuckle_radius == pytest.approx(4.0)
    assert big.geometry.hinge.tongue_thickness == pytest.approx(3.5)
    assert big.geometry.hinge.pin_diameter == 1.75 and big.geometry.first.setback == pytest.approx(0.2)
    # Different scales have different hinges: they do not join.
    assert cat.can_join("sq-20-s1-k0", "sq-25.5-s1-k-0.01")
    assert not cat.can_join("sq-20-s1-k0", "sq-20-s1.25-k0")


def test_hinge_layouts_decide_which_pairs_join(tmp_path: Path) -> None:
    cat = load(tmp_path, BASE + """\
  - name: flip
    length: 30
    joint: {layout: fork-tongue}
""")
    assert cat.can_join("sq-30", "sq-30") and cat.can_join("flip-30", "flip-30")
    assert not cat.can_join("sq-30", "flip-30") and not cat.can_join("flip-30", "sq-30")
    assert [(a.name, b.name) for a, b in cat.pairs()] == [("sq-30", "sq-30"), ("flip-30", "flip-30")]


def test_catalog_lookup_suggests_names(tmp_path: Path) -> None:
    cat = load(tmp_path, BASE)
    assert isinstance(cat, Catalog) and "sq-30" in cat and cat.type("sq-30") is cat["sq-30"]
    with pytest.raises(KeyError, match=r"unknown rod type 'sq-3' \(did you mean 'sq-30'\?\)"):
        cat["sq-3"]


def test_yaml_merge_keys_and_plain_exponent_numbers(tmp_path: Path) -> None:
    cat = load(tmp_path, """\
catalog: 1
name: merged
families:
  - &base
    name: a
    length: 3e1
    section: {height: 12, thickness: 8}
    joint: {pin_diameter: 1.75, knuckle_radius: 3.2, tongue_thickness: 2.8}
    material: {density: 1.24, min_wall: 1.2}
  - <<: *base
    name: b
    length: 20
""")
    assert cat.names == ["a-30", "b-20"]


# --------------------------------------------------------------------------- mistakes

# Each case: catalog text and the exact problems (line, column, key, message).
MISTAKES = {
    "unknown key, did you mean": (
        BASE.replace("section: {height: 12, thickness: 8}", "section: {height: 12, thicknes: 8}"),
        [(4, 25, "defaults.section.thicknes", "unknown key 'thicknes' (did you mean 'thickness'?)")],
    ),
    "unknown key, no close match": (
        BASE + "    colour: red\n",
        [(10, 5, "families[0].colour", "unknown key 'colour' (expected one of: name, description, length, "
                                        "scale, curvature, stops, section, joint, ends, material, fill, balls)")],
    ),
    "unknown choice": (
        BASE.replace("knuckle_radius: 3.2,", "layout: tongue-fok, knuckle_radius: 3.2,"),
        [(5, 39, "defaults.joint.layout", "unknown value 'tongue-fok' (did you mean 'tongue-fork'?)")],
    ),
    "wrong type, number": (
        BASE.replace("length: 30", "length: thirty"),
        [(9, 13, "families[0].length", "expected a number, got a string ('thirty')")],
    ),
    "wrong type, quoted number": (
        BASE.replace("density: 1.24", "density: '1.24'"),
        [(6, 23, "defaults.material.density", "expected a number, got a string ('1.24')")],
    ),
    "wrong type, mapping": (
        BASE + "    joint: 3\n",
        [(10, 12, "families[0].joint", "expected a mapping, got a number (3)")],
    ),
    "wrong type, list item": (
        BASE.replace("length: 30", "length: [20, true]"),
        [(9, 18, "families[0].length[1]", "expected a number, got a boolean (true)")],
    ),
    "out of range": (
        BASE + "    ends: {top_chamfer: 95}\n",
        [(10, 25, "families[0].ends.top_chamfer", "must be between -60 deg and 80 deg (got 95)")],
    ),
    "must be positive": (
        BASE.replace("length: 30", "length: 0"),
        [(9, 13, "families[0].length", "must be greater than 0 mm and at most 1000 mm (got 0)")],
    ),
    "duplicate list value": (
        BASE.replace("length: 30", "length: [20, 30, 20]"),
        [(9, 22, "families[0].length[2]", "duplicate value 20 (also item 0)")],
    ),
    "duplicate key": (
        BASE + "    length: 40\n",
        [(10, 5, "families[0].length", "duplicate key 'length' (first given at line 9)")],
    ),
    "missing required key after defaults": (
        BASE.replace("    length: 30\n", ""),
        [(8, 5, "families[0]", "missing required key 'length' (give it in the family or under 'defaults')")],
    ),
    "missing top-level key": (
        "catalog: 1\nname: x\n",
        [(1, 1, "", "missing required key 'families'")],
    ),
    "unsupported format": (
        BASE.replace("catalog: 1", "catalog: 2"),
        [(1, 10, "catalog", "unsupported catalog format 2 (this rodcad reads format 1)")],
    ),
    "bad name": (
        BASE.replace("name: sq", "name: 'square rod'"),
        [(8, 11, "families[0].name", "'square rod' is not a name of letters, digits, '.', '_', '+' or '-'")],
    ),
    "duplicate family name": (
        BASE + "  - name: sq\n    length: 40\n",
        [(10, 11, "families[1].name", "duplicate family name 'sq' (also families[0])")],
    ),
    "duplicate type name": (
        BASE.replace("length: 30", "length: [30, 30.0000001]"),
        [(9, 18, "families[0].length[1]", "rod type name 'sq-30' is also made by family 'sq'")],
    ),
    "knuckle wider than the rod": (
        BASE + "    joint: {knuckle_radius: 5.8}\n",
        [(10, 29, "families[0].joint.knuckle_radius",
          "knuckle radius 5.8 mm + radial gap 0.4 mm is wider than the rod: it must stay below half the "
          "section height (6 mm)")],
    ),
    "knuckle from defaults, reported there for the family": (
        BASE.replace("knuckle_radius: 3.2", "knuckle_radius: 5.8"),
        [(5, 47, "defaults.joint.knuckle_radius",
          "knuckle radius 5.8 mm + radial gap 0.4 mm is wider than the rod: it must stay below half the "
          "section height (6 mm) (in family 'sq')")],
    ),
    "end face outside the hinge zone thinner than the wall": (
        BASE + "    joint: {knuckle_radius: 4.5}\n",
        [(10, 29, "families[0].joint.knuckle_radius",
          "knuckle radius 4.5 mm + radial gap 0.4 mm leaves 1.1 mm of end face between the hinge zone and "
          "the rod's edge (6 mm from the axis), less than the minimum wall 1.2 mm")],
    ),
    "wall thicker than half the section": (
        BASE + "    material: {min_wall: 4.5}\n",
        [(10, 26, "families[0].material.min_wall",
          "minimum wall 4.5 mm is thicker than half the section (4 mm): no room inside the rod")],
    ),
    "thin wall around the pin hole": (
        BASE + "    joint: {knuckle_radius: 2}\n",
        [(10, 29, "families[0].joint.knuckle_radius",
          "knuckle radius 2 mm leaves a wall of 1 mm around the 2 mm pin hole, less than the minimum wall 1.2 mm")],
    ),
    "fork prongs too thin": (
        BASE + "    joint: {tongue_thickness: 5.2}\n",
        [(10, 31, "families[0].joint.tongue_thickness",
          "tongue 5.2 mm + 2 layer gaps of 0.3 mm leave fork prongs 1.1 mm thick in a 8 mm thick rod, less "
          "than the minimum wall 1.2 mm")],
    ),
    "rod too short": (
        BASE.replace("length: 30", "length: [30, 8]"),
        [(9, 18, "families[0].length[1]",
          "length 8 mm is too short: the two hinge zones and a minimum wall need 8.4 mm")],
    ),
    "chamfers cut through the rod": (
        BASE.replace("length: 30", "length: 12") + "    ends: {top_chamfer: 60}\n",
        [(10, 25, "families[0].ends.top_chamfer",
          "top chamfers of 60 and 60 deg cut through a 12 mm rod: the two top end faces would cross")],
    ),
    "curvature too strong": (
        BASE + "    curvature: 0.06\n",
        [(10, 16, "families[0].curvature",
          "curvature 0.06 /mm bends a 30 mm rod past a 120 deg arc (at most 0.057735 /mm)")],
    ),
    "balls do not fit": (
        BASE + "    balls: {diameter: 6, density: 7.85}\n",
        [(10, 23, "families[0].balls.diameter",
          "a 6 mm ball in a 6.2 mm socket with 1.2 mm walls needs a section of at least 8.6 mm; "
          "the rod is 12 x 8 mm")],
    ),
    "rod larger than the printer": (
        BASE.replace("length: 30", "length: [30, 300]") + "printer: {build_volume: [220, 220, 250], nozzle: 0.4}\n",
        [(9, 18, "families[0].length[1]",
          "a 300 mm rod (306.4 x 12 x 8 mm) does not fit the printer's build volume (220 x 220 x 250 mm)")],
    ),
    "wall thinner than the nozzle": (
        BASE.replace("min_wall: 1.2", "min_wall: 0.3") + "printer: {build_volume: [220, 220, 250], nozzle: 0.4}\n",
        [(6, 39, "defaults.material.min_wall",
          "minimum wall 0.3 mm is thinner than the printer's nozzle (0.4 mm) (in family 'sq')")],
    ),
    "yaml syntax error": (
        BASE.replace("length: 30", "length: [30"),
        [(10, 1, "", "YAML syntax error: while parsing a flow sequence, expected ',' or ']', but got '<stream end>'")],
    ),
    "empty file": (
        "# nothing here\n",
        [(1, 1, "", "the file is empty")],
    ),
    "not a mapping": (
        "- a\n- b\n",
        [(1, 1, "", "expected a mapping, got a list")],
    ),
}


@pytest.mark.parametrize("text, expected", MISTAKES.values(), ids=MISTAKES.keys())
def test_bad_catalog_reports_exact_problem(tmp_path: Path, text: str, expected: list) -> None:
    assert problems(tmp_path, text) == expected


def test_every_problem_is_reported_at_once(tmp_path: Path) -> None:
    text = BASE.replace("thickness: 8", "thickness: eight").replace("length: 30", "length: -30") + """\
  - name: b
    length: 20
    joint: {knuckle_radius: 5.8}
  - name: c
    lenght: 20
"""
    assert problems(tmp_path, text) == [
        (4, 36, "defaults.section.thickness", "expected a number, got a string ('eight')"),
        (9, 13, "families[0].length", "must be greater than 0 mm and at most 1000 mm (got -30)"),
        (14, 5, "families[2].lenght", "unknown key 'lenght' (did you mean 'length'?)"),
    ]
    # With the defaults fixed, cross-field checks run for the families that are fine.
    text = text.replace("thickness: eight", "thickness: 8")
    assert problems(tmp_path, text) == [
        (9, 13, "families[0].length", "must be greater than 0 mm and at most 1000 mm (got -30)"),
        (14, 5, "families[2].lenght", "unknown key 'lenght' (did you mean 'length'?)"),
        (12, 29, "families[1].joint.knuckle_radius",
         "knuckle radius 5.8 mm + radial gap 0.4 mm is wider than the rod: it must stay below half the "
         "section height (6 mm)"),
    ]


def test_problems_print_as_file_line_col(tmp_path: Path) -> None:
    path = write(tmp_path, BASE.replace("length: 30", "length: thirty"))
    with pytest.raises(InputError) as info:
        load_catalog(path)
    assert str(info.value) == f"{path}:9:13: families[0].length: expected a number, got a string ('thirty')"


def test_unreadable_inputs(tmp_path: Path) -> None:
    (tmp_path / "bin.yaml").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputError) as info:
        load_catalog(tmp_path / "bin.yaml")
    assert info.value.problems[0].message.startswith("not UTF-8 text")
    with pytest.raises(InputError) as info:
        load_catalog(tmp_path)
    assert info.value.problems[0].message == "is a directory, expected a catalog file"


def test_schema_json_round_trips() -> None:
    assert json.loads(schema_text()) == catalog_schema()


@pytest.mark.parametrize("value,key,message", [
    ("{layer_height: 0}", "print.layer_height", "must be greater than 0"),
    ("{layer_height: 0.35}", "print.layer_height", "more than 0.8 of the printer's 0.4 mm nozzle"),
    ("{perimeters: 0}", "print.perimeters", ""),
    ("{layer_heigth: 0.2}", "print", "layer_heigth"),
])
def test_bad_print_profile_is_reported_at_its_key(value, key, message):
    """The catalog's print profile (what every mass assumes): a zero or too thick layer, no
    perimeters, a misspelt key: bad input at the key, with its line."""
    import re
    from pathlib import Path

    from rodcad.catalog.loader import catalog_from_text

    root = Path(__file__).resolve().parents[1]
    text = (root / "catalogs" / "pla-parametric.yaml").read_text()
    text = re.sub(r"(?m)^print: .*$", f"print: {value}", text)
    with pytest.raises(InputError) as err:
        catalog_from_text(text, "c.yaml")
    probs = err.value.problems
    assert any(p.key.startswith(key) and message in p.message and p.line > 0 for p in probs), probs
