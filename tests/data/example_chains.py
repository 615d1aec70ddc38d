"""Regenerate tests/data/example_chains.json: the designed chains of the shipped examples, the
inputs of the as-printed tests (tests/test_pinplay.py, tests/test_tolerance.py).

    python tests/data/example_chains.py [semicircle necklace heart garland]

Builds each with ``rodcad build examples/NAME.yaml --no-cad`` and keeps its numbers: lengths mm,
masses g, com (along, perp) mm in the rod (pivot) frame, limits in degrees (null = no bound).
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(__file__).with_suffix(".json")


def chain_of(name: str, folder: Path) -> dict:
    out = folder / name
    subprocess.run([sys.executable, "-m", "rodcad.cli", "build", str(ROOT / "examples" / f"{name}.yaml"), "-o",
                    str(out), "--no-cad", "-q"], check=True, cwd=ROOT)
    d = json.loads((out / "design.json").read_text())
    rods = d["rods"]
    return {"anchors": d["anchors"], "anchor_limits_deg": d["anchor_limits_deg"],
            "lengths": [r["length"] for r in rods], "masses": [r["mass"] for r in rods],
            "com": [r.get("com_rod_frame", r["com"]) for r in rods],
            "limits_deg": [r["limits_deg"] for r in rods[:-1]], "target": d["target"]["points"]}


def main(names: list[str]) -> None:
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=ROOT).stdout
    with tempfile.TemporaryDirectory() as tmp:
        chains = {n: chain_of(n, Path(tmp)) for n in names}
    note = (f"Designed chains of the shipped examples (rodcad build examples/NAME.yaml --no-cad, commit "
            f"{commit.strip()}; tests/data/example_chains.py): the inputs of the as-printed tests. Lengths mm, "
            "masses g, com (along, perp) mm in the pivot frame, limits in degrees (null = no bound).")
    OUT.write_text(json.dumps({"note": note, "chains": chains}, indent=1) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:] or ["semicircle", "necklace", "heart", "garland"])
