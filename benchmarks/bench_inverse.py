"""Inverse design methods side by side (issue 4): error vs wall time and vs simulator calls.

Targets: the paper's Fig. 7 shapes (semicircle, triangle, regular polygon) and
its heart (Fig. 9, the lower outline: see rodcad.design.targets.heart), laid on the
shipped catalog pla-weighted (straight stops that meet free corners, wider mass
ranges), plus a convex target reachable within the catalog's mass bounds (a
catenary). The triangle comes twice: with sides of 150 mm (five 30 mm rods fit
each side, so its apex is a joint) and 120 mm deep (sides of 156.2 mm, which no
combination of 30 and 40 mm rods tiles). The semicircle also comes twice: as
planned (joints put on the catalog's 20 degree curve stops where the masses cannot
hold the sag, see ``plan_chain(add_stops=...)``) and with masses only
(``add_stops=False``), a bounded best fit whose masses all sit on their bounds.
Every method works on the
same InverseProblem; the particle swarms get the same wall-time budget as each
other (--pso-time), refine runs until it converges. Prints a table and writes
benchmarks/inverse_convergence.png.

Run:  python benchmarks/bench_inverse.py [--pso-time 3] [--seeds 3]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from optimize import design
from optimize.chain.curves import curve_distance
from rodcad.catalog.loader import load_catalog
from rodcad.design.plan import catalog_arrays, plan_chain
from rodcad.design.targets import make_target

A, B = (0.0, 0.0), (200.0, 0.0)
TARGETS = {
    "catenary (reachable)": ("catenary", {"length": 300}),
    "semicircle": ("semicircle", {}),
    "semicircle, no stops": ("semicircle", {}),
    "triangle (sides 150)": ("triangle", {"depth": float(np.sqrt(150**2 - 100**2))}),
    "triangle (depth 120)": ("triangle", {"depth": 120}),
    "polygon (3 sides)": ("polygon", {"sides": 3}),
    "heart": ("heart", {}),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pso-time", type=float, default=3.0, help="seconds per PSO run")
    ap.add_argument("--seeds", type=int, default=3, help="PSO seeds per target")
    ap.add_argument("--catalog", default="pla-weighted", help="catalog name or file")
    ap.add_argument("--png", default=str(Path(__file__).with_name("inverse_convergence.png")))
    ap.add_argument("--spans", type=float, nargs="*", default=[200, 400, 600],
                    help="anchor distances (mm) for the bounded-target size sweep (none: skip it)")
    args = ap.parse_args()

    cat = load_catalog(args.catalog)
    arrays = catalog_arrays(cat)
    rows, curves = [], {}
    print(f"catalog {cat.name}")
    print(f"{'target':<22} {'N':>3} {'method':<11} {'max err/span':>13} {'time s':>8} "
          f"{'sim calls':>9}  note")
    for label, (form, params) in TARGETS.items():
        plan = plan_chain(cat, make_target(form, A, B, **params), arrays=arrays,
                          add_stops="no stops" not in label)
        prob = plan.problem
        curves[label] = {}
        for method in ("exact", "refine", "guided-pso", "pso"):
            seeds = range(args.seeds) if method.endswith("pso") else [0]
            errs, times, calls = [], [], []
            for seed in seeds:
                t0 = time.perf_counter()
                r = design(prob, method, seed=seed, max_nfev=10**9 if method.endswith("pso") else 400,
                           max_time=args.pso_time if method.endswith("pso") else None)
                times.append(time.perf_counter() - t0)
                errs.append(r.distance.max_rel_span)
                calls.append(r.nfev)
                if seed == 0:
                    curves[label][method] = r.history or [(r.nfev, r.time_s, r.distance.max_rel_span)]
            note = "exact" if method in ("exact", "refine") and errs[0] < 1e-9 else ""
            if len(errs) > 1:
                note = f"median of {len(errs)} seeds, best {min(errs):.2e}"
            err = float(np.median(errs))
            rows.append((label, method, err, float(np.median(times)), int(np.median(calls))))
            print(f"{label:<22} {prob.n:>3} {method:<11} {err:>13.3e} {np.median(times):>8.3f} "
                  f"{int(np.median(calls)):>9}  {note}")
        unmet = (f"; {len(plan.unmet_joints)} joint(s) no pair of types can hold: "
                 f"{plan.unmet_joints}" if plan.unmet_joints else "")
        print(f"{'':<22} discretisation error {plan.discretization.curve_error:.2f} mm; "
              f"stop mismatch {np.degrees(plan.assign_cost):.1f} deg{unmet}")
        print(f"{'':<22} types: {_types_summary(plan.type_names)}")
        if plan.added_stops:
            print(f"{'':<22} stops added at joints {plan.added_stops} "
                  f"({', '.join(f'{round(np.degrees(plan.problem.limits[j, 1]), 1) + 0.0:g}' for j in plan.added_stops)} deg)")

    print("\nrefine vs guided PSO at the same wall time (guided PSO's best error when it had used "
          "as much time as refine took, and at its full budget):")
    for label in TARGETS:
        ref = next(r for r in rows if r[0] == label and r[1] == "refine")
        hist = curves[label]["guided-pso"]
        early = [e for _, t, e in hist if t <= ref[3]]
        at_same = min(early) if early else hist[0][2]
        first = "" if early else f" (its first result, at {hist[0][1]:.3f} s)"
        full = next(r for r in rows if r[0] == label and r[1] == "guided-pso")[2]
        ratio_same = at_same / ref[2] if ref[2] > 0 else float("inf")
        ratio_full = full / ref[2] if ref[2] > 0 else float("inf")
        print(f"  {label:<22} refine {ref[2]:.2e} in {ref[3]:.3f} s; guided PSO {at_same:.2e}{first} "
              f"(x{ratio_same:.3g}) then {full:.2e} after {args.pso_time:g} s (x{ratio_full:.3g})")
    print("\nrefine vs guided PSO at the same number of simulator calls (guided PSO's best error "
          "after as many calls as refine used):")
    for label in TARGETS:
        ref = next(r for r in rows if r[0] == label and r[1] == "refine")
        hist = curves[label]["guided-pso"]
        at_same = min((e for n, _, e in hist if n <= ref[4]), default=float("nan"))
        ratio = at_same / ref[2] if ref[2] > 0 else float("inf")
        print(f"  {label:<22} refine {ref[2]:.2e} in {ref[4]} calls; guided PSO {at_same:.2e} (x{ratio:.3g})")
    print("\nguided PSO vs plain PSO (median final error, same time):")
    for label in TARGETS:
        g = next(r for r in rows if r[0] == label and r[1] == "guided-pso")[2]
        p = next(r for r in rows if r[0] == label and r[1] == "pso")[2]
        print(f"  {label:<22} guided {g:.3e}  plain {p:.3e}  -> "
              f"{'guided better' if g < p else 'plain better or equal'}")
    if args.spans:
        _size_sweep(cat, arrays, args.spans, args.pso_time)
    _plot(curves, args.png)
    print(f"\nwrote {args.png}")


def _size_sweep(cat, arrays, spans, pso_time) -> None:
    """Bounded targets at several sizes (more rods): refine against guided PSO at the same
    wall time, masses only and with the planner's stops."""
    print("\nbounded targets at other sizes (more rods): max joint error / span of refine and of "
          "guided PSO (seed 0) at refine's wall time and at the end of its budget; 'hang mm': how far "
          "refine's chain hangs from the target curve")
    print(f"{'target':<12} {'span':>5} {'N':>3} {'stops':<6} {'refine':>9} {'ms':>5} {'gPSO same t':>11} "
          f"{'ratio':>8} {'gPSO end':>9} {'hang mm':>8}")
    for form in ("semicircle", "heart"):
        for span in spans:
            for stops in (False, True):
                plan = plan_chain(cat, make_target(form, A, (float(span), 0.0)), arrays=arrays,
                                  add_stops=stops)
                prob = plan.problem
                r = design(prob, "refine", max_nfev=400)
                g = design(prob, "guided-pso", seed=0, max_nfev=10**9, max_time=pso_time)
                early = [e for _, t, e in g.history if t <= r.time_s]
                same = min(early) if early else g.history[0][2]
                ref = r.distance.max_rel_span
                ratio = same / ref if ref > 0 else float("inf")
                hang = curve_distance(plan.curve, r.equilibrium.points)
                print(f"{form:<12} {span:>5.0f} {prob.n:>3} {'yes' if plan.added_stops else 'no':<6} "
                      f"{ref:>9.2e} {1e3 * r.time_s:>5.0f} {same:>11.2e} {ratio:>8.3g} "
                      f"{g.distance.max_rel_span:>9.2e} {hang:>8.2f}")


