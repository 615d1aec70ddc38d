"""Design files: what a user asks ``rodcad build`` / ``rodcad simulate`` for.

A design file is YAML (units: mm, g, degrees)::

    design: 1                     # format version
    name: semicircle              # default output folder outputs/<name>
    catalog: pla-pinned           # shipped catalog name, or a path relative to this file
                                  # (default: pla-parametric, rods printed to order)
    anchors: [[0, 0], [200, 0]]   # anchor A and anchor B (mm, y up)
    target:                       # the shape to hang in (for `build`)
      form: semicircle            # polyline, arc, semicircle, triangle, polygon, heart,
                                  # catenary, function, svg (see rodcad.design.targets)
    constraints:                  # optional
      types: [free-20, free-30]   # rod types allowed (default: all)
      lengths: [30]               # rod lengths allowed (default: all)
      rods: 8                     # number of rods (default: what the chord walk gives)
      fixed:                      # rods whose type (and mass) is imposed
        - {index: 0, type: free-30, mass: 6.5}
      joints: free                # no stops: weights alone (default: any)
      same_shell: true            # rods printed to order: one outer shell for every rod
    method: refine                # exact, refine (default), guided-pso, pso
    seed: 0
    tolerance: 0.01               # optional: largest acceptable error / span
    fabrication: {cad: true, seed: 0}

or, for ``rodcad simulate``, an explicit chain instead of (or besides) a target::

    chain:
      - {type: free-30, mass: 6.5}
      - {type: straight-30}       # mass defaults to the type's solid mass

Loading checks everything at once (:func:`load_design`): schema problems, then
names against the catalog (did-you-mean), the target's parameters and the
anchors against the chain's reach, each reported as ``FILE:LINE:COL: key.path:
message``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rodcad.catalog.model import Catalog
from rodcad.errors import Problem
from rodcad.yamlspec import Checked

__all__ = ['ANCHOR_STOP_MODES', 'DEFAULT_CATALOG', 'FUSE_MODES', 'DESIGN_FORMAT', 'JOINT_MODES', 'METHOD_NAMES', 'FixedRod', 'Constraints', 'ChainRod', 'ChandelierSpec', 'Design']


#: Design file format this rodcad reads.
DESIGN_FORMAT = 1


#: The shipped catalog a design file that names none uses: PLA rods printed to order.
DEFAULT_CATALOG = "pla-parametric"


#: ``constraints.joints``: 'any' lets joints rest on stops, 'free' forbids stops.
JOINT_MODES = ("any", "free")

#: ``constraints.anchor_stops``: 'auto' (the anchor fixture may stop the first and last rods
#: where the shape needs it: what the planner does when the design says nothing) or 'none'
#: (bare pins).
ANCHOR_STOP_MODES = ("auto", "none")

#: ``constraints.fuse``: 'auto' (rods are printed as one piece where a bend is sharper than
#: any stop the family prints: what the planner does when the design says nothing), 'never'
#: (or 'none': no fused pieces) or 'stops' (also every run of joints resting on stops is
#: printed as one rigid piece, where it fits the printer).
FUSE_MODES = ("auto", "never", "none", "stops")


#: Inverse-design methods (mirrors optimize.chain.inverse.METHODS).
METHOD_NAMES = ("exact", "refine", "guided-pso", "pso")


@dataclass(frozen=True)
class FixedRod:
    """A rod whose type (and optionally mass) the user imposes.

    Attributes:
        index: position in the chain (0 = the rod at anchor A).
        type: rod type name.
        mass: imposed mass (g), or None to let the design choose it.
    """

    index: int
    type: str
    mass: float | None = None


@dataclass(frozen=True)
class Constraints:
    """Optional restrictions on the designed chain.

    Attributes:
        types: rod type names allowed (None: all).
        lengths: rod lengths allowed (mm; None: all).
        rods: number of rods (None: what the chord walk gives).
        preferred_length: the length to use most (mm; None: chosen by the walk).
        fixed: imposed rods.
        joints: 'any' (stops where the masses cannot hold a bend) or 'free' (no stops:
            weights alone, the best fit where they cannot hold the shape).
        same_shell: a family printed to order makes every rod of the chain with one outer
            shell (one length, one curvature, the family's own ends); masses then differ
            only inside (the paper's Fig. 7).
        anchor_stops: 'auto', 'none' (:data:`ANCHOR_STOP_MODES`) or None: not given (the
            planner decides: 'auto' for rods printed to order, bare pins for a fixed menu).
        anchor_limits_deg: bounds [lo, hi] on the absolute angles of the first and of the
            last rod (deg from +x) that the anchor fixture imposes, or None per end.
        robust: the design file's top-level ``robust`` (held here, where the planner reads
            it): prefer designs whose friction and mass bands stay within the tolerance.
        fuse: 'auto', 'never' ('none'), 'stops' (:data:`FUSE_MODES`) or None: not given
            (the planner decides: 'auto' for rods printed to order).
    """

    types: tuple[str, ...] | None = None
    lengths: tuple[float, ...] | None = None
    rods: int | None = None
    preferred_length: float | None = None
    fixed: tuple[FixedRod, ...] = ()
    joints: str = "any"
    same_shell: bool = False
    anchor_stops: str | None = None
    anchor_limits_deg: tuple[tuple[float, float] | None, tuple[float, float] | None] = (None, None)
    fuse: str | None = None
    robust: bool = True

    @property
    def anchor_stops_allowed(self) -> bool:
        """The planner may stop the end rods at the fixture: unless the design says 'none',
        or forbids every stop (``joints: free``, weights alone) without asking for them."""
        if self.anchor_stops is None:
            return self.joints != "free"
        return self.anchor_stops == "auto"

    @property
    def fuse_mode(self) -> str:
        """'auto' (also when not given), 'never' or 'stops'."""
        return {None: "auto", "none": "never"}.get(self.fuse, self.fuse)

    @property
    def end_limits(self) -> np.ndarray | None:
        """``anchor_limits_deg`` as (2, 2) radians (None: both ends bare pins)."""
        if self.anchor_limits_deg == (None, None):
            return None
        return np.radians([lim if lim is not None else (-np.inf, np.inf) for lim in self.anchor_limits_deg])


@dataclass(frozen=True)
class ChainRod:
    """One rod of an explicit chain: its type and mass (g)."""

    type: str
    mass: float


@dataclass(frozen=True)
class ChandelierSpec:
    """A design file's ``chandelier`` block, checked.

    Attributes:
        pattern: 'ring', 'two-rings', 'polygon' or 'explicit'.
        params: the pattern's parameters as written (count, radius, vertices, ...).
        frame_kind: the frame to build ('ring', 'two_rings' or 'bars').
        frame: the frame's options (width, thickness, ...), without its kind.
        vertices: the polygon's vertices (mm), or None.
        written: the block as written, less its per-chain entries (for design.json).
    """

    pattern: str
    params: dict[str, Any]
    frame_kind: str
    frame: dict[str, Any]
    vertices: list[list[float]] | None
    written: dict[str, Any]


@dataclass
class Design:
    """A validated design file.

    Attributes:
        path: the design file.
        name: design name (default output folder ``outputs/<name>``).
        description: free text.
        catalog: the loaded rod catalog.
        catalog_ref: the catalog as written in the file.
        anchors: (2, 2) anchors A and B (mm).
        target_form: target form name, or None (explicit chain only).
        target_params: the form's parameters.
        target_curve: (M, 2) dense target polyline from A to B, or None.
        chain: explicit chain, or None.
        constraints: restrictions on the designed chain.
        method: inverse-design method.
        seed: random seed of the design (PSO, multi-start).
        tolerance: largest acceptable max error / span, or None.
        g: gravitational acceleration (m/s^2; only scales moments and reactions).
        cad: build the solids (False: design and check only).
        fabrication_seed: seed of the cavity layouts.
        source: the checked document (positions of every key, for later problems).
    """

    path: Path
    name: str
    description: str
    catalog: Catalog
    catalog_ref: str
    anchors: np.ndarray
    target_form: str | None
    target_params: dict[str, Any]
    target_curve: np.ndarray | None
    chain: list[ChainRod] | None
    constraints: Constraints
    method: str
    seed: int
    tolerance: float | None
    g: float
    cad: bool
    fabrication_seed: int
    source: Checked | None = field(default=None, repr=False)
    chandelier: ChandelierSpec | None = None
    placements: list[Any] | None = None
    chain_targets: list[dict[str, Any]] | None = None
    net: Any = None  # rodcad.design.net.target.NetTarget for a net design (three or more rods at a joint)

    @property
    def span(self) -> float:
        """Distance between the anchors (mm)."""
        return float(np.hypot(*(self.anchors[1] - self.anchors[0])))

    def problem(self, key: str, message: str) -> Problem:
        """A problem pointing at ``key`` in the design file (for later stages)."""
        pos = self.source.pos(key) if self.source is not None else None
        return Problem(str(self.path), pos.line if pos else 0, pos.column if pos else 0, key, message)


