"""A net's solids: hubs, rods, their files, the assembly and the net as built
(:mod:`.solids`), a bent rod's body (:mod:`.bent`), hubs cut in two halves that take the balls
(:mod:`.hub`) and the print files through the chains' :mod:`rodcad.cad.printfile`
(:mod:`.print_files`).
"""
