"""A net as a design: its ``net:`` block (:mod:`.spec`), the target it names (:mod:`.target`,
generated nets from :mod:`.layouts`), hubs and rods laid on it with their mass bounds
(:mod:`.plan`), hubs' sockets turned to balance and bounds narrowed to buildable masses
(:mod:`.hubs`), and the mass design with its exact check and fit (:mod:`.check`).
"""
