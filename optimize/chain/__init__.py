"""The numerics of a hanging chain of rigid rods in a plane.

The problem and its active sets (:mod:`.model`, :class:`Chain`), the exact constrained
equilibrium (:mod:`.equilibrium`, with :mod:`.dual`, :mod:`.branches`, the anchor stops'
conventions in :mod:`.endlimits` and the paper's penalty model in :mod:`.penalty`),
multi-start (:mod:`.multistart`), statics at a target (:mod:`.problem`, :mod:`.statics`),
inverse design (:mod:`.inverse`, :mod:`.pso`, :mod:`.sensitivity`), the target laid into
rods (:mod:`.discretize`, :mod:`.curves`) and their stops (:mod:`.assign`, :mod:`.stops`,
:mod:`.verify`), and the chain as printed: pins in their holes (:mod:`.pins`,
:mod:`.pinplay`, :mod:`.compensate`), pin friction (:mod:`.friction`) and mass tolerance
(:mod:`.tolerance`). Never imports :mod:`optimize.net`; what both kinds use sits at the top
of :mod:`optimize`.
"""

from optimize.chain.model import Chain

__all__ = ["Chain"]
