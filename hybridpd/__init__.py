"""hybridpd: analysis and design of PD control for mechanical systems with dynamic backlash.

The package follows the paper "Analysis of PD control of mechanical systems with dynamic
backlash" (Mata-Jimenez, Brogliato, Goswami) with the conventions of CONVENTIONS.md
(the repository's conventions page): state order ``[x1, y1, x2, y2, pc, ps]``, reference
``xd = xm cos(w t)``, Poincare section ``z3 = x1 - x2 = +L`` (pre-impact) with coordinates
``(phi, z1, z2, z4)``.

Everything a workflow needs is one attribute away, ``import hybridpd as hp``:

====================  =====================================================================
the impact pair       :class:`ImpactPair`, :class:`PDGains`, :class:`Reference`,
                      :class:`ControlledImpactPair`, :func:`symmetric_orbit`,
                      :func:`symmetric_orbits`, :class:`ImpactMap`,
                      :func:`certified_map`, :func:`verify_certificate`
any hybrid automaton  :class:`HybridAutomaton`, :class:`Section`, :class:`SectionMap`,
                      :func:`find_orbit`, :class:`PeriodicOrbit`, :func:`stability`
mechanical systems    :class:`MechanicalSystem`, :class:`Contact`, :func:`load_model`,
                      :func:`simulate`
continuation          :func:`continue_orbit` (of a :class:`ParameterFamily`),
                      :func:`switch_branch`, :func:`boundary_curves`,
                      :func:`bifurcation_diagram`
sweeps                :func:`region_map`, :func:`basin_of_attraction` (of a :func:`mapper`),
                      :func:`run_sweep`
design, figures       :func:`design`, :func:`reproduce`, :func:`plot_file`
the page              :func:`explore` (the region map as a page you click; Panel, Bokeh)
====================  =====================================================================

The names load lazily (PEP 562): ``import hybridpd`` imports NumPy only, and each name brings
in just the modules it needs (SymPy, numba, python-control, matplotlib and xarray only where
they are used; Panel and Bokeh only when :func:`explore` builds a page). The subpackages
(``hybridpd.hybrid``, ``pair``, ``mechanics``, ``analysis``, ``sweeps``, ``plotting``,
``reproduce``, ``explore``) stay importable for everything else.

Starting is cheap: the SymPy derivations of the closed forms run once per installation and
version; their generated code is cached on disk (see :mod:`hybridpd._codecache`). numba
compiles a kernel on its first large call; a small call (one orbit, a short simulation) runs
the same kernel as plain Python while numba is not loaded (see :mod:`hybridpd._jit`).

Every public function validates its input: a wrong type, shape or value raises
``ValueError`` naming the parameter and its allowed range. Result objects print on one line,
with array shapes.

Examples
--------
>>> import hybridpd as hp
>>> orb = hp.symmetric_orbit(hp.ImpactPair(mu=0.1, e=0.5, L=0.75), hp.PDGains(10, 20),
...                          omega=5.0, case="collocated")
>>> bool(orb.exists), bool(orb.stable)
(True, True)
"""
import importlib as _importlib

from hybridpd._version import __version__

