"""Distance between a target chain and a simulated one (Song, Feng, Zhou 2017, Sec. 4.2.1).

Both shapes are given by their joints ``p_0 .. p_N`` (the anchors included), in the
same order and the same length unit (millimetres in rodcad, hence the ``_mm`` keys of
:meth:`ShapeDistance.as_dict`). The paper's two descriptors are

    Eq. 4   D~(T, S) = sum_i |p_T,i - p_S,i|      (the Euclidean distance, a scalar)
    Eq. 5   D(T, S)  = sum_i (p_T,i - p_S,i)      (the deviation vector, signed)

Eq. 5 is called a "weighted sum" in the paper but no weights are given; every joint
has weight 1 here, exactly as the equation is printed. ``D`` tells *which way* the
simulated shape is off: a chain that sags too low has ``D`` pointing up (target minus
simulated), one that sags too little has ``D`` pointing down, though both may have the
same ``D~`` (the paper's Fig. 3b). The guided PSO (:mod:`optimize.chain.pso`) uses it.

numpy only; never imports rodcad or build123d.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from optimize.validate import as_joints

__all__ = ["ShapeDistance", "shape_distance"]


@dataclass
class ShapeDistance:
    """How far a simulated chain is from its target.

    Attributes:
        sum: the paper's D~ (Eq. 4), sum over joints of |p_T - p_S| (length unit).
        deviation: the paper's deviation vector D (Eq. 5), sum over joints of
            (p_T - p_S), shape (2,) (length unit). Points from the simulated shape
            towards the target, on balance.
        max: largest joint distance |p_T,i - p_S,i|.
        mean: mean joint distance, ``sum / (N + 1)``.
        max_rel_span: ``max / |B - A|`` with ``A = target[0]``, ``B = target[-1]``;
            ``inf`` if the target's anchors coincide and ``max > 0`` (0 if both are 0).
    """

    sum: float
    deviation: np.ndarray
    max: float
    mean: float
    max_rel_span: float

    def as_dict(self) -> dict:
        """JSON-friendly summary (plain floats; a non-finite ``max_rel_span`` becomes None).

        Keys: ``sum_mm``, ``max_mm``, ``mean_mm``, ``max_rel_span``, ``deviation`` ([x, y]).
        The ``_mm`` suffix assumes rodcad's millimetre convention; the numbers are in
        whatever unit the joints were given in.
        """
        rel = float(self.max_rel_span)
        return {
            "sum_mm": float(self.sum),
            "max_mm": float(self.max),
            "mean_mm": float(self.mean),
            "max_rel_span": rel if math.isfinite(rel) else None,
            "deviation": [float(v) for v in np.asarray(self.deviation).reshape(2)],
        }


def shape_distance(target, simulated) -> ShapeDistance:
    """The paper's shape distance D~ (Eq. 4), deviation vector D (Eq. 5) and summaries.

    Args:
        target: (N+1, 2) joints of the target shape T, anchors first and last.
        simulated: (N+1, 2) joints of the simulated shape S, same order.

    Returns:
        ShapeDistance.

    Raises:
        ValueError: an argument is not an (N+1, 2) array of finite numbers, or the
            two have different shapes (the message names the argument).

    Example:
        >>> t = [[0, 0], [1, -1], [2, 0]]
        >>> d = shape_distance(t, [[0, 0], [1, -2], [2, 0]])
        >>> d.sum, d.deviation.tolist(), d.max_rel_span
        (1.0, [0.0, 1.0], 0.5)
    """
    t = as_joints("target", target)
    s = as_joints("simulated", simulated)
    if s.shape != t.shape:
        raise ValueError(
            f"simulated has shape {s.shape} but target has shape {t.shape}; "
            "both must list the same N+1 joints"
        )
    diff = t - s
    dist = np.hypot(diff[:, 0], diff[:, 1])
    total = float(dist.sum())
    biggest = float(dist.max())
    span = float(np.hypot(*(t[-1] - t[0])))
    if span > 0:
        rel = biggest / span
    else:
        rel = math.inf if biggest > 0 else 0.0
    return ShapeDistance(
        sum=total,
        deviation=diff.sum(axis=0),
        max=biggest,
        mean=total / dist.size,
        max_rel_span=rel,
    )
