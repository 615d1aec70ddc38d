"""A hub that can be put together: printed as two halves split through its sockets' centres.

A hub (:func:`rodcad.cad.net.solids.hub_solid`) holds each rod's ball in a socket whose mouth is
narrower than the ball, so a whole hub cannot take its balls. Cut through the plane that
best fits its sockets' centres (least squares; with one or two sockets the plane through
them and the hub's centre), each socket is open at the cut ``2 sqrt(rs^2 - d^2)`` across
(``rs`` the socket's radius, ``d`` its centre's distance from the plane): wider than the
ball when ``d < sqrt(rs^2 - (ball / 2)^2)`` (less :data:`MARGIN`). Then each rod's ball is
laid in its socket (in either half), the rod's neck in its half cone, and the other half
glued on: the two halves are the hub solid cut in two (their union is the hub: the mass
model is unchanged). Each half prints on its flat cut face (no support: the half sockets
and cones are domes over the bed, a few mm across). A hub whose sockets lie further off
every plane is not split (:attr:`HubSplit.reason` says why).

Units: mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from build123d import Keep, Plane, Solid

from rodcad.cad.solids import GeometryError, one_solid, precise_volume

__all__ = ["MARGIN", "MAX_CLEARANCE", "HubSplit", "precise_volume", "split_hub", "split_plane", "splittable_sockets"]

#: How much closer (mm) than the ball's limit a socket's centre must lie to the cut.
MARGIN = 0.05
#: The widest socket clearance (mm; socket diameter less ball diameter) a hub's sockets are
#: widened to so that one cut admits every ball (:func:`splittable_sockets`).
MAX_CLEARANCE = 1.0


@dataclass
class HubSplit:
    """A hub as printed parts.

    Attributes:
        parts: the parts (hub frame), labelled ``<hub>-a`` / ``<hub>-b``, or [the hub] when
            it is not split.
        print_matrices: per part, the 4x4 rotation laying it on its cut face (hub frame to bed).
        normal, offset: the cut plane ``normal . x = offset`` (hub frame, mm).
        off_plane: the sockets' largest distance from it (mm).
        reason: '' when split, else why not.
        clearance: its sockets' clearance (mm, the hardware's it was split with: the catalog's,
            or wider where one cut would not admit the balls otherwise, :func:`splittable_sockets`);
            None for a node without a hub.
    """

    parts: list
    print_matrices: list
    normal: np.ndarray
    offset: float
    off_plane: float
    reason: str = ""
    clearance: float | None = None

    @property
    def split(self) -> bool:
        return not self.reason


def split_plane(sockets: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The plane through a hub's socket centres: (unit normal, offset, largest distance of a
    centre from it); least squares for three or more, else through the hub's centre."""
    p = np.asarray(sockets, float).reshape(-1, 3)
    pts = p if len(p) >= 3 else np.vstack([p, np.zeros((1, 3))])
    c = pts.mean(axis=0)
    _, s, vt = np.linalg.svd(pts - c)
    n = vt[-1]
    if len(p) == 1 or (len(s) > 1 and s[1] < 1e-9 * max(s[0], 1.0)):  # one axis: any plane along it
        a = p[0] / np.linalg.norm(p[0])
        n = np.cross(a, [0.0, 0.0, 1.0]) if abs(a[2]) < 0.9 else np.cross(a, [1.0, 0.0, 0.0])
        c = np.zeros(3)
    n = n / np.linalg.norm(n)
    if n[np.argmax(np.abs(n))] < 0:  # a canonical sign
        n = -n
    off = float(n @ c)
    return n, off, float(np.max(np.abs(p @ n - off)))


