"""Mutated design files and catalogs: exit 0, 1 or 2, never a traceback, and a failed run
leaves an earlier output folder as it was (hypothesis, derandomised: the same cases on
every machine, a bounded number of them)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rodcad.cli import main

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ["catenary", "triangle", "chain", "necklace"]  # necklace: rods printed to order
NUMBER = re.compile(r"(?<![\w.])-?\d+(\.\d+)?(e-?\d+)?(?![\w.])")
REPLACEMENTS = ["0", "-1", "1e-9", "0.5", "3", "1e12", "1e13", "-1e300", "10" * 40, ".nan", ".inf", "''", "[]",
                "{}", "null", "true", "abc", "[1, 2, 3]"]


def _mutate(text: str, kind: int, which: int, value: str) -> str:
    lines = text.splitlines()
    body = [i for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
    i = body[which % len(body)]
    line = lines[i]
    if kind == 0:  # replace a number
        nums = list(NUMBER.finditer(line))
        if nums:
            m = nums[which % len(nums)]
            lines[i] = line[:m.start()] + value + line[m.end():]
    elif kind == 1:  # replace a value after a key
        if ":" in line:
            key = line.split(":", 1)[0]
            lines[i] = f"{key}: {value}"
    elif kind == 2:  # drop a line
        del lines[i]
    elif kind == 3:  # duplicate a line (a duplicate key)
        lines.insert(i, line)
    else:  # cut the file short
        lines = lines[: i + 1]
        lines[-1] = lines[-1][: max(1, len(lines[-1]) // 2)]
    return "\n".join(lines) + "\n"


@pytest.mark.filterwarnings("error::RuntimeWarning")  # numpy overflows are bugs too, not noise
@settings(max_examples=24, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(example=st.sampled_from(EXAMPLES), kind=st.integers(0, 4), which=st.integers(0, 50),
       value=st.sampled_from(REPLACEMENTS))
def test_mutated_design_files(tmp_path_factory, example, kind, which, value):
    tmp = tmp_path_factory.mktemp("fuzz")
    text = (ROOT / "examples" / f"{example}.yaml").read_text()
    text = text.replace("catalog: pla-weighted", f"catalog: {ROOT / 'catalogs' / 'pla-weighted.yaml'}")
    text = text.replace("catalog: pla-pinned", f"catalog: {ROOT / 'catalogs' / 'pla-pinned.yaml'}")
    design = tmp / "d.yaml"
    design.write_text(_mutate(text, kind, which, value))
    out = tmp / "out"
    out.mkdir()
    (out / "design.json").write_text('{"rodcad": "earlier"}')
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    args = ["simulate", str(design)] if example == "chain" else ["build", str(design), "-o", str(out), "--no-cad",
                                                                  "-q"]
    import contextlib
    import io

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(args)
    assert code in (0, 1, 2)
    assert "Traceback" not in err.getvalue() and "internal error" not in err.getvalue(), err.getvalue()
    if code == 2:
        assert err.getvalue().strip(), "bad input must say what is wrong"
    if code != 0:
        assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.parametrize("value", ["[]", "-5", "{min: 3}", "1e13", "abc"])
def test_mutated_catalog_lengths(tmp_path, capsys, value):
    text = (ROOT / "catalogs" / "pla-pinned.yaml").read_text()
    cat = tmp_path / "c.yaml"
    cat.write_text(re.sub(r"(?m)^(\s*)length: .*$", rf"\1length: {value}", text, count=1))
    code = main(["catalog", "check", str(cat)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and f"{cat}:" in err


@pytest.mark.parametrize("key,value", [
    ("length", "{min: 60, max: 20}"), ("length", "{min: 20}"), ("length", "{min: 0, max: 60}"),
    ("length", "{min: 20, max: 1e13}"), ("length", "{min: 20, max: 60, resolution: 0}"),
    ("length", "{min: 20, max: 60, step: 1}"), ("curvature", "{min: 0.5, max: 0.9}"),
    ("curvature", "{min: -0.05, max: .nan}"), ("stops", "{min: 90, max: -90}"), ("stops", "[0, 10]"),
])
def test_mutated_ranges_of_rods_printed_to_order(tmp_path, capsys, key, value):
    text = (ROOT / "catalogs" / "pla-parametric.yaml").read_text()
    cat = tmp_path / "c.yaml"
    cat.write_text(re.sub(rf"(?m)^(\s*){key}: .*$", rf"\1{key}: {value}", text, count=1))
    code = main(["catalog", "check", str(cat)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and f"{cat}:" in err and f"{key}" in err, err
