"""Pictures of a designed net: from above and from the side, target vs simulated."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rodcad.outputs.preview import legend_below

__all__ = ["plot_net"]


def plot_net(check, title: str, *paths: Path) -> None:
    """Two orthographic views of a :class:`rodcad.design.net.plan.NetCheck`, saved to every path.

    Left: from above (x, y); right: from the side (x, z). The target's rods are thin dashed
    grey lines between the target nodes; the simulated rods (pivot to pivot, a bent rod along its
    arc bowing down) thick,
    coloured from light (blue) to heavy (red) by mass with a colour bar in grams; nodes are
    dots (hubs as circles to scale), anchored nodes black triangles.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import EllipseCollection, LineCollection

    plan, eq = check.plan, check.equilibrium
    t = plan.target
    masses = np.asarray(check.masses, float)
    lo, hi = float(masses.min()), float(masses.max())
    norm = matplotlib.colors.Normalize(lo, hi if hi > lo else lo + 1e-9)
    cmap = matplotlib.colormaps["coolwarm"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 6), layout="constrained")
    for ax, (a, b), label in ((axes[0], (0, 1), ("x (mm)", "y (mm)")), (axes[1], (0, 2), ("x (mm)", "z (mm)"))):
        tgt = t.positions[t.edges][:, :, [a, b]]
        ax.add_collection(LineCollection(tgt, colors="0.55", linestyles="--", linewidths=1.0, label="target",
                                         zorder=1))
        if eq.success:
            sim = [c[:, [a, b]] for c in _centrelines(plan, eq.ends)]
            lc = LineCollection(sim, cmap=cmap, norm=norm, linewidths=3.5, zorder=2)
            lc.set_array(masses)
            ax.add_collection(lc)
            x = eq.positions
            if plan.hardware.is_hub:  # (one collection: a patch per hub took seconds for a thousand)
                d = np.array([2 * plan.hub(k).radius for k in range(len(x))])
                ax.add_collection(EllipseCollection(d, d, np.zeros(len(x)), units="xy", offsets=x[:, [a, b]],
                                                    offset_transform=ax.transData, facecolors="0.85", edgecolors="0.3",
                                                    linewidths=0.6, alpha=0.45, zorder=3))
            ax.plot(x[:, a], x[:, b], ".", color="0.2", ms=3, zorder=4)
            anch = x[t.hung_from]
            ax.plot(anch[:, a], anch[:, b], "v", color="k", ms=8, zorder=5, label="anchored")
            if t.glued is not None:
                ax.plot(x[t.glued, a], x[t.glued, b], "s", mfc="none", mec="k", ms=6, zorder=5,
                        label="held by glued rods")
        ax.plot(t.positions[:, a], t.positions[:, b], "o", mfc="none", mec="0.45", ms=5, zorder=1,
                label="target nodes")
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.margins(0.06)
        ax.set_xlabel(label[0])
        ax.set_ylabel(label[1])
        ax.grid(alpha=0.3)
    axes[0].set_title("from above")
    axes[1].set_title("from the side (looking along +y)")
    legend_below(fig, axes[1], ncol=3)
    sm = matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=axes, shrink=0.8, label="rod mass (g)")
    fig.suptitle(title)
    for p in paths:
        fig.savefig(p, dpi=110)
    plt.close(fig)


def _centrelines(plan, ends: np.ndarray, samples: int = 16) -> list[np.ndarray]:
    """Each rod's centreline in the world (mm): pivot to pivot, a bent rod's body along its arc
    bowing down in the vertical plane through its chord (the pose it hangs in)."""
    out = []
    for (p0, p1), arc in zip(ends, plan.arcs):
        if arc is None:
            out.append(np.array([p0, p1]))
            continue
        x = (p1 - p0) / np.linalg.norm(p1 - p0)
        down = np.array([0.0, 0.0, -1.0]) + x[2] * x
        n = np.linalg.norm(down)
        down = down / n if n > 1e-12 else np.cross(x, [1.0, 0.0, 0.0]) / np.linalg.norm(np.cross(x, [1.0, 0.0, 0.0]))
        local = arc.point(np.linspace(arc.offset, arc.offset + arc.arc_length, samples))  # bowing toward -z
        pts = p0 + np.outer(local[:, 0], x) - np.outer(local[:, 2], down)
        out.append(np.vstack([p0, pts, p1]))
    return out
