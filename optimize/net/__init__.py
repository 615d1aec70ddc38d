"""The numerics of a hanging net of rigid rods in 3D (three or more rods at a joint).

The problem and its node bodies (:mod:`.model`), energy, constraints and their sparse
derivatives (:mod:`.deriv`), Newton on the KKT system (:mod:`.newton`), the entry point
:func:`optimize.solve_net` with multi-start and self-stress tensions (:mod:`.solve`),
self-stresses, mechanisms and curvatures (:mod:`.modes`), statics at a target and the mass
design (:mod:`.statics`), hubs' socket turns solved with the masses (:mod:`.sockets`), the design (:mod:`.design`)
and its masses refined toward the least largest distance of the fit (:mod:`.refine`). Never imports
:mod:`optimize.chain`; what both kinds use sits at the top of :mod:`optimize`.
"""
