"""Old import paths that keep working for one more release, with a ``DeprecationWarning``.

One import hook serves every moved module: :class:`MovedModuleFinder`, a meta path finder
installed by ``import hybridpd``, answers each old path of :data:`MOVED_MODULES` (and any
module below an old package path) with a small module that warns once when imported and hands
every attribute on to the module at the new place, so an old import gives the same objects.
Names that moved out of a module that still exists are served by that module's
``__getattr__`` (:func:`moved_names`), which warns on each access. After SciPy's
``_sub_module_deprecation``.

The new places are named by strings and imported with :mod:`importlib`, so nothing here adds
an import arrow between the package's layers. Every old path goes in version :data:`REMOVAL`.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import types
import warnings

__all__ = ["MOVED_APART", "MOVED_MODULES", "REMOVAL", "MovedModuleFinder", "install", "moved_names"]

#: The release that removes the old paths.
REMOVAL = "0.4.0"

#: Each module path that moved and the module that replaced it (a package's old path also
#: serves the modules below it).
MOVED_MODULES = {
    # moved in 0.2.0 (their old files at the package root are gone; the paths still import)
    "hybridpd.automaton": "hybridpd.hybrid.automaton",
    "hybridpd.basins": "hybridpd.pair.basins",
    "hybridpd.batch": "hybridpd.pair.batch",
    "hybridpd.continuation": "hybridpd.pair.continuation",
    "hybridpd.design": "hybridpd.pair.design",
    "hybridpd.events": "hybridpd.hybrid.events",
    "hybridpd.impactmap": "hybridpd.pair.impactmap",
    "hybridpd.impactpair": "hybridpd.pair.impactpair",
    "hybridpd.lti": "hybridpd.pair.lti",
    "hybridpd.naive": "hybridpd.pair.naive",
    "hybridpd.orbits": "hybridpd.pair.orbits",
    "hybridpd.regions": "hybridpd.pair.regions",
    "hybridpd.samples": "hybridpd.hybrid.samples",
    "hybridpd.sweep": "hybridpd.sweeps.sweep",
    "hybridpd.symbolic": "hybridpd.pair.symbolic",
    # moved in 0.3.0: what only the impact pair has lives with the pair
    "hybridpd.analysis.impactmap": "hybridpd.pair.impactmap",
    "hybridpd.analysis.orbits": "hybridpd.pair.orbits",
    "hybridpd.analysis.lti": "hybridpd.pair.lti",
    "hybridpd.analysis.boundaries": "hybridpd.pair.boundaries",
    "hybridpd.analysis.boundarymask": "hybridpd.pair.boundarymask",
    "hybridpd.analysis.testfunctions": "hybridpd.pair.testfunctions",
    "hybridpd.analysis.design": "hybridpd.pair.design",
    # the pair's package once at hybridpd.analysis.continuation, whose name is now the one
    # continuation engine (that module serves the pair's names): its submodules
    "hybridpd.analysis.continuation.branchio": "hybridpd.analysis.continuation",
    **{f"hybridpd.analysis.continuation.{m}": f"hybridpd.pair.continuation.{m}"
       for m in ("branch", "events", "newton", "switching", "symmetric", "trace")},
    "hybridpd.analysis.continuation.plot": "hybridpd.plotting.branches",
    "hybridpd.pair.continuation.plot": "hybridpd.plotting.branches",
    "hybridpd.analysis.hybridcont": "hybridpd.analysis.continuation",
    "hybridpd.analysis.bifdiagram": "hybridpd.pair.bifdiagram",
    "hybridpd.analysis.attractors": "hybridpd.pair.attractors",
    "hybridpd.sweeps.basins": "hybridpd.pair.basins",
    "hybridpd.sweeps.attractor_basins": "hybridpd.pair.basins",
    "hybridpd.pair.attractor_basins": "hybridpd.pair.basins",
    "hybridpd.sweeps.diagram_sweep": "hybridpd.pair.bifdiagram",
    # the executor sweep of diagrams is generic (hybridpd.sweeps.diagrams); the pair's
    # pair_diagram is served, with its old signature, by hybridpd.pair.bifdiagram
    "hybridpd.pair.diagram_sweep": "hybridpd.pair.bifdiagram",
    "hybridpd.analysis.sections": "hybridpd.mechanics.sections",
    "hybridpd.sweeps.basin_result": "hybridpd.analysis.basins",
}


#: Names of an old module of :data:`MOVED_MODULES` that went to another module than the rest.
MOVED_APART = {
    "hybridpd.analysis.sections": {"impact_pair_section": "hybridpd.pair.section"},
}


def _message(old: str, new: str) -> str:
    return (f"{old} is deprecated and will be removed in hybridpd {REMOVAL}; "
            f"import it from {new} instead")


def _target(fullname: str) -> str | None:
    """The new module of an old path: an entry of :data:`MOVED_MODULES`, or a module below a
    moved package (the longest moved prefix)."""
    if fullname in MOVED_MODULES:
        return MOVED_MODULES[fullname]
    best = None
    for old in MOVED_MODULES:
        if fullname.startswith(old + ".") and (best is None or len(old) > len(best)):
            best = old
    return None if best is None else MOVED_MODULES[best] + fullname[len(best):]


class _Forward(importlib.abc.Loader):
    """Makes the old module: it warns and forwards every attribute to the new one."""

    def __init__(self, new: str):
        self.new = new

    def create_module(self, spec):
        return None          # the default module object

    def exec_module(self, module):
        old, new = module.__name__, self.new
        warnings.warn(_message(f"the module {old}", new), DeprecationWarning, stacklevel=2)
        target = importlib.import_module(new)

        apart = MOVED_APART.get(old, {})

        def __getattr__(name):
            if name in apart:
                return getattr(importlib.import_module(apart[name]), name)
            try:
                return getattr(target, name)
            except AttributeError:
                raise AttributeError(f"module {old!r} (deprecated, now {new!r}) has no "
                                     f"attribute {name!r}") from None

        module.__getattr__ = __getattr__
        module.__dir__ = lambda: sorted(set(dir(target)))
        module.__doc__ = (f"Deprecated: this module moved to {new} and goes in hybridpd "
                          f"{REMOVAL}.")
        if hasattr(target, "__path__"):
            module.__path__ = []      # an old package: modules below it import too
        if callable(getattr(target, old.rsplit(".", 1)[1], None)):
            # importing hybridpd.design binds the module to the package's attribute 'design',
            # the flat namespace's function: calling the module keeps that name working
            module.__class__ = _CallableModule


class _CallableModule(types.ModuleType):
    """An old module named like a function of its new module: calling it calls that."""

    def __call__(self, *args, **kwargs):
        target = importlib.import_module(_target(self.__name__))
        return getattr(target, self.__name__.rsplit(".", 1)[1])(*args, **kwargs)


class MovedModuleFinder(importlib.abc.MetaPathFinder):
    """The meta path finder that serves the old module paths (module docstring)."""

    def find_spec(self, fullname, path=None, target=None):
        if not fullname.startswith("hybridpd."):
            return None
        new = _target(fullname)
        if new is None:
            return None
        return importlib.util.spec_from_loader(fullname, _Forward(new))


def install() -> None:
    """Put the finder on ``sys.meta_path`` once (``import hybridpd`` does this)."""
    if not any(isinstance(f, MovedModuleFinder) for f in sys.meta_path):
        sys.meta_path.append(MovedModuleFinder())


def moved_names(module: str, moves: dict):
    """Return a module ``__getattr__`` that serves names moved out of ``module``.

    Parameters
    ----------
    module : str
        The old module's ``__name__``.
    moves : dict of str to str
        Each moved name and the dotted path of the module that now holds it (given as a string
        so that the old module does not import the new one), or ``"module:new_name"`` for a
        name that was also renamed.

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
        new, _, new_name = new.partition(":")
        new_name = new_name or name
        warnings.warn(_message(f"{module}.{name}", f"{new}.{new_name} (or hybridpd.{new_name})"
                               if _is_public(new_name) else f"{new}.{new_name}"),
                      DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module(new), new_name)

    return __getattr__


def _is_public(name: str) -> bool:
    top = importlib.import_module("hybridpd")
    return name in getattr(top, "__all__", ())
