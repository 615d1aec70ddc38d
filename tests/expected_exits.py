"""What the shipped examples are expected to do that is not plain success."""

from __future__ import annotations

from pathlib import Path

#: Shipped examples whose best fit misses the default tolerance: `rodcad build` exits 1 and
#: writes the best fit beside OUTDIR. semicircle-weights (weights alone, one outer shell)
#: fitted 0.98 % of its size with weightless pins; its joints' hardware (pins, bushings,
#: bearings: 0.4-0.6 g on its lightest rods) takes it to about 1.09 %, and even weightless pins
#: with their sleeves and holes leave 1.00002 %: only stops (the planner's default) hold it.
#: dome (a grid hung from its four corners) cannot hang on a surface drawn over a rectangle: a
#: node of its straight border has nothing pulling it outward (the example says so).
EXPECTED_EXIT = {"semicircle-weights": 1, "dome": 1}


def built_folder(out: Path, code: int) -> Path:
    """Where a build's files are: OUTDIR, or OUTDIR.best-fit after exit 1."""
    return out if code == 0 else out.with_name(out.name + ".best-fit")
