"""Pictures of a designed chain: target dashed, rods coloured by mass, anchors, error."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from optimize.chain.curves import centerline, curve_distance
from rodcad.outputs.printed import draw_bands

__all__ = ['draw_rods', 'finish_figure', 'fit_title', 'legend_below', 'plot_chain']


def plot_chain(r, *paths: Path) -> None:
    """Draw a :class:`rodcad.pipeline.BuildResult` and save it to every path (PNG, SVG, ...).

    The target curve is dashed, its joints are small open circles; each rod is a
    thick segment (the arc of a curved rod) coloured from light (blue) to heavy (red) by mass, with a
    colour bar in grams; anchors are black squares; the as-built chain, when
    present, is a thin dotted line. The title gives the shape error.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = r.design
    eq = r.equilibrium
    pts = eq.points
    fig, ax = plt.subplots(figsize=(8, 6))
    if d.target_curve is not None:
        ax.plot(*d.target_curve.T, "--", color="0.45", lw=1.2, label="target")
    if r.target_points is not None:
        ax.plot(*r.target_points.T, "o", mfc="none", mec="0.35", ms=6, label="target joints")
    curvature = [getattr(d.catalog[n], "curvature", 0.0) if n in d.catalog else 0.0 for n in r.type_names]
    geoms = [getattr(d.catalog[n], "geometry", None) if n in d.catalog else None for n in r.type_names]
    heights = None if any(g is None for g in geoms) else [g.body_h for g in geoms]
    lc, _ = draw_rods(ax, pts, curvature, r.masses, heights)
    fused = [j for a, b in (r.plan.fused if r.plan is not None else []) for j in range(a, b)]
    stops = [j for j in (r.plan.added_stops if r.plan is not None else []) if j not in fused]
    if stops:
        ax.plot(*pts[[j + 1 for j in stops]].T, "^", mfc="gold", mec="k", ms=7, zorder=5,
                label="joint on a stop")
    if fused:
        ax.plot(*pts[[j + 1 for j in fused]].T, "D", mfc="darkorange", mec="k", ms=6, zorder=5,
                label="fused joint (one printed piece)")
    held = np.asarray((eq.info or {}).get("end_active", np.zeros(2)), int)
    if held.any():
        ax.plot(*np.asarray(d.anchors)[held != 0].T, "s", mfc="none", mec="gold", mew=2.5, ms=15, zorder=7,
                label="anchor fixture stops the end rod")
    if r.as_built is not None:
        ax.plot(*r.as_built.equilibrium.points.T, ":", color="k", lw=1, zorder=5, label="as built")
    if getattr(r, "as_printed", None) is not None:
        tapped = getattr(r, "tapping", None)
        draw_bands(ax, r.as_printed, pts, max(d.span, float(np.ptp(pts[:, 0])), float(np.ptp(pts[:, 1]))),
                   rest=None if tapped is None else tapped.rests[-1])
    title = f"{d.name}: {r.n} rods"
    if r.method:
        title += f", {r.method}"
    if not eq.stable:
        title += "  [NOT STABLE]"
    if r.distance is not None:
        if r.plan is not None and d.target_curve is not None:
            from rodcad.design.shell import curve_size

            hang = curve_distance(d.target_curve, centerline(pts, curvature))
            size = curve_size(d.target_curve)
            title += (f"\nrods at most {100 * hang / d.span:.3g} % of the span off the target curve" if size < 1.5 * d.span
                      else f"\nrods at most {100 * hang / size:.3g} % of its {size:.4g} mm size off the target curve")
        title += f"\njoints {100 * r.distance.max_rel_span:.3g} % of the span off the target"
        if r.as_built is not None:
            title += f", as built {100 * r.as_built.distance.max_rel_span:.3g} %"
        if getattr(r, "as_printed", None) is not None:
            title += f"\nas printed (pins in their holes) {100 * r.as_printed.distance.max_rel_span:.3g} %"
    finish_figure(fig, ax, lc, d.anchors, title, paths)


#: Line width (pt) per mm of a rod's body height in the previews (6 pt for a 16 mm section).
WIDTH_PER_MM = 0.375

