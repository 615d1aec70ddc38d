"""Previews: no text is cut off by the canvas (titles, labels, legends) for any example.

Every figure rodcad saves while building the shipped examples is inspected at save time
(Figure.savefig is wrapped): everything each axes draws (title, axis labels, tick labels,
legend) and every figure text must lie inside the canvas.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from expected_exits import EXPECTED_EXIT
from figure_clip import saved_figures as recorded_figures

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted(p for p in (ROOT / "examples").glob("*.yaml") if p.stem != "chain"
                  and "\nnet:" not in p.read_text())  # nets: tests/test_net_build.py


@pytest.fixture
def saved_figures():
    """Every figure saved while the test runs: (path, texts outside the canvas)."""
    with recorded_figures() as seen:
        yield seen


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
def test_no_preview_text_is_clipped(example, build_store):
    """The figures of the session's build of the example (tests/test_build.py reads the same
    build), inspected as they were saved."""
    code, _, _ = build_store.cli_build(example, "--no-cad", "-q")
    assert code == EXPECTED_EXIT.get(example.stem, 0)
    figures = build_store.figures(example, "--no-cad", "-q")
    assert figures, "no figure was saved"
    clipped = [(path, bad) for path, bad in figures if bad]
    assert not clipped, clipped


def test_a_long_title_is_wrapped_inside_the_canvas(tmp_path, saved_figures):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rodcad.outputs.preview import draw_rods, finish_figure

    fig, ax = plt.subplots(figsize=(8, 6))
    pts = np.array([[0.0, 0.0], [30.0, -20.0], [60.0, 0.0]])
    lc, _ = draw_rods(ax, pts, [0.0, 0.01], [10.0, 12.0])
    title = "a chain: 2 rods, refine\n" + " ".join(["joints 1.23e-09 % of span off the target"] * 4)
    finish_figure(fig, ax, lc, pts[[0, -1]], title, [tmp_path / "p.png"])
    (path, bad), = saved_figures
    assert not bad, bad
    assert len(fig.axes[0].get_title().splitlines()) > 2  # it was wrapped


CHAINS = [p for p in EXAMPLES if p.stem != "chandelier"]


@pytest.mark.parametrize("example", CHAINS, ids=lambda p: p.stem)
def test_the_longest_preview_title_fits(example, tmp_path, saved_figures, build_store):
    """With CAD the title also gives the as-built figure (the longest title): the design's
    own re-simulation stands in for the solids' here."""
    from dataclasses import replace

    from rodcad import pipeline
    from rodcad.outputs.preview import plot_chain

    r = build_store.result(example)  # the session's build (tests/test_determinism.py reads it too)
    r = replace(r, as_built=pipeline.AsBuilt(r.masses, np.zeros((r.n, 2)), r.equilibrium, r.distance))
    plot_chain(r, tmp_path / "preview.png")
    (path, bad), = saved_figures
    assert not bad, bad
