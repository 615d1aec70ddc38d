"""CAD: the only package that imports build123d or OCP. Rod and frame solids, booleans,
collision queries, STEP/STL writing.

build123d is imported here first, with two of its imports deferred until they are used:
scikit-learn's DBSCAN (its STL import's primitive detection) and IPython's pretty printer
(shapes' ``_repr_pretty_``). rodcad uses neither, and importing them takes about a third of
build123d's import (scipy.stats comes with scikit-learn). The names build123d takes from
them are stand-ins that import the real module on first use; a later ``import sklearn`` or
``import IPython`` gets the real modules.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import Any

#: Modules build123d imports at its own import and rodcad never uses (deferred, see above).
DEFERRED_IMPORTS = ("sklearn.cluster", "IPython.lib.pretty")


class _Deferred:
    """A name from a module not imported yet: the module is imported when it is used."""

    def __init__(self, module: str, name: str) -> None:
        self._where = (module, name)

    def _target(self) -> Any:
        module, name = self._where
        return getattr(importlib.import_module(module), name)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self._target()(*args, **kwargs)

    def __getattr__(self, attr: str) -> Any:
        if attr.startswith("__"):
            raise AttributeError(attr)
        return getattr(self._target(), attr)

    def __repr__(self) -> str:
        return f"<deferred {'.'.join(self._where)}>"


class _DeferredModule(types.ModuleType):
    """Stands in for a module during build123d's import: every name is :class:`_Deferred`."""

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return _Deferred(self.__name__, name)


def _import_build123d() -> None:
    if "build123d" in sys.modules:
        return
    stubs = {name: _DeferredModule(name) for name in DEFERRED_IMPORTS if name not in sys.modules}
    sys.modules.update(stubs)
    try:
        import build123d  # noqa: F401
    finally:
        for name, stub in stubs.items():
            if sys.modules.get(name) is stub:
                del sys.modules[name]


_import_build123d()
