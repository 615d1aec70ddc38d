"""As printed: pin play, pin friction and mass tolerance on the shipped examples (issue 25).

For every example chain (built with ``rodcad build examples/X.yaml -o DIR/X --no-cad`` unless
DIR/X/design.json exists) this prints, in mm and in % of the target's size (design.json
``curve.size_mm``: the larger of span, width and height):

* model:  the design's own error, simulated joints vs target joints (design.json error.max_mm);
* play:   the chain with every pin bearing in its holes, rods printed with their holes on the
          hinge axes (design.json as_printed.uncompensated_error.max_mm);
* l-c:    the rule of thumb: spacing = l - c, centre of mass c/2 nearer the first hole
          (optimize.solve_pin_play);
* comp:   the chain as printed, holes placed by the compensation (design.json as_printed.error);
* fric:   the friction band (design.json friction_band_mm: the catalog's joint.friction, the
          pins' radii);
* mass:   the 95 % mass band (design.json mass_band_mm: the catalog's print.mass_tolerance).

With ``--cad NAME ...`` those examples are also built with CAD (DIR/X-cad) and the printed rods
measured: each rod's pin holes from its STEP file, its mass and centre of mass from the B-rep
(design.json fabrication), hung by the independent pins-in-discs model (tests/pinhole_model.py)
with the holes as printed and with holes on the hinge axes.

Then the solve times (median of --repeat): solve_equilibrium, solve_pin_play, friction_band,
mass_band.

    python benchmarks/bench_asprinted.py [--dir /tmp/ap] [--repeat 5] [--cad semicircle necklace] [examples ...]
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from optimize import friction_band, mass_band, solve_equilibrium, solve_pin_play

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ["catenary", "garland", "garland-rise", "heart", "necklace", "polygon", "semicircle",
            "semicircle-menu", "semicircle-weights", "triangle"]


ROOT_TESTS = ROOT / "tests"
sys.path.insert(0, str(ROOT_TESTS))  # the independent pins-in-discs model


def design_of(name: str, folder: Path, cad: bool = False) -> tuple[Path, dict]:
    out = folder / (f"{name}-cad" if cad else name)
    if not (out / "design.json").exists():
        subprocess.run([sys.executable, "-m", "rodcad.cli", "build", str(ROOT / "examples" / f"{name}.yaml"),
                        "-o", str(out), "-q", *([] if cad else ["--no-cad"])], check=True, cwd=ROOT,
                       stdout=subprocess.DEVNULL)
    return out, json.loads((out / "design.json").read_text())


def chain_of(d: dict) -> dict:
    rods = d["rods"]

    def rad(pair):
        if pair is None:
            return [-np.inf, np.inf]
        return [-np.inf if pair[0] is None else np.radians(pair[0]), np.inf if pair[1] is None else np.radians(pair[1])]

    ends = np.array([rad(p) for p in d["anchor_limits_deg"]])
    return dict(lengths=np.array([r["length"] for r in rods]), masses=np.array([r["mass"] for r in rods]),
                com=np.array([r.get("com_rod_frame", r["com"]) for r in rods]),
                limits=np.array([rad(r["limits_deg"]) for r in rods[:-1]]),
                end_limits=None if np.all(np.isinf(ends)) else ends,
                a=np.array(d["anchors"][0], float), b=np.array(d["anchors"][1], float),
                target=np.array(d["target"]["points"], float), simulated=np.array(d["simulated"]["points"], float),
                clearance=float(rods[0]["params"]["pin_clearance"]), g=9.81)


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def measured(out: Path, d: dict) -> tuple[float, float, float, float]:
    """A chain built with CAD, its rods measured: (as built, as printed by rodcad, as printed by
    the independent model with the holes measured on the STEP files, the same with the holes on
    the hinge axes), largest joint distance from the target (mm)."""
    from pinhole_model import hang_built, step_holes

    holes, axes = [], []
    for r in d["rods"]:
        f = r["fabrication"]
        rh = (r["params"]["pin_diameter"] + r["params"]["pin_clearance"]) / 2
        holes.append(step_holes(out / f["file"], f["print_matrix"], rh, r["length"]))
        axes.append([[0.0, 0.0], [r["length"], 0.0]])
    tgt = np.array(d["target"]["points"])

    def off(p):
        return float(np.linalg.norm(np.asarray(p) - tgt, axis=1).max())

    return (float(d["as_built"]["error"]["max_mm"]), float(d["as_printed"]["error"]["max_mm"]),
            off(hang_built(d, np.array(holes))), off(hang_built(d, np.array(axes))))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("examples", nargs="*", default=EXAMPLES)
    ap.add_argument("--dir", default="/tmp/ap", type=Path)
    ap.add_argument("--repeat", default=5, type=int)
    ap.add_argument("--cad", nargs="*", default=[], help="examples also built with CAD and measured")
    args = ap.parse_args(argv)
    print(f"# {platform.machine()}, python {platform.python_version()}, numpy {np.__version__}")
    head = (f"{'example':19s} {'N':>3s} {'c mm':>5s} {'mu':>4s} {'tol':>5s} {'size':>6s} | {'model':>15s} | "
            f"{'play':>15s} | {'l-c':>15s} | {'comp':>15s} | {'fric':>15s} | {'mass 95%':>15s}")
    print(head)
    print("-" * len(head))
    timing = []
    for name in args.examples:
        _, d = design_of(name, args.dir)
        ch = chain_of(d)
        n = ch["lengths"].size
        c = ch["clearance"]
        tgt = ch["target"]
        size = float(d["curve"]["size_mm"])
        kw = dict(com=ch["com"], limits=ch["limits"], end_limits=ch["end_limits"])
        st = solve_equilibrium(ch["lengths"], ch["masses"], ch["a"], ch["b"], **kw)
        ap_ = d["as_printed"]
        rule_com = ch["com"] - np.array([0.5 * c, 0.0])
        rule = solve_pin_play(ch["lengths"] - c, ch["masses"], ch["a"], ch["b"], clearance=c, com=rule_com,
                              limits=ch["limits"], end_limits=ch["end_limits"])
        mu = d["bands"]["friction"]["mu"] if d["bands"]["friction"] else float("nan")
        tol = d["print"]["mass_tolerance"]

        def cell(mm):
            return f"{mm:7.3f} {100 * mm / size:6.3f}%" if mm is not None else f"{'-':>15s}"

        unc = ap_["uncompensated_error"]["max_mm"] if ap_["uncompensated_error"] else None
        print(f"{name:19s} {n:3d} {c:5.2f} {mu:4.2f} {tol:5.3f} {size:6.1f} | {cell(d['error']['max_mm'])} | "
              f"{cell(unc)} | {cell(float(np.linalg.norm(rule.points - tgt, axis=1).max()))} | "
              f"{cell(ap_['error']['max_mm'])} | {cell(d['friction_band_mm'])} | {cell(d['mass_band_mm'])}"
              + ("" if not d["bands"]["friction"] or d["bands"]["friction"]["cells"] == 1
                 else f"  friction: {d['bands']['friction']['cells']} cells"))
        radius = d["rods"][0]["params"]["pin_diameter"] / 2
        timing.append((name, n,
                       median_time(lambda: solve_equilibrium(ch["lengths"], ch["masses"], ch["a"], ch["b"], **kw),
                                   args.repeat),
                       median_time(lambda: solve_pin_play(ch["lengths"], ch["masses"], ch["a"], ch["b"], clearance=c,
                                                          **kw), args.repeat),
                       median_time(lambda: friction_band(ch["lengths"], ch["masses"], ch["a"], ch["b"], mu=mu,
                                                         pin_radius=radius, result=st, **kw), args.repeat),
                       median_time(lambda: mass_band(ch["lengths"], ch["masses"], ch["a"], ch["b"], tol=tol,
                                                     result=st, **kw), args.repeat)))
    print()
    print(f"{'example':19s} {'N':>3s} {'equilibrium ms':>15s} {'pin play ms':>12s} {'friction ms':>12s} "
          f"{'mass band ms':>13s}")
    for name, n, t_eq, t_pp, t_fb, t_mb in timing:
        print(f"{name:19s} {n:3d} {1e3 * t_eq:15.2f} {1e3 * t_pp:12.2f} {1e3 * t_fb:12.2f} {1e3 * t_mb:13.2f}")
    if args.cad:
        print()
        head = (f"{'built with CAD':19s} {'size':>6s} | {'as built':>15s} | {'as printed':>15s} | "
                f"{'independent':>15s} | {'holes on axes':>15s}")
        print(head)
        print("-" * len(head))
        for name in args.cad:
            out, d = design_of(name, args.dir, cad=True)
            size = float(d["curve"]["size_mm"])
            values = measured(out, d)
            print(f"{name:19s} {size:6.1f} | " + " | ".join(f"{v:7.2g} {100 * v / size:6.2g}%" for v in values))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
