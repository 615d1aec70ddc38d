"""Graduated rods in the planner (issue 26): stops and fit with and without the scale range.

    python benchmarks/bench_graduated_plan.py [--garlands 12] [--seed 0]

Each design is built (``--no-cad``) twice with the default catalog's family: as shipped
(each rod's body scale chosen with its mass, 0.55-1.6) and with its scale range removed
(every rod at the family's 16 x 16 mm section: the catalog before graduated rods). Per
design: joints on stops (one- or two-sided, fused included) out of all, anchor stops, and
how far the rods' centrelines hang from the target curve over the span, with the exit code.

The designs: the shipped examples that use the default catalog, the paper's semicircle by
weight alone (``constraints: {joints: free}``), a 1.2 m garland (24 rods: a parabola with a
heavier middle) and a seeded family of smooth garlands the project has not seen (convex
curves between anchors at random heights: sums of a parabola, a Gaussian dip and a
slope, 0.6-1.6 m span). The issue's targets: the semicircle by weight alone within 1 % of
its span; a long smooth garland with at most a third of its joints on stops, within 0.1 %.
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]


def _catalogs(folder: Path) -> tuple[str, Path]:
    """The default catalog's name and a copy of it without the scale range."""
    src = ROOT / "catalogs" / "pla-parametric.yaml"
    data = yaml.safe_load(src.read_text(encoding="utf-8"))
    data["name"] = "pla-parametric-one-scale"
    for fam in data["families"]:
        fam.pop("scale", None)
    out = folder / "pla-parametric-one-scale.yaml"
    out.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return "pla-parametric", out


def _garland(rng: np.random.Generator, k: int) -> dict:
    span = float(rng.uniform(600, 1600))
    sag = float(rng.uniform(0.15, 0.35)) * span
    dip = float(rng.uniform(0.0, 0.08)) * span
    width = float(rng.uniform(0.1, 0.25)) * span
    at = float(rng.uniform(0.35, 0.65)) * span
    rise = float(rng.uniform(-0.15, 0.15)) * span
    y = (f"-{sag:.3f} * (1 - (2 * x / {span:.3f} - 1)**2) - {dip:.3f} * exp(-((x - {at:.3f}) / {width:.3f})**2)"
         f" + {rise:.3f} * x / {span:.3f}")
    y_b = rise - dip * float(np.exp(-((span - at) / width) ** 2))
    y_a = -dip * float(np.exp(-(at / width) ** 2))
    return {"design": 1, "name": f"garland-{k}", "anchors": [[0, round(y_a, 6)], [round(span, 6), round(y_b, 6)]],
            "target": {"form": "function", "y": y}, "seed": 0}


def designs(n_garlands: int, seed: int) -> list[dict]:
    out = []
    for name in ("semicircle", "heart", "necklace", "garland", "garland-rise", "catenary"):
        path = ROOT / "examples" / f"{name}.yaml"
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
        if "catalog" in data or "target" not in data:
            continue
        out.append(data)
    out.append({"design": 1, "name": "semicircle-by-weight", "anchors": [[0, 0], [200, 0]],
                "target": {"form": "semicircle"}, "constraints": {"joints": "free"}, "seed": 0})
    out.append({"design": 1, "name": "garland-1.2m", "anchors": [[0, 0], [1200, 0]],
                "target": {"form": "function",
                           "y": "-300 * (1 - (2 * x / 1200 - 1)**2) - 50 * exp(-((x - 600) / 200)**2)"},
                "seed": 0})
    rng = np.random.default_rng(seed)
    out += [_garland(rng, k) for k in range(n_garlands)]
    return out


def run(data: dict, catalog: str | Path, folder: Path, tag: str) -> dict:
    d = dict(data)
    d["catalog"] = str(catalog)
    path = folder / f"{d['name']}-{tag}.yaml"
    path.write_text(yaml.safe_dump(d, sort_keys=False), encoding="utf-8")
    out = folder / f"{d['name']}-{tag}"
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "rodcad.cli", "build", str(path), "-o", str(out), "--no-cad", "-q"],
                       capture_output=True, text=True, timeout=600)
    dt = time.perf_counter() - t0
    row = {"code": p.returncode, "time": dt}
    for f in (out, out.with_name(out.name + ".best-fit")):
        j = f / "design.json"
        if j.is_file():
            js = json.loads(j.read_text())
            disc = js.get("discretisation", {})
            held = {s["joint"] for s in disc.get("added_stops", [])}
            held |= {j for a, b in js.get("fused", []) for j in range(a, b)}
            row.update(rods=len(js["rods"]), stops=len(held), joints=len(js["rods"]) - 1,
                       anchor=sum(1 for x in js.get("anchor_limits_deg", []) or [] if x is not None),
                       fit=js["curve"]["rel_span"],
                       scales=[r["params"].get("scale", 1.0) for r in js["rods"]])
            break
    if p.returncode not in (0, 1):
        row["err"] = p.stderr.strip().splitlines()[-1:] if p.stderr.strip() else []
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--garlands", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(f"# {platform.node()} {platform.processor() or platform.machine()}, python {platform.python_version()}, "
          f"{time.strftime('%Y-%m-%d')}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        graded, fixed = _catalogs(folder)
        print(f"{'design':24s} | {'one scale: stops':>17s} {'fit %':>8s} {'s':>5s} | "
              f"{'graduated: stops':>17s} {'fit %':>8s} {'s':>5s} {'scales':>11s}")
        rows = []
        for d in designs(args.garlands, args.seed):
            a = run(d, fixed, folder, "fixed")
            b = run(d, graded, folder, "graded")
            rows.append((d["name"], a, b))

            def cell(r: dict) -> str:
                if "fit" not in r:
                    return f"{'exit ' + str(r['code']):>17s} {'':>8s} {r['time']:5.1f}"
                st = f"{r['stops']}/{r['joints']}" + (f" +{r['anchor']}A" if r["anchor"] else "")
                mark = "" if r["code"] == 0 else f" (exit {r['code']})"
                return f"{st + mark:>17s} {100 * r['fit']:8.4f} {r['time']:5.1f}"

            sc = b.get("scales") or [1.0]
            print(f"{d['name']:24s} | {cell(a)} | {cell(b)} {min(sc):5.2f}-{max(sc):4.2f}", flush=True)
        gar = [(a, b) for name, a, b in rows if name.startswith("garland-") and name[8:].isdigit()]
        if gar:
            def share(r):
                return r["stops"] / max(r["joints"], 1)
            fa = [share(a) for a, _ in gar if "fit" in a]
            fb = [share(b) for _, b in gar if "fit" in b]
            ok = sum(1 for _, b in gar if "fit" in b and share(b) <= 1 / 3 + 1e-9 and b["fit"] <= 1e-3)
            print(f"\nseeded garlands: joints on stops, median {100 * np.median(fa):.0f} % (one scale) -> "
                  f"{100 * np.median(fb):.0f} % (graduated); {ok} of {len(gar)} graduated at most a third on stops "
                  "and within 0.1 % of the span")


if __name__ == "__main__":
    main()