def _lay_flat(n: np.ndarray) -> np.ndarray:
    """4x4 rotation taking ``n`` (a part's direction away from its cut face) to +Z."""
    z = n / np.linalg.norm(n)
    x = np.cross([0.0, 1.0, 0.0], z) if abs(z[1]) < 0.9 else np.cross([1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    m = np.eye(4)
    m[:3, :3] = np.vstack([x, np.cross(z, x), z])
    return m


def split_hub(hub: Solid, sockets: np.ndarray, hw, name: str) -> HubSplit:
    """Cut ``hub`` (its sockets' centres ``sockets``, (k, 3) hub frame) into two halves that
    take their rods' balls (module docstring), or keep it whole with the reason.

    Raises:
        GeometryError: the cut leaves a half that is not one valid solid, or the halves'
            volumes do not add up to the hub's.
    """
    n, off, far = split_plane(sockets)
    rs = hw.socket_radius
    limit = math.sqrt(max(rs**2 - (hw.ball / 2) ** 2, 0.0)) - MARGIN
    if far > limit:
        return HubSplit([hub], [np.eye(4)], n, off, far,
                        f"its sockets' centres lie up to {far:.2f} mm off any plane; a cut admits a "
                        f"{hw.ball:g} mm ball within {limit:.2f} mm", clearance=hw.clearance)
    plane = Plane(tuple(float(v) for v in n * off), z_dir=tuple(float(v) for v in n))
    top, bottom = hub.split(plane, keep=Keep.BOTH)
    parts, mats = [], []
    for solid, suffix, up in ((top, "a", n), (bottom, "b", -n)):
        s = one_solid(solid, f"splitting {name}")
        if not s.is_valid:
            raise GeometryError(f"{name}-{suffix} is not a valid solid")
        s.label = f"{name}-{suffix}"
        parts.append(s)
        mats.append(_lay_flat(up))
    total, whole = sum(precise_volume(p) for p in parts), precise_volume(hub)
    if abs(total - whole) > 1e-7 * whole:
        raise GeometryError(f"{name}: its halves hold {total:.6f} mm^3, the hub {whole:.6f} mm^3")
    return HubSplit(parts, mats, n, off, far, clearance=hw.clearance)


def splittable_sockets(sockets: np.ndarray, pivots: np.ndarray, clearance: float, ball: float) -> tuple[np.ndarray, float]:
    """A hub's socket centres and the clearance that lets one cut admit every ball.

    A cut admits a ball through a socket whose centre lies within ``sqrt(rs^2 - (ball/2)^2)``
    of it (``rs`` the socket's radius, ``(ball + clearance) / 2``): sockets further off any
    plane (a node whose rods leave it far out of one plane) are widened, just enough (to at
    most :data:`MAX_CLEARANCE`), and each moved back against its rod's pull by half the new
    clearance (:func:`rodcad.catalog.net.node.socket_centres`), so the loaded ball still sits on
    its pivot: the net hangs as designed, the ball only rattles more when the rod is slack.

    Args:
        sockets: (k, 3) the socket centres at the catalog's clearance (hub frame, mm).
        pivots: (k, 3) the rods' pivots (the loaded balls' centres) in the same frame.
        clearance: the catalog's clearance (mm).
        ball: the rods' end balls' diameter (mm).

    Returns:
        (sockets (k, 3), clearance): as given where a cut admits the balls already, or
        where even :data:`MAX_CLEARANCE` does not.
    """
    socks = np.asarray(sockets, float).reshape(-1, 3)
    piv = np.asarray(pivots, float).reshape(-1, 3)
    pull = (piv - socks) / (clearance / 2) if clearance > 0 else np.zeros_like(socks)  # unit, or 0
    c, out = clearance, socks
    for _ in range(4):  # the off-plane distance moves with the sockets (by under a tenth of a mm)
        far = split_plane(out)[2]
        if far <= math.sqrt(max(((ball + c) / 2) ** 2 - (ball / 2) ** 2, 0.0)) - MARGIN:
            return out, c
        need = 2 * math.sqrt((ball / 2) ** 2 + (far + 2 * MARGIN) ** 2) - ball
        if need > MAX_CLEARANCE:
            return socks, clearance
        c = max(c, need)
        out = piv - 0.5 * c * pull
    return socks, clearance
