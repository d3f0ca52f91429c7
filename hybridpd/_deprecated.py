"""Old import paths that keep working for one release, with a ``DeprecationWarning``.

Two kinds of shim, after SciPy's ``_sub_module_deprecation``:

* a **moved module** (``hybridpd.orbits`` is now ``hybridpd.analysis.orbits``): the old path is a
  small module that warns once when imported and hands every attribute on to the new module;
* a **moved name** (``hybridpd.sweeps.basins.attractor_basin`` is now in
  ``hybridpd.sweeps.attractor_basins``): the old module's ``__getattr__`` warns on each access
  and returns the object from its new place.

The new place is named by string and imported with :mod:`importlib`, so a shim adds no import
arrow between the package's layers. Every shim goes in version :data:`REMOVAL`.
"""
from __future__ import annotations

import importlib
import warnings

__all__ = ["MOVED_MODULES", "REMOVAL", "moved_module", "moved_names"]

#: The release that removes the shims.
REMOVAL = "0.3.0"

#: Each module path that moved (its old file is now a shim) and the module that replaced it.
MOVED_MODULES = {
    "hybridpd.automaton": "hybridpd.hybrid.automaton",
    "hybridpd.basins": "hybridpd.sweeps.basins",
    "hybridpd.batch": "hybridpd.pair.batch",
    "hybridpd.continuation": "hybridpd.analysis.continuation",
    "hybridpd.design": "hybridpd.analysis.design",
    "hybridpd.events": "hybridpd.hybrid.events",
    "hybridpd.impactmap": "hybridpd.analysis.impactmap",
    "hybridpd.impactpair": "hybridpd.pair.impactpair",
    "hybridpd.lti": "hybridpd.analysis.lti",
    "hybridpd.naive": "hybridpd.pair.naive",
    "hybridpd.orbits": "hybridpd.analysis.orbits",
    "hybridpd.regions": "hybridpd.sweeps.regions",
    "hybridpd.samples": "hybridpd.hybrid.samples",
    "hybridpd.sweep": "hybridpd.sweeps.sweep",
    "hybridpd.symbolic": "hybridpd.pair.symbolic",
    "hybridpd.analysis.continuation.branchio": "hybridpd.analysis.continuation.events"}


def _message(old: str, new: str) -> str:
    return (f"{old} is deprecated and will be removed in hybridpd {REMOVAL}; "
            f"import it from {new} instead")


def moved_module(old: str):
    """Warn that module ``old`` moved; return ``(__getattr__, __dir__)`` for ``old``.

    Parameters
    ----------
    old : str
        The shim's ``__name__``, a key of :data:`MOVED_MODULES` (which names the new module).

    Returns
    -------
    tuple of callable
        The shim module's ``__getattr__`` and ``__dir__``: every attribute comes from ``new``.
    """
    new = MOVED_MODULES[old]
    warnings.warn(_message(f"the module {old}", new), DeprecationWarning, stacklevel=3)
    target = importlib.import_module(new)

    def __getattr__(name):
        try:
            return getattr(target, name)
        except AttributeError:
            raise AttributeError(f"module {old!r} (deprecated, now {new!r}) has no attribute "
                                 f"{name!r}") from None

    def __dir__():
        return sorted(set(dir(target)))

    return __getattr__, __dir__


def moved_names(module: str, moves: dict):
    """Return a module ``__getattr__`` that serves names moved out of ``module``.

    Parameters
    ----------
    module : str
        The old module's ``__name__``.
    moves : dict of str to str
        Each moved name and the dotted path of the module that now holds it (given as a string
        so that the old module does not import the new one).

    Returns
    -------
    callable
        ``__getattr__(name)``: warns with ``DeprecationWarning`` naming the new place and returns
        the object; raises ``AttributeError`` for any other name.
    """

    def __getattr__(name):
        new = moves.get(name)
        if new is None:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        warnings.warn(_message(f"{module}.{name}", f"{new}.{name} (or hybridpd.{name})"
                               if _is_public(name) else f"{new}.{name}"),
                      DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module(new), name)

    return __getattr__


def _is_public(name: str) -> bool:
    top = importlib.import_module("hybridpd")
    return name in getattr(top, "__all__", ())