#: How far below the axes the legend starts (pt): the x tick labels and the x label (10 pt each,
#: with their pads) and a gap.
LEGEND_DROP_PT = 36.0


def legend_below(fig, ax, ncol: int) -> None:
    """The axes' legend below them and their x label, not over the drawing (loc="best" laid it
    over the heart's tip and the lampshade's rods): a fixed distance in points, the tick labels'
    and the label's height whatever the axes' (a tenth of the axes' height laid the legend's
    first row over "x (mm)" on a wide chain)."""
    from matplotlib.transforms import offset_copy

    below = offset_copy(ax.transAxes, fig=fig, y=-LEGEND_DROP_PT, units="points")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=below, ncol=ncol, fontsize=8,
              frameon=False)


def draw_rods(ax, points: np.ndarray, curvature, masses, heights=None) -> tuple[object, list[np.ndarray]]:
    """Each rod as it is printed (its chord, or the arc of its curved body), coloured by mass,
    its line width proportional to its body's height (``heights``, mm; None: 6 pt each),
    with its joints as dots; returns (the collection, the rods' polylines)."""
    from matplotlib.collections import LineCollection

    segs = [centerline(points[i:i + 2], [k]) for i, k in enumerate(curvature)]
    widths = 6 if heights is None else [WIDTH_PER_MM * float(h) for h in heights]
    lc = LineCollection(segs, cmap="coolwarm", linewidths=widths, capstyle="round", zorder=3)
    lc.set_array(np.asarray(masses, float))
    if np.ptp(masses) == 0:
        lc.set_clim(masses[0] * 0.95, masses[0] * 1.05)
    ax.add_collection(lc)
    ax.plot(*np.asarray(points).T, "o", color="k", ms=2.5, zorder=4)
    return lc, segs


def finish_figure(fig, ax, lc, anchors: np.ndarray, title: str, paths) -> None:
    """Anchors, the mass colour bar, equal axes in mm, title, legend and grid; saved to every
    path and closed."""
    import matplotlib.pyplot as plt

    from mpl_toolkits.axes_grid1 import make_axes_locatable

    ax.plot(*np.asarray(anchors).T, "ks", ms=9, zorder=6, label="anchors")
    ax.set_aspect("equal")
    # the colour bar as tall as the axes as drawn (equal axes are shorter than their slot: a bar
    # sized to the slot reached down over the legend's right-hand column)
    bar = make_axes_locatable(ax).append_axes("right", size="3%", pad=0.15)
    fig.colorbar(lc, cax=bar, label="rod mass (g)")
    ax.autoscale_view()
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    legend_below(fig, ax, ncol=2)
    ax.grid(True, lw=0.3, alpha=0.5)
    fit_title(fig, ax, title)
    for path in paths:
        fig.savefig(path, dpi=130)
    plt.close(fig)


def fit_title(fig, ax, title: str) -> None:
    """Set the axes' title and lay the figure out so that the title lies inside the canvas:
    lines too long for the room on either side of the axes' centre are wrapped at spaces
    (the layout is redone after each wrap). The title's width and its place across the
    canvas are known once the layout has placed the axes; drawing the figure only moves it
    up or down, so it is not drawn here (the previews of the examples and of ten drawn
    shapes, and titles wrapped on 2D and 3D axes, came out byte-identical without it).

    The layout is final when it returns: the figure is left with no layout engine (the
    placeholder ``tight_layout`` leaves behind made every save draw the figure twice, once
    only to lay it out again; the pictures are the same bytes without that draw)."""
    import textwrap

    lines = title.splitlines()
    text = ax.set_title(title)
    for _ in range(6):
        fig.tight_layout()
        box = text.get_window_extent(fig.canvas.get_renderer())
        if box.x0 >= 0 and box.x1 <= fig.bbox.width:
            break
        centre = (box.x0 + box.x1) / 2
        room = 2 * min(centre, fig.bbox.width - centre) - 8  # px, a margin of 4 on each side
        longest = max(len(line) for line in lines)
        width = max(20, int(longest * min(0.95, room / max(box.width, 1.0))))
        lines = [w for line in lines for w in (textwrap.wrap(line, width) or [""])]
        text.set_text("\n".join(lines))
    fig.set_layout_engine(None)
