"""Record (``--write``) or recompute the golden basins.

Cases: the impact pair's basin mapper (collocated ``e = 0.1``, the orbit with a period-2
attractor beside it) labelling a 25 x 25 grid of its ``(x1, y1)`` slice with the early exits
on and off; its attractor basin with window growth (2 extensions, ``max_period = 8``); the
reproduction's shared-window basins of two orbits; a slice of the same orbit's section map
(``SectionMap`` of the pair's automaton, two section coordinates); and a model file's basin
(the pair as a model file, its impact section). Recorded: labels, the mapper's labels against
the orbit, iterations, attractors (names, periods, points, multipliers), windows, edges and
the metadata (as JSON; without the growth options, whose spelling changed, and of a model
basin the file, section and criterion).

The calls go through :func:`_api`, which picks the basin functions of the version on the path
(the mapper classes and entry points of earlier versions, or the one mapper and
``basin_of_attraction``), so the same script records with one and checks with the other.

Run from outside the repository with the package to record on the path:
``python tests/_golden_basins.py --write``.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import _golden
from _pair_model import PAIR

PATH = _golden.DATA / "golden_basins.npz"
WINDOW = ((-3.0, 5.0), (-2.0, 10.0))


def _api() -> SimpleNamespace:
    """The basin calls of the version on the path, as one interface."""
    import hybridpd as hp
    from hybridpd.pair.impactmap import ImpactMap
    from hybridpd.pair.section import impact_pair_section
    from hybridpd.reproduce.basins import shared_window_basins

    try:
        from hybridpd.analysis.mappers import Growth, mapper
    except ImportError:     # the mapper classes and entry points of earlier versions
        from hybridpd.sweeps.model_basins import model_basin
        from hybridpd.sweeps.section_basins import section_basin

        from hybridpd.analysis.periodic import SectionMapper
        from hybridpd.pair.basins import ImpactMapper, attractor_basin

        return SimpleNamespace(
            pair_mapper=lambda orb, **kw: ImpactMapper.from_orbit(orb, **kw),
            pair_basin=lambda m, x, y, n: attractor_basin(m, x, y, max_period=8,
                                                          max_extensions=n),
            section_basin=lambda P, fp, ax, x, y, n: section_basin(
                SectionMapper(P, fp, n_iter=n), ax[0], ax[1], x, y),
            model_basin=lambda x, y, n: model_basin(PAIR, x, y, n_iter=n, event="impact"),
            shared=shared_window_basins, impact_map=ImpactMap,
            section=impact_pair_section, hp=hp)
    from hybridpd.analysis.model_orbits import model_map
    from hybridpd.reproduce.basins import orbit_mapper

    def model_basin(x, y, n):
        m = model_map(PAIR, event="impact").mapper(n_iter=n)
        return hp.basin_of_attraction(m, x[1:], y[1:], axes=(x[0], y[0]), max_period=4)

    return SimpleNamespace(
        pair_mapper=orbit_mapper,
        pair_basin=lambda m, x, y, n: hp.basin_of_attraction(
            m, x, y, max_period=8, grow=Growth(max_extensions=n)),
        section_basin=lambda P, fp, ax, x, y, n: hp.basin_of_attraction(
            mapper(P, fp, n_iter=n), x, y, axes=ax, max_period=0),
        model_basin=model_basin, shared=shared_window_basins, impact_map=ImpactMap,
        section=impact_pair_section, hp=hp)


def _orbit(api, e=0.1):
    hp = api.hp
    return hp.symmetric_orbit(hp.ImpactPair(0.1, e, 0.75), hp.PDGains(10, 20), 5.0)


#: Metadata left out: the window growth's options (``extend``, ``max_extensions``,
#: ``max_points`` of earlier versions; a ``Growth`` now), recorded however the call spells them.
GROWTH_KEYS = ("extend", "max_extensions", "max_points")
#: A model basin's metadata compared: what the file, section and criterion were.
MODEL_KEYS = ("criterion", "inadmissible", "model", "n_iter", "section_mode", "spec", "values")


def _metadata(md: dict, keys=None) -> np.ndarray:
    md = {k: v for k, v in md.items() if k not in GROWTH_KEYS and (keys is None or k in keys)}
    return np.array(json.dumps(md, sort_keys=True, default=str))


def _basin_arrays(name, b, keys=None) -> dict:
    atts = b.attractors
    out = {f"{name}.labels": b.labels, f"{name}.iterations": b.iterations,
           f"{name}.x": b.x, f"{name}.y": b.y, f"{name}.base": b.base,
           f"{name}.names": np.array([a.name for a in atts]),
           f"{name}.att_labels": np.array([a.label for a in atts], np.int64),
           f"{name}.periods": np.array([a.period for a in atts], np.int64),
           f"{name}.windows": np.array(b.windows, float).reshape(-1, 4),
           f"{name}.edges": np.array(list(b.edges), str),
           f"{name}.metadata": _metadata(b.metadata, keys)}
    if b.criterion_labels is not None:
        out[f"{name}.criterion_labels"] = b.criterion_labels
    for a in atts:
        if a.periodic:
            out[f"{name}.att{a.label}.points"] = a.points
            if a.multipliers is not None:
                out[f"{name}.att{a.label}.multipliers"] = np.asarray(a.multipliers)
    return out


def compute() -> dict:
    """Every golden array, computed by the package on the path."""
    api = _api()
    orb = _orbit(api)
    arrays = {}
    # the mapper's labels on a 25 x 25 grid of the slice, early exits on and off
    from hybridpd.pair.basins import section_grid

    xs, ys = np.linspace(*WINDOW[0], 25), np.linspace(*WINDOW[1], 25)
    S = section_grid(orb.fixed_point, orb.pair.L, xs, ys).reshape(-1, 4)
    for early in (True, False):
        m = api.pair_mapper(orb, n_iter=300, early_exit=early)
        lab, its = m.labels(S)
        arrays[f"mapper_early{int(early)}.labels"] = lab
        arrays[f"mapper_early{int(early)}.iterations"] = its
        arrays[f"mapper_early{int(early)}.certified_radius"] = np.float64(m.certified_radius)
    # the attractor basin on a window around the orbit's fixed point (1, 3.18), grown twice
    m = api.pair_mapper(orb, n_iter=300)
    b = api.pair_basin(m, (0.0, 2.0, 11), (2.2, 4.2, 11), 2)
    arrays.update(_basin_arrays("pair", b))
    # the reproduction's shared window of two orbits
    res = api.shared({"e01": orb, "e05": _orbit(api, 0.5)}, (-3, 5, -2, 10), (7, 7),
                     n_iter=200, max_growths=1)
    arrays["shared.window"] = np.array(res.window, float)
    arrays["shared.windows"] = np.array(res.windows, float)
    for k, b in sorted(res.basins.items()):
        arrays.update(_basin_arrays(f"shared_{k}", b))
    # a slice of the section map of the pair's automaton
    P = api.hp.SectionMap(api.section(orb.system()))
    b = api.section_basin(P, orb.fixed_point, ("z1", "z4"), (-0.5, 0.5, 5), (1.0, 2.0, 4), 50)
    arrays.update(_basin_arrays("section", b))
    # a model file's basin (the pair as a model file, its impact section)
    b = api.model_basin(("x2", -1.0, 1.0, 5), ("x1_dot", -1.0, 3.0, 5), 150)
    arrays.update(_basin_arrays("model", b, MODEL_KEYS))
    return arrays


if __name__ == "__main__":
    if "--write" not in sys.argv:
        raise SystemExit("usage: python tests/_golden_basins.py --write")
    arrays = compute()
    _golden.save(PATH, arrays)
    print(f"wrote {PATH} ({PATH.stat().st_size} bytes, {len(arrays)} arrays)")
