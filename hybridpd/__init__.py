"""hybridpd: analysis and design of PD control for mechanical systems with dynamic backlash.

The package follows the paper "Analysis of PD control of mechanical systems with dynamic
backlash" (Mata-Jimenez, Brogliato, Goswami) with the conventions of CONVENTIONS.md
(the repository's conventions page): state order ``[x1, y1, x2, y2, pc, ps]``, reference
``xd = xm cos(w t)``, Poincare section ``z3 = x1 - x2 = +L`` (pre-impact) with coordinates
``(phi, z1, z2, z4)``.

Starting is cheap: importing the package loads NumPy only. The SymPy derivations of the
closed forms run once per installation and version; their generated code is cached on disk
(``$HYBRIDPD_CACHE_DIR``, else ``$XDG_CACHE_HOME/hybridpd`` or ``~/.cache/hybridpd``; see
:mod:`hybridpd._codecache`). numba compiles a kernel on its first large call; a small call
(one orbit, a short simulation) runs the same kernel as plain Python while numba is not
loaded (see :mod:`hybridpd._jit`). The PD closed loop is written out directly; python-control
is imported only for general LTI controllers (its interconnection stays the reference the
tests check the PD matrices against).

Every public function validates its input: a wrong type, shape or value raises
``ValueError`` naming the parameter and its allowed range (see the ``check_*`` helpers of
:mod:`hybridpd.model`). Result objects print on one line, with array shapes.
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
