"""Labels of a basin mapper: what one initial condition on a section leads to.

A mapper (Attractors.jl's "initial condition -> label") iterates a section map from one point
and returns one of these labels; basins are the thin layer that applies a mapper over a grid
(:mod:`hybridpd.sweeps`).

``converged``
    The paper's criterion holds after the requested number of iterations of ``P``.
``not_converged``
    The iterations ran out without meeting the criterion.
``diverged``
    The state left the bounded region, became non-finite, or no further return came.
``zeno_sticking``
    Impacts accumulated and the contact stayed closed.
``unresolved``
    An iteration bound inside one return was hit.
``off_section``
    The point is not on the section (for the impact pair: ``z4 = y1 - y2 <= 0``).
``inadmissible``
    The point's state lies outside the admissible set (a contact's gap beyond its bounds):
    it is never iterated.
"""
from __future__ import annotations

__all__ = ["INADMISSIBLE", "LABELS", "OFF_SECTION"]

LABELS = ("converged", "not_converged", "diverged", "zeno_sticking", "unresolved", "off_section",
          "inadmissible")
OFF_SECTION = 5
INADMISSIBLE = 6
