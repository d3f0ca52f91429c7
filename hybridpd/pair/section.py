"""The paper's Poincaré section of the controlled impact pair, as a section of its automaton."""
from __future__ import annotations

import numpy as np

from hybridpd.hybrid.section import Section

__all__ = ["impact_pair_section"]


def impact_pair_section(system, wall: int = 1) -> Section:
    """The paper's section of a :class:`~hybridpd.pair.impactpair.ControlledImpactPair`.

    Pre-impact states on the ``wall`` (``+1``: ``z3 = +L``), coordinates
    ``(phi, z1, z2, z4, c_1, ...)`` = ``(t mod T, x2, y2, y1 - y2, controller states)``.
    """
    if wall not in (1, -1):
        raise ValueError(f"wall must be +1 or -1, got {wall!r}")
    ha = system.automaton
    n = ha.n_states
    rows = [np.eye(n)[2], np.eye(n)[3], np.eye(n)[1] - np.eye(n)[3]]
    rows += [np.eye(n)[i] for i in range(6, n)]
    names = ("z1", "z2", "z4") + tuple(ha.state_names[6:])
    T = system.reference.period
    return Section(ha, "free", "wall+" if wall == 1 else "wall-", exo=(4, 5), period=T,
                   exo_state=system.reference.exo_state(0.0), coords=np.array(rows),
                   names=names)
