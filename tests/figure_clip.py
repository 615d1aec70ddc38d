"""What of a saved figure lies outside its canvas (tests/test_preview.py's check), recorded
for every figure saved while code runs (``Figure.savefig`` wrapped)."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator


def outside(fig) -> list[str]:
    """What of ``fig`` is drawn outside the canvas: each axes' tight box (its title, labels,
    the tick labels it draws, its legend) and every figure-level text, with 1 px of slack
    for anti-aliasing."""
    renderer = fig.canvas.get_renderer()
    w, h = fig.bbox.width, fig.bbox.height
    boxes = [(f"axes {k} ({ax.get_title()!r})", ax.get_tightbbox(renderer)) for k, ax in enumerate(fig.axes)]
    boxes += [(repr(t.get_text()), t.get_window_extent(renderer)) for t in fig.texts
              if t.get_visible() and t.get_text().strip()]
    return [f"{what} at x {b.x0:.0f}..{b.x1:.0f}, y {b.y0:.0f}..{b.y1:.0f} of {w:.0f} x {h:.0f}"
            for what, b in boxes if b is not None and (b.x0 < -1 or b.y0 < -1 or b.x1 > w + 1 or b.y1 > h + 1)]


@contextlib.contextmanager
def saved_figures() -> Iterator[list[tuple[str, list[str]]]]:
    """Every figure saved inside the block: (path, :func:`outside` of it at save time, when
    its extents are final)."""
    from matplotlib.figure import Figure

    seen: list[tuple[str, list[str]]] = []
    original = Figure.savefig

    def savefig(self, fname, *args, **kwargs):
        original(self, fname, *args, **kwargs)  # draws the figure: extents are final
        seen.append((str(fname), outside(self)))

    Figure.savefig = savefig
    try:
        yield seen
    finally:
        Figure.savefig = original
