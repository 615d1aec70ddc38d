"""A net's linear programs: HiGHS through SciPy, the method chosen by the net's size.

Units: none (the programs come scaled from :mod:`optimize.net.statics`).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog

__all__ = ["LP_PRESOLVED_ITERATIONS", "LP_SIMPLEX_RODS", "net_linprog"]

#: Nets of more rods than this solve their linear programs by HiGHS's interior point method
#: (with crossover to a vertex) instead of its dual simplex: on 2,000-rod nets whose rods'
#: buildable masses are a few micrograms wide, the simplex ran 46 s into "numerical
#: difficulties" where the interior point said "infeasible" in 0.4 s; smaller nets keep the
#: simplex they were designed with.
LP_SIMPLEX_RODS = 300

#: The interior point's iterations with presolve before the same program is solved without it
#: (:func:`net_linprog`). Presolved, a 2,112-rod grid's programs took 0.02-1.3 s where unpresolved
#: they took 0.2-5 s, their vertices as exact or more (a margin's inequalities held to 6e-9
#: where unpresolved they were 5.5e-6 off), and every one of its 16 infeasible programs said so
#: either way; but two of its 31 ran on (47 s to the optimum, 40 s to "numerical
#: difficulties") where unpresolved they took 1.2 and 1.3 s. Those reach this many iterations
#: within a second (the others took 3-14): a count, not a time, so a design is the same on
#: every machine.
LP_PRESOLVED_ITERATIONS = 100


def net_linprog(c: np.ndarray, m: int, **program):
    """``scipy.optimize.linprog(c, **program)`` for a net of ``m`` rods: HiGHS's dual simplex
    up to :data:`LP_SIMPLEX_RODS` rods, beyond that its interior point with presolve and, where
    that does not end optimal or infeasible within :data:`LP_PRESOLVED_ITERATIONS`, without."""
    if m <= LP_SIMPLEX_RODS:
        return linprog(c, method="highs", **program)
    lp = linprog(c, method="highs-ipm", options={"maxiter": LP_PRESOLVED_ITERATIONS}, **program)
    if lp.status in (0, 2):
        return lp
    return linprog(c, method="highs-ipm", options={"presolve": False}, **program)
