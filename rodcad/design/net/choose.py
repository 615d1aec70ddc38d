"""Where the planner's joints hang: the choice per net, checked against the physics.

A generated net's joints go on its target surface first (:func:`rodcad.design.net.plan.
plan_net`), where the design's masses can kink the rods to it; a net given by its edges
(explicit nodes, a mesh) has no surface between its nodes, and a joint on a straight edge
cannot hang (:mod:`rodcad.design.net.joints`): its joints go to the funicular sag below the
edge. Where the surface's joints leave the net off its tolerance, the funicular sag is
designed too and the better fit kept.
"""

from __future__ import annotations

from rodcad.design.net.check import NetCheck, design_net_plan
from rodcad.design.net.plan import plan_net
from rodcad.design.net.target import NetTarget

__all__ = ["design_drawn_net"]


def design_drawn_net(target: NetTarget, catalog, *, g: float = 9.81, seed: int = 0,
                     tolerance: float | None = None, n_starts: int | None = None) -> NetCheck:
    """The drawn net planned (:func:`rodcad.design.net.plan.plan_net`) and designed
    (:func:`rodcad.design.net.check.design_net_plan`), its joints where they hang best.

    Raises:
        DesignLimit: what no hardware in the catalog can do.
    """
    kw = dict(g=g, seed=seed, tolerance=tolerance, n_starts=n_starts)
    on_surface = target.surface is not None
    plan = plan_net(target, catalog, tolerance=tolerance, hang=not on_surface, g=g)
    check = design_net_plan(plan, **kw)
    joints = plan.target.joints
    if not on_surface or joints is None or not len(joints) or check.ok:
        return check
    other = design_net_plan(plan_net(target, catalog, tolerance=tolerance, hang=True, g=g), **kw)
    if other.ok and not check.ok or (other.ok == check.ok and other.rel_size < check.rel_size):
        other.notes.append("The two-rod joints hang at the funicular sag below their chords: on the target "
                           f"surface the net hung {100 * check.rel_size:.3g} % of its size off it.")
        return other
    return check