# Each public name and the module that defines it. Nothing below is imported until used.
_NAMES = {
    # parameters and the impact pair
    "Case": "hybridpd.model",
    "ImpactPair": "hybridpd.model",
    "PDGains": "hybridpd.model",
    "PairParams": "hybridpd.pair.params",
    "Reference": "hybridpd.model",
    "virtual_restitution": "hybridpd.model",
    "ControlledImpactPair": "hybridpd.pair.impactpair",
    "symmetric_orbit": "hybridpd.pair.orbits",
    "symmetric_orbits": "hybridpd.pair.orbits",
    "certify_orbit": "hybridpd.pair.certified_orbit",
    "certified_map": "hybridpd.pair.certified",
    "verify_certificate": "hybridpd.pair.certificate",
    "load_certificate": "hybridpd.pair.certificate",
    "ImpactMap": "hybridpd.pair.impactmap",
    # the map protocol: any map a user writes
    "PoincareMap": "hybridpd.analysis.maps",
    "MapResult": "hybridpd.analysis.maps",
    # any hybrid automaton: sections, maps, orbits, stability
    "HybridAutomaton": "hybridpd.hybrid.automaton",
    "Section": "hybridpd.hybrid.section",
    "SectionMap": "hybridpd.analysis.hybridmap",
    "find_orbit": "hybridpd.analysis.periodic",
    "PeriodicOrbit": "hybridpd.analysis.periodic",
    "mapper": "hybridpd.analysis.mappers",
    "stability": "hybridpd.analysis.floquet",
    "Stability": "hybridpd.analysis.floquet",
    # general mechanical systems
    "MechanicalSystem": "hybridpd.mechanics.system",
    "Contact": "hybridpd.mechanics.contacts",
    "load_model": "hybridpd.mechanics.modelfile",
    "simulate": "hybridpd.mechanics.simulate",
    # continuation, boundaries, diagrams
    "continue_orbit": "hybridpd.analysis.continuation",
    "ParameterFamily": "hybridpd.analysis.family",
    "switch_branch": "hybridpd.pair.continuation",
    "load_branch": "hybridpd.analysis.continuation",
    "boundary_curves": "hybridpd.pair.boundaries",
    "bifurcation_diagram": "hybridpd.analysis.diagrams",
    # sweeps and result files
    "run_sweep": "hybridpd.sweeps.sweep",
    "region_map": "hybridpd.sweeps.regions",
    "load_region_map": "hybridpd.sweeps.regions",
    "basin_of_attraction": "hybridpd.sweeps.basins",
    "load_basin": "hybridpd.analysis.basins",
    # design, figures, the paper
    "design": "hybridpd.pair.design",
    "plot_file": "hybridpd.plotting.files",
    # the page (a callable package, as ``reproduce``: served from _SUBPACKAGES)
    "explore": "hybridpd.explore"}

# ``reproduce`` is both a subpackage and its main function: the package is callable (it runs
# :func:`hybridpd.reproduce.reproduce`), so ``hp.reproduce(...)`` works whichever Python binds.
# ``explore`` likewise (:func:`hybridpd.explore.explore`).
_SUBPACKAGES = ("analysis", "explore", "hybrid", "mechanics", "pair", "plotting", "reproduce",
                "sweeps")

# the flat namespace: every name of _NAMES, the version and ``reproduce``
__all__ = ["Case", "Contact", "ControlledImpactPair", "HybridAutomaton", "ImpactMap",
           "ImpactPair", "MapResult", "MechanicalSystem", "PDGains", "PairParams",
           "ParameterFamily",
           "PeriodicOrbit", "PoincareMap",
           "Reference", "Section", "SectionMap", "Stability", "__version__",
           "basin_of_attraction", "bifurcation_diagram", "boundary_curves",
           "certified_map", "certify_orbit", "continue_orbit", "design", "explore", "find_orbit", "load_basin", "load_branch",
           "load_certificate", "load_model", "load_region_map", "mapper", "plot_file", "region_map", "reproduce", "run_sweep", "simulate", "stability", "switch_branch",
           "symmetric_orbit", "symmetric_orbits", "verify_certificate", "virtual_restitution"]


def __getattr__(name):
    if name in _SUBPACKAGES:    # before _NAMES: ``explore`` is its callable package
        return _importlib.import_module(f"hybridpd.{name}")
    module = _NAMES.get(name)
    if module is not None:
        value = getattr(_importlib.import_module(module), name)
        globals()[name] = value  # later look-ups skip __getattr__
        return value
    raise AttributeError(f"module 'hybridpd' has no attribute {name!r}")


def __dir__():
    return sorted([*__all__, *_SUBPACKAGES])
