"""The YAML/schema framework behind catalogs (reused later for design files)."""

from __future__ import annotations

import jsonschema
import pytest

from rodcad.errors import InputError
from rodcad.yamlio import Pos, format_number, load_yaml, load_yaml_text
from rodcad.yamlspec import (
    Bool,
    Field,
    ListOf,
    Nullable,
    Num,
    Obj,
    OneOrList,
    Str,
    check_document,
)

SPEC = Obj(
    {
        "name": Field(Str(pattern=r"[a-z]+", pattern_hint="lower-case letters"), required=True),
        "kind": Field(Str(choices=("alpha", "beta")), default="alpha"),
        "size": Field(Num(minimum=1, maximum=10, unit="mm")),
        "count": Field(Num(integer=True, exclusive_minimum=0)),
        "on": Field(Bool()),
        "sizes": Field(OneOrList(Num(exclusive_minimum=0), unique=True)),
        "pair": Field(ListOf(Num(), min_items=2)),
        "maybe": Field(Nullable(Obj({"x": Field(Num(), required=True)}))),
    },
    title="test",
)


def check(text: str):
    return check_document(load_yaml_text(text, "t.yaml"), SPEC)


def errors(text: str) -> list[str]:
    with pytest.raises(InputError) as info:
        check(text)
    return [str(p) for p in info.value.problems]


def test_values_defaults_and_positions() -> None:
    doc = check("name: abc\nsize: 2.5\ncount: 3\non: true\nsizes: 4\npair: [1, 2]\nmaybe: null\n")
    assert doc.value == {"name": "abc", "kind": "alpha", "size": 2.5, "count": 3, "on": True, "sizes": [4.0],
                         "pair": [1.0, 2.0], "maybe": None}
    assert doc.pos("size") == Pos(2, 7)
    assert doc.pos("pair[1]") == Pos(6, 11)
    assert doc.pos("nope") == Pos()


def test_each_kind_of_problem_at_its_value() -> None:
    text = (
        "name: Abc\n"           # 1 pattern
        "kind: gamma\n"         # 2 choice
        "size: 11\n"            # 3 range
        "count: 2.5\n"          # 4 integer
        "on: maybe\n"           # 5 boolean
        "sizes: [1, 1]\n"       # 6 unique
        "pair: [1]\n"           # 7 min items
        "maybe: {y: 1}\n"       # 8 unknown key + missing key in a nested mapping
        "nmae: x\n"             # 9 unknown key with suggestion
    )
    assert errors(text) == [
        "t.yaml:1:7: name: 'Abc' is not lower-case letters",
        "t.yaml:2:7: kind: unknown value 'gamma' (expected one of: alpha, beta)",
        "t.yaml:3:7: size: must be between 1 mm and 10 mm (got 11)",
        "t.yaml:4:8: count: expected a whole number, got 2.5",
        "t.yaml:5:5: on: expected true or false, got a string ('maybe')",
        "t.yaml:6:12: sizes[1]: duplicate value 1 (also item 0)",
        "t.yaml:7:7: pair: expected at least 2 items, got 1",
        "t.yaml:8:9: maybe.y: unknown key 'y' (expected one of: x)",
        "t.yaml:8:8: maybe: missing required key 'x'",
        "t.yaml:9:1: nmae: unknown key 'nmae' (did you mean 'name'?)",
    ]


def test_numbers_as_a_person_writes_them() -> None:
    assert check("name: a\nsize: 1e0\n").value["size"] == 1.0  # YAML 1.1 reads 1e0 as a string
    assert errors("name: a\nsize: .nan\n") == ["t.yaml:2:7: size: expected a finite number, got .nan"]
    assert errors("name: a\nsize: '2'\n") == ["t.yaml:2:7: size: expected a number, got a string ('2')"]
    assert errors("name: a\nsize: true\n") == ["t.yaml:2:7: size: expected a number, got a boolean (true)"]
    assert errors("name: a\nsize:\n") == ["t.yaml:2:6: size: expected a number, got nothing (null)"]


def test_syntax_errors_and_several_documents() -> None:
    with pytest.raises(InputError) as info:
        load_yaml_text("a: [1, 2\n", "s.yaml")
    assert str(info.value).startswith("s.yaml:2:1: YAML syntax error: ")
    with pytest.raises(InputError) as info:
        load_yaml_text("a: 1\n---\nb: 2\n", "s.yaml")
    assert str(info.value) == "s.yaml:3:1: expected one YAML document, found several"


def test_missing_file(tmp_path) -> None:
    with pytest.raises(InputError) as info:
        load_yaml(tmp_path / "none.yaml", "none.yaml")
    assert str(info.value) == "none.yaml:0:0: no such file"


def test_json_schema_from_the_same_specs() -> None:
    schema = SPEC.json_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["required"] == ["name"] and schema["additionalProperties"] is False
    assert schema["properties"]["size"] == {"description": "(mm)", "type": "number", "minimum": 1, "maximum": 10}
    assert schema["properties"]["kind"]["enum"] == ["alpha", "beta"]
    assert schema["properties"]["kind"]["default"] == "alpha"
    ok = {"name": "abc", "sizes": [1, 2], "maybe": None, "pair": [0, 1]}
    jsonschema.validate(ok, schema)
    for bad in ({"name": "abc", "size": 11}, {"name": "abc", "extra": 1}, {"size": 2},
                {"name": "abc", "sizes": [1, 1]}, {"name": "ABC"}):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(bad, schema)


@pytest.mark.parametrize("x, text", [(3, "3"), (3.0, "3"), (0.25, "0.25"), (1 / 3, "0.333333"), (-0.01, "-0.01")])
def test_format_number(x: float, text: str) -> None:
    assert format_number(x) == text


def test_numbers_beyond_any_meaning_and_text_that_is_a_number() -> None:
    assert errors("name: a\nsize: 1e308\n") == ["t.yaml:2:7: size: expected a number between -1e+12 and 1e+12, got 1e308"]
    huge = "1" + "0" * 400
    assert errors(f"name: a\nsize: {huge}\n") == [
        "t.yaml:2:7: size: expected a number between -1e+12 and 1e+12, got 10000000000000000000..."]
    assert errors("name: 5\nsize: 1\n") == ["t.yaml:1:7: name: expected a string, got a number (5); quote it if you "
                                           "meant text"]


def test_self_referring_and_deeply_nested_yaml_is_refused() -> None:
    with pytest.raises(InputError) as info:
        load_yaml_text("a: &t {b: 1, <<: *t}\n", "r.yaml")
    assert "refers to itself" in str(info.value) and str(info.value).startswith("r.yaml:1:")
    with pytest.raises(InputError) as info:
        load_yaml_text("a: " + "[" * 200 + "]" * 200 + "\n", "d.yaml")
    assert "nests more than 64 levels" in str(info.value)
