"""The planner's joint limits kept: :func:`rodcad.catalog.jointlimits.joint_limits` (20-100 ms
a pair, marched from the rods' outlines) answered from this process's memory, then from the
disk cache and its seed files (:mod:`rodcad.catalog.cache`), and computed only where neither
has the pair. A plan asks for the same pairs again and again, and a design built again (by
another process, or after an edit elsewhere in it) asks for the ones it asked before.
"""

from __future__ import annotations

from functools import lru_cache

from rodcad.catalog.cache import DiskCache, make_key
from rodcad.catalog.jointlimits import joint_limits
from rodcad.catalog.model import RodGeometry

__all__ = ["CACHE_KIND", "JOINT_LIMITS_VERSION", "kept_joint_limits", "limits_key"]


#: The version of :func:`joint_limits` in the keys of its disk cache
#: (:func:`kept_joint_limits`): raise it with any change that moves a limit (the samples, the
#: membership tests, the march, the bisection,
#: :data:`rodcad.catalog.jointlimits.SAFETY_DEG`), so that limits kept on disk or shipped in a
#: seed file are computed again. tests/test_seed_cache.py compares the suite's seeded limits
#: with a fresh computation.
JOINT_LIMITS_VERSION = 1

#: The disk cache's kind for them.
CACHE_KIND = "jointlimits"


def limits_key(left: RodGeometry, right: RodGeometry) -> str:
    """The disk cache's key of a pair: both geometries' reprs (every field to the last digit)
    and :data:`JOINT_LIMITS_VERSION`."""
    return make_key(CACHE_KIND, JOINT_LIMITS_VERSION, repr(left), repr(right))


@lru_cache(maxsize=4096)
def kept_joint_limits(left: RodGeometry, right: RodGeometry) -> tuple[float | None, float | None]:
    """:func:`joint_limits`, kept in this process and in the disk cache
    (:class:`rodcad.catalog.cache.DiskCache`, its seed files too): a planner asks for the
    same pairs again and again, and a design built again (edited, or by another process)
    asks for the ones it asked before. Keyed by both geometries' reprs (every field to the
    last digit) and :data:`JOINT_LIMITS_VERSION`; a pair that overlaps at every bend is
    kept as that and raises as :func:`joint_limits` does.

    Raises:
        ValueError: the rods overlap at every angle tried as a start.
    """
    cache = DiskCache()
    key = limits_key(left, right)
    hit = cache.get(CACHE_KIND, key)
    if isinstance(hit, dict) and "error" in hit:
        raise ValueError(hit["error"])
    if isinstance(hit, dict) and "lo" in hit and "hi" in hit:
        return hit["lo"], hit["hi"]
    try:
        lo, hi = joint_limits(left, right)
    except ValueError as exc:
        cache.put(CACHE_KIND, key, {"error": str(exc)})
        raise
    cache.put(CACHE_KIND, key, {"lo": lo, "hi": hi})
    return lo, hi
