"""Record (``--write``) or recompute the golden traced boundaries.

Cases: :func:`~hybridpd.pair.boundaries.boundary_curves` on three planes of
``tests/test_boundaries.py`` (collocated ``e = 0.1`` in ``(kp, kv)``: one grazing curve;
the non-collocated zoom at ``e = 0.5``: Neimark-Sacker, fold and period-doubling curves with
1:1 / 1:2 resonances and a fold + Neimark-Sacker point; collocated ``(gamma, omega)``: curves
ending where the orbit stops existing) and the reproduction's traced panel boundaries
(``reproduce/figures.py``'s tracing of one zoom panel, non-collocated ``e = 0.9``).
Recorded per curve: kind, ends, points (unit coordinates and parameters), largest test value;
per codim-2 point: kind, unit coordinates, multipliers, residual; and the result's counts.

Run from outside the repository with the package to record on the path:
``python tests/_golden_boundaries.py --write``.
"""
from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import _golden

PATH = _golden.DATA / "golden_boundaries.npz"
PAPER = dict(mu=0.1, gamma=0.75, omega=5.0)
PLANES = {
    "col_e01": ("collocated", dict(x=("kp", 0.1, 50.0), y=("kv", 0.1, 50.0), e=0.1)),
    "non_e05_zoom": ("noncollocated", dict(x=("kp", 0.1, 20.0), y=("kv", 0.1, 6.0), e=0.5)),
    "col_gamma_omega": ("collocated", dict(x=("gamma", 0.1, 0.95), y=("omega", 1.0, 10.0),
                                           e=0.1, kp=10.0, kv=2.0)),
}


def _plane_arrays(name, res) -> dict:
    out = {f"{name}.kinds": np.array([c.kind for c in res.curves]),
           f"{name}.ends": np.array([list(c.ends) for c in res.curves]).reshape(-1, 2),
           f"{name}.sizes": np.array([len(c) for c in res.curves], np.int64),
           f"{name}.max_test": np.array([c.max_test for c in res.curves]),
           f"{name}.codim2_kinds": np.array([q.kind for q in res.codim2]),
           f"{name}.counts": np.array([res.n_seeds, res.unresolved, res.uncovered,
                                       res.n_evals], np.int64)}
    out[f"{name}.u"] = (np.concatenate([c.u for c in res.curves]) if res.curves
                        else np.zeros((0, 2)))
    out[f"{name}.xy"] = (np.concatenate([np.column_stack([c.x, c.y]) for c in res.curves])
                         if res.curves else np.zeros((0, 2)))
    out[f"{name}.codim2_u"] = np.array([q.u for q in res.codim2]).reshape(-1, 2)
    out[f"{name}.codim2_xy"] = np.array([[q.x, q.y] for q in res.codim2]).reshape(-1, 2)
    out[f"{name}.codim2_lam"] = np.array([q.multipliers for q in res.codim2]).reshape(-1, 4)
    out[f"{name}.codim2_res"] = np.array([q.residual for q in res.codim2])
    return out


def compute() -> dict:
    from hybridpd.pair.boundaries import boundary_curves
    from hybridpd.reproduce import figures

    arrays = {}
    for name, (case, kw) in PLANES.items():
        arrays |= _plane_arrays(name, boundary_curves(case, **PAPER, **kw))
    # the reproduction's tracing of one panel (exists-and-stable region edges)
    edges = figures._trace("noncollocated", 0.9, (0.1, 20.0, 0.1, 6.0),
                           SimpleNamespace(gamma=0.75, x10=1.0))
    arrays["reproduce.kinds"] = np.array([c.kind for c in edges])
    arrays["reproduce.sizes"] = np.array([len(c.x) for c in edges], np.int64)
    arrays["reproduce.xy"] = (np.concatenate([np.column_stack([c.x, c.y]) for c in edges])
                              if edges else np.zeros((0, 2)))
    return arrays


if __name__ == "__main__":
    if "--write" not in sys.argv[1:]:
        sys.exit("usage: python tests/_golden_boundaries.py --write")
    arrays = compute()
    _golden.save(PATH, arrays)
    print(f"wrote {PATH} ({PATH.stat().st_size} bytes): "
          + ", ".join(f"{k} {v.shape}" for k, v in arrays.items()))
