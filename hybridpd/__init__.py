"""hybridpd: analysis and design of PD control for mechanical systems with dynamic backlash.

The package follows the paper "Analysis of PD control of mechanical systems with dynamic
backlash" (Mata-Jimenez, Brogliato, Goswami) with the conventions fixed in the project's SPEC:
state order ``[x1, y1, x2, y2, pc, ps]``, reference ``xd = xm cos(w t)``, Poincare section
``z3 = x1 - x2 = +L`` (pre-impact) with coordinates ``(phi, z1, z2, z4)``.

Importing the package is cheap: SymPy derivations and numba kernels are built on first use.
"""
from hybridpd._version import __version__
from hybridpd.model import Case, ImpactPair, PDGains, Reference, virtual_restitution

__all__ = [
    "Case",
    "ImpactPair",
    "PDGains",
    "Reference",
    "__version__",
    "virtual_restitution",
]