def _types_summary(names) -> str:
    """Rod types along the chain, runs collapsed: 'straight-30 x4, straight-free-30, ...'."""
    out, k = [], 0
    while k < len(names):
        j = k
        while j + 1 < len(names) and names[j + 1] == names[k]:
            j += 1
        out.append(names[k] + (f" x{j - k + 1}" if j > k else ""))
        k = j + 1
    return ", ".join(out)


def _plot(curves, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(curves), figsize=(4 * len(curves), 7), squeeze=False)
    colors = {"exact": "k", "refine": "tab:blue", "guided-pso": "tab:red", "pso": "tab:orange"}
    for col, (label, methods) in enumerate(curves.items()):
        for method, hist in methods.items():
            h = np.array(hist, dtype=float)
            floor = np.maximum(h[:, 2], 1e-17)
            axes[0, col].step(np.maximum(h[:, 1], 1e-4), floor, where="post", color=colors[method], label=method)
            axes[1, col].step(h[:, 0], floor, where="post", color=colors[method], label=method)
        axes[0, col].set_title(label)
        for row, xl in enumerate(("wall time (s)", "simulator calls")):
            ax = axes[row, col]
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(xl)
            ax.grid(True, which="both", alpha=0.3)
        axes[0, col].set_ylabel("best max joint error / span")
        axes[1, col].set_ylabel("best max joint error / span")
    axes[0, 0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    main()
