"""3D preview of a chandelier: every chain in its plane, rods coloured by mass, the frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from rodcad.design.chandelier import ChainResult
from rodcad.outputs.preview import fit_title

__all__ = ['preview_3d']




def preview_3d(path: str | Path, chains: Sequence[ChainResult],
               frame_outline: Sequence[np.ndarray] | None = None, title: str = "chandelier", *,
               svg: bool = False, elev: float = 22.0, azim: float = -60.0) -> list[Path]:
    """Draw the chandelier in 3D: rods coloured by mass, anchors, the frame's outline.

    One colour scale (coolwarm, light blue -> heavy red) spans every chain, with
    a colour bar in grams; anchors are black squares; the frame outline is grey;
    the axes have equal scale.

    Args:
        path: the PNG to write (its parent must exist).
        chains: designed chains (anything with ``placement``, ``points`` (N+1, 2)
            and ``masses`` (N,)).
        frame_outline: polylines (M, 3) of the frame (see :func:`frame_outline`).
        title: figure title.
        svg: also write the same picture as SVG next to the PNG.
        elev, azim: view angles (deg).

    Returns:
        The files written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    all_m = np.concatenate([np.asarray(c.masses, float) for c in chains])
    lo, hi = float(all_m.min()), float(all_m.max())
    if hi - lo <= 1e-12 * max(abs(hi), 1.0):
        lo, hi = lo * 0.95, hi * 1.05 + 1e-12
    norm = Normalize(lo, hi)
    cmap = matplotlib.colormaps["coolwarm"]
    fig = plt.figure(figsize=(8, 7))
    ax = fig.add_subplot(projection="3d")
    pts_all = []
    for c in chains:
        p3 = c.placement.to_3d(c.points)
        pts_all.append(p3)
        segs = np.stack([p3[:-1], p3[1:]], axis=1)
        lc = Line3DCollection(segs, colors=cmap(norm(np.asarray(c.masses, float))), linewidths=4,
                              capstyle="round")
        ax.add_collection3d(lc)
        ax.plot(*p3[1:-1].T, "o", color="k", ms=1.5)
        ax.plot(*np.array([c.placement.a3, c.placement.b3]).T, "ks", ms=5)
    for line in frame_outline or []:
        line = np.asarray(line, float)
        ax.plot(*line.T, "-", color="0.45", lw=1.0)
        pts_all.append(line)
    allp = np.vstack(pts_all)
    mid = (allp.max(axis=0) + allp.min(axis=0)) / 2
    half = float(np.ptp(allp, axis=0).max()) / 2 * 1.05 + 1e-9
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    fig.colorbar(ScalarMappable(norm, cmap), ax=ax, label="rod mass (g)", shrink=0.6, pad=0.1)
    fit_title(fig, ax, title)
    path = Path(path)
    fig.savefig(path, dpi=130)
    written = [path]
    if svg:
        fig.savefig(path.with_suffix(".svg"))
        written.append(path.with_suffix(".svg"))
    plt.close(fig)
    return written
