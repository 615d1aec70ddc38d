"""``rodcad demo``: hang an example chain and show it (until ``rodcad build`` exists)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from optimize import find_equilibria, solve_equilibrium
from rodcad.outdir import staged_output


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        help="hang an example chain (free joints and a locked straight run) and plot it",
        description="Solve the exact equilibrium of an example chain and write a picture.",
    )
    p.add_argument("-o", "--outdir", default="outputs/demo", help="output folder (default %(default)s)")
    p.set_defaults(handler=run)


def demo_chain():
    """Twelve 30 mm rods between anchors 250 mm apart; joints 4..6 stop at straight."""
    n = 12
    lengths = np.full(n, 30.0)
    masses = np.linspace(2.0, 6.0, n)
    limits = np.tile([-np.pi / 2, np.pi / 2], (n - 1, 1))
    limits[4:7, 1] = 0.0
    return lengths, masses, limits, np.array([0.0, 0.0]), np.array([250.0, 20.0])


def run(args: argparse.Namespace) -> int:
    lengths, masses, limits, a, b = demo_chain()
    free = solve_equilibrium(lengths, masses, a, b)
    res = solve_equilibrium(lengths, masses, a, b, limits=limits)
    multi = find_equilibria(lengths, masses, a, b, limits=limits, n_starts=8, seed=0)
    print("rodcad demo: 12 rods of 30 mm, anchors (0, 0) and (250, 20) mm, joints 4-6 stop at straight")
    print(f"{'joint':>5} {'bend free deg':>14} {'bend limited deg':>17} {'stop moment N mm':>17}")
    for j in range(lengths.size - 1):
        moment = res.moments[j] * 1e-3  # g * mm * (m/s^2) -> N mm
        print(f"{j:>5} {np.degrees(free.bends[j]):>14.3f} {np.degrees(res.bends[j]):>17.3f} "
              f"{moment:>17.4f}")
    print(f"closure error {res.closure_error:.2e} mm, KKT residual {res.kkt_residual:.1e}, "
          f"stable {res.stable}, distinct stable equilibria found from 8 starts: {multi.n_distinct}")

    out = Path(args.outdir)
    with staged_output(out) as tmp:
        _plot(tmp / "demo.png", free, res, masses)
        (tmp / "equilibrium.json").write_text(json.dumps({
            "units": {"length": "mm", "mass": "g"},
            "points_free": free.points.tolist(),
            "points_limited": res.points.tolist(),
            "kkt_residual": res.kkt_residual,
            "stable": res.stable,
        }, indent=2))
    print(f"wrote {out / 'demo.png'} and {out / 'equilibrium.json'}")
    return 0 if res.success else 1


def _plot(path: Path, free, res, masses) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(*free.points.T, "--", color="0.6", lw=1, label="all joints free")
    segs = np.stack([res.points[:-1], res.points[1:]], axis=1)
    lc = LineCollection(segs, cmap="coolwarm", linewidths=5)
    lc.set_array(masses)
    ax.add_collection(lc)
    ax.plot(*res.points.T, "o", color="k", ms=3)
    ax.plot(*res.points[[0, -1]].T, "ks", ms=8, label="anchors")
    fig.colorbar(lc, ax=ax, label="rod mass (g)")
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"exact equilibrium, joints 4-6 locked straight (KKT {res.kkt_residual:.0e})")
    ax.legend(loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
