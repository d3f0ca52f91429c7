"""``summary.json`` (machine-readable, with a documented schema) and ``summary.md``.

Every verdict in both files comes from :mod:`hybridpd.reproduce.conclusions`; the markdown is
rendered from the same dict that is written as JSON, so the two cannot disagree.
"""
from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np

from hybridpd.reproduce import conclusions as C
from hybridpd.reproduce import rules as R
from hybridpd.reproduce.settings import PAPER

CASES = ("collocated", "noncollocated")

__all__ = ["SCHEMA", "build_summary", "render_markdown", "validate", "write_summary"]

_NUM = {"type": ["number", "null"]}
_VERDICT = {"type": "string", "enum": list(R.VERDICTS)}
_PAIR = {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}
_INTERVALS = {"type": "object", "required": [f"{e:g}" for e in PAPER["e"]],
              "additionalProperties": {"type": "array", "items": _PAIR}}
_SHARE = {"type": "object", "required": ["exists_stable", "exists", "exists_unstable",
                                         "no_orbit", "cells", "grid"],
          "properties": {"exists_stable": _PAIR, "exists": _PAIR, "exists_unstable": _PAIR,
                         "no_orbit": _PAIR, "grid": {"type": "array", "items":
                                                     {"type": "integer"}}}}
_PER_E = {"type": "object", "required": [f"{e:g}" for e in PAPER["e"]],
          "additionalProperties": _SHARE}
_READING = {"type": "object", "required": ["verdict", "m2"],
            "properties": {"verdict": _VERDICT, "m2": _PAIR}}

#: JSON schema (draft 2020-12 subset) of ``summary.json``; checked by :func:`validate`.
SCHEMA = {
    "type": "object",
    "required": ["schema_version", "mode", "paper", "conventions", "table", "certified",
                 "certified_shares", "conclusions", "remarks", "m2_stable_intervals",
                 "m2_interval_ends", "m2_study", "runs", "studies", "timings"],
    "properties": {
        "schema_version": {"type": "integer", "enum": [2]},
        "mode": {"type": "string"},
        "paper": {"type": "object", "required": ["mu", "gamma", "n", "omega", "e", "kp", "kv"]},
        "conventions": {
            "type": "object", "required": ["m2", "x10", "gamma", "L", "chosen_m2",
                                           "chosen_m2_rule"],
            "properties": {"m2": {"type": "array", "items": {"type": "number"}, "minItems": 1},
                           "x10": {"type": "number"}, "gamma": {"type": "number"},
                           "L": {"type": "number"}, "chosen_m2": _NUM,
                           "chosen_m2_rule": {"type": "string"}}},
        "table": {"type": "array", "minItems": 7, "maxItems": 7, "items": {
            "type": "object", "required": ["id", "paper", "verdict", "finding", "m2_text",
                                           "m2_readings"],
            "properties": {"verdict": _VERDICT, "paper": {"type": "string"},
                           "finding": {"type": "string"}, "m2_text": {"type": "string"}}}},
        "certified": {"type": "object", "required": ["box", "main", "readings"]},
        "certified_shares": {"type": "object", "required": ["collocated", "noncollocated"],
                             "additionalProperties": _PER_E},
        "conclusions": {
            "type": "array", "minItems": 5, "maxItems": 5,
            "items": {"type": "object",
                      "required": ["id", "statement", "verdict", "evidence", "m2_readings"],
                      "properties": {
                          "id": {"type": "integer", "enum": [1, 2, 3, 4, 5]},
                          "statement": {"type": "string"},
                          "verdict": _VERDICT,
                          "evidence": {"type": "object"}}}},
        "m2_stable_intervals": {"type": "object", "required": ["noncollocated", "collocated"],
                                "properties": {"noncollocated": _INTERVALS,
                                               "collocated": _INTERVALS}},
        "m2_interval_ends": {"type": "object"},
        "m2_study": {"type": "object", "required": ["range", "readings"]},
        "runs": {"type": "array", "minItems": 1, "items": {
            "type": "object", "required": ["m2", "gain_box_scale", "orbits", "regions",
                                           "basins", "directory"]}},
        "studies": {"type": "object", "required": ["mu", "gamma"], "additionalProperties": {
            "type": "object", "required": ["values", "fractions", "box"]}},
        "remarks": {"type": "array", "minItems": 2, "maxItems": 2, "items": {
            "type": "object", "required": ["id", "statement", "verdict", "evidence"],
            "properties": {"verdict": _VERDICT}}},
        "timings": {"type": "object", "additionalProperties": {"type": "number"}}}}

_TYPES = {"object": dict, "array": list, "string": str, "boolean": bool, "null": type(None)}


def _is(value, t) -> bool:
    if t == "number":
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if t == "integer":
        return isinstance(value, int) and not isinstance(value, bool)
    return isinstance(value, _TYPES[t])


def validate(instance, schema=SCHEMA, path="$") -> list:
    """Errors of ``instance`` against the schema subset used by :data:`SCHEMA` (empty: valid).

    Supports ``type``, ``enum``, ``required``, ``properties``, ``additionalProperties``
    (a schema), ``items``, ``minItems``, ``maxItems``.
    """
    errs = []
    t = schema.get("type")
    if t is not None:
        ts = t if isinstance(t, list) else [t]
        if not any(_is(instance, x) for x in ts):
            return [f"{path}: expected {t}, got {type(instance).__name__}"]
    if "enum" in schema and instance not in schema["enum"]:
        errs.append(f"{path}: {instance!r} not in {schema['enum']}")
    if isinstance(instance, dict):
        for k in schema.get("required", []):
            if k not in instance:
                errs.append(f"{path}: missing {k!r}")
        props = schema.get("properties", {})
        for k, v in instance.items():
            if k in props:
                errs += validate(v, props[k], f"{path}.{k}")
            elif isinstance(schema.get("additionalProperties"), dict):
                errs += validate(v, schema["additionalProperties"], f"{path}.{k}")
    if isinstance(instance, list):
        if len(instance) < schema.get("minItems", 0):
            errs.append(f"{path}: fewer than {schema['minItems']} items")
        if len(instance) > schema.get("maxItems", math.inf):
            errs.append(f"{path}: more than {schema['maxItems']} items")
        if "items" in schema:
            for i, v in enumerate(instance):
                errs += validate(v, schema["items"], f"{path}[{i}]")
    return errs


def _clean(x):
    """JSON-ready copy: numpy scalars/arrays to Python, non-finite floats to None."""
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, np.ndarray):
        return _clean(x.tolist())
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x


RULE = ("the smallest value of the 1-2-5 series (..., 10, 20, 50, 100, 200, ...) at or above "
        "every threshold at which all six orbits of Figs 6-7 (both cases, every e, "
        "kp = 10, kv = 20) exist and are stable")


def _orbit_row(o) -> dict:
    return {"case": o.case.value, "e": o.pair.e, "exists": o.exists, "reason": o.reason,
            "stable": o.stable, "spectral_radius": o.spectral_radius, "xm": o.xm,
            "phi0": o.phi0, "viability_margin": o.viability_margin,
            "fixed_point": list(o.fixed_point),
            "multipliers_abs": None if o.multipliers is None
            else [abs(z) for z in o.multipliers]}


def _run_dict(r) -> dict:
    basins = []
    for (case, e), b in r.basins.items():
        o = r.orbits[(case, e)]
        row = {"case": case, "e": e, "measured": b is not None,
               "converged_fraction": 0.0 if b is None else b.converged_fraction,
               "window": None if b is None else [float(v) for v in b.window],
               "why_empty": None if b is not None else (
                   o.reason if not o.exists else "orbit unstable")}
        if b is not None:
            N = int(b.labels.size)
            # one denominator for every share: the points of the window
            row["points"] = N
            row["grid"] = [len(b.x1), len(b.y1)]
            row["shares"] = [{"label": int(a.label), "name": a.name,
                              "count": int((b.labels == a.label).sum()),
                              "share": float((b.labels == a.label).sum()) / N}
                             for a in b.attractors]
            row["converged_area"] = b.measure(0).area
            row["reaches_edge"] = b.reaches_edge
            row["attractors"] = b.to_dict()["attractors"]
        basins.append(row)
    regions = {}
    for case in ("collocated", "noncollocated", "zoom"):
        rm = r.maps[case]
        regions[case] = {"kp": [float(rm.x[0]), float(rm.x[-1]), len(rm.x)],
                         "kv": [float(rm.y[0]), float(rm.y[-1]), len(rm.y)],
                         "exists_fraction": rm.fraction("exists"),
                         "stable_fraction": rm.fraction("stable"),
                         "stable_area": rm.area("stable")}
    return {"m2": r.m2, "x10": r.x10, "gamma": r.gamma, "L": r.L, "gain_box_scale": r.scale,
            "basin_window": list(r.basin_window),
            "basin_windows": [list(w) for w in r.basin_windows],
            "touches_edge": r.touches_edge, "directory": r.directory.name,
            "orbits": [_orbit_row(o) for o in r.orbits.values()], "regions": regions,
            "basins": basins,
            "conclusion_4": {"verdict": r.verdict_4, "grids": r.basin_grids,
                             "verdicts": [r.check_4["verdict"],
                                          r.check_4_check_grid["verdict"]],
                             "run_grid": r.check_4, "check_grid": r.check_4_check_grid},
            "timings": r.timings}


def _intervals(shares, group, keys, prop="exists_stable") -> list:
    return [shares[group][k].interval(prop) for k in keys]


def _checks(shares, es, settings, check5) -> dict:
    """Every claim's check in scaled gains, from the certified shares."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.certified import MU_LIMIT

    main = {c: _intervals(shares, "main", [(c, e) for e in es]) for c in CASES}
    exist = {c: _intervals(shares, "main", [(c, e) for e in es], "exists") for c in CASES}
    lo_mu, hi_mu = settings.mu_range
    ends = {m: {c: _intervals(shares, "mu_ends", [(c, e, m) for e in es], "exists")
                for c in CASES} for m in (lo_mu, hi_mu)}
    # every certified value inside the range: the values between which a sampled share
    # rises most, every other value of the study (when certified) and the paper's mu, whose
    # cells are the main box's
    inside = {(c, e): sorted([(k[2], r.interval("exists"))
                              for g in ("mu_moves", "mu_values")
                              for k, r in shares.get(g, {}).items() if k[:2] == (c, e)]
                             + [(PAPER["mu"], shares["main"][(c, e)].interval("exists"))])
              for c in CASES for e in es}
    limit = {c: _intervals(shares, "limit", [(c, e) for e in es]) for c in CASES}
    return {1: C.check_1(main["collocated"], main["noncollocated"], es,
                         col_exists=exist["collocated"], non_exists=exist["noncollocated"]),
            2: C.check_2(main["collocated"], main["noncollocated"], es),
            3: C.check_3(main["collocated"], es), 5: check5,
            "mu-existence": C.check_mu_existence((lo_mu, hi_mu), ends[lo_mu], ends[hi_mu], es,
                                                 inside=inside),
            "mu-small": C.check_mu_small((MU_LIMIT, PAPER["mu"]), limit, main, es)}


def _readings_123(shares, es, settings) -> dict:
    """Conclusions 1-3 read on the printed box at every reading ``m2`` (certified)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.certified import reading_values

    values = reading_values(settings)
    per = {1: [], 2: [], 3: []}
    evidence = []
    for m2 in values:
        if m2 == 1.0:
            sh = {c: _intervals(shares, "main", [(c, e) for e in es]) for c in CASES}
        else:
            sh = {c: _intervals(shares, "readings", [(c, e, m2) for e in es]) for c in CASES}
        chk = {1: C.check_1(sh["collocated"], sh["noncollocated"], es),
               2: C.check_2(sh["collocated"], sh["noncollocated"], es),
               3: C.check_3(sh["collocated"], es)}
        for k, lst in per.items():
            lst.append(chk[k]["verdict"])
        evidence.append({"m2": m2, "collocated": sh["collocated"],
                         "noncollocated": sh["noncollocated"],
                         "verdicts": {str(k): chk[k]["verdict"] for k in chk}})
    return {k: R.m2_readings(values, v) for k, v in per.items()}, evidence


def _stable_at(ivs, m2) -> bool:
    return any(i.lo.m2 < m2 < i.hi.m2 for i in ivs)


def readings_4(intervals, m2_range, runs) -> list:
    """Conclusion 4 along ``m2``, from the located interval ends (exact): where, for some
    ``e``, the orbit at the paper's gains is stable in one case only, a basin faces none
    (contradicted); where all six are stable only the basins decide, at the conventions
    of the run."""
    es = list(intervals["collocated"])
    lo, hi = m2_range
    ends = sorted({lo, hi} | {x.m2 for d in intervals.values() for ivs in d.values()
                              for i in ivs for x in (i.lo, i.hi) if lo < x.m2 < hi})
    out = []
    for a, b in itertools.pairwise(ends):
        m = math.sqrt(a * b)
        st = {c: [_stable_at(intervals[c][e], m) for e in es] for c in CASES}
        v = C.check_4_necessary(st["collocated"], st["noncollocated"])
        if v == R.CONTRADICTED:
            if out and out[-1].get("exact") and out[-1]["m2"][1] == a:
                out[-1]["m2"][1] = b
            else:
                out.append({"verdict": v, "m2": [a, b], "exact": True,
                            "computed": [], "change_after": None})
            continue
        for r in runs:
            if a < r.m2 < b or (r.m2 == b == hi):
                out.append({"verdict": r.verdict_4, "m2": [r.m2, r.m2], "exact": False,
                            "computed": [r.m2], "change_after": None})
    return out


def _readings_5(study) -> dict:
    return {crit: R.m2_readings(list(study.robust_grid),
                                [r["by_criterion"][crit] for r in study.robust])
            for crit in C.CRITERIA_5}


def _certified_section(shares, settings) -> dict:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.certified import MU_LIMIT, reading_values

    def cfg(c, group):
        r = next(iter(shares[group].values()), None)
        grid, levels, width = c
        return {"base_grid": grid, "levels": levels, "width": width,
                "grid": None if r is None else [r.finest, r.finest],
                "seconds": shares["seconds"].get(group), "cpu_seconds":
                    shares["cpu_seconds"].get(group)}
    return {"method": ("each class's share of the box is enclosed in [proved, proved + "
                       "undecided] cells of the finest grid; cells proved by interval "
                       "arithmetic on the paper's closed forms (hybridpd.pair.proofs), "
                       "undecided cells cut in four up to the level cap"),
            "box": {"kp/m2": [0.1, settings.gains[0]], "kv/m2": [0.1, settings.gains[1]]},
            "main": cfg(settings.certified, "main"), "limit": cfg(settings.certified_ends, "limit"),
            "mu_ends": cfg(settings.certified_ends, "mu_ends"),
            "readings": cfg(settings.certified_readings, "readings"),
            "values": cfg(settings.certified_values, "mu_values")
            if shares.get("mu_values") else None,
            "every_value": bool(shares.get("mu_values") or shares.get("gamma_values")),
            "mu_limit": MU_LIMIT, "mu_ends_values": list(settings.mu_range),
            "readings_m2": reading_values(settings)}


def gamma_certified(shares, settings) -> dict | None:
    """The ``gamma`` study certified at every value (None when it is sampled only): per case
    and ``e`` the certified share where the orbit exists and is stable at each value, and the
    values where stable gains are proved to exist somewhere in the box (``lo > 0``) and where
    they are proved absent from it (``hi = 0``)."""
    group = shares.get("gamma_values") or {}
    if not group:
        return None
    out = {}
    for case in CASES:
        for e in (float(v) for v in PAPER["e"]):
            pts = sorted((k[2], r.interval("exists_stable")) for k, r in group.items()
                         if k[:2] == (case, e))
            out.setdefault(case, {})[f"{e:g}"] = {
                "gamma": [g for g, _ in pts], "exists_stable": [list(iv) for _, iv in pts],
                "proved_somewhere": [g for g, iv in pts if iv[0] > 0],
                "proved_nowhere": [g for g, iv in pts if iv[1] == 0]}
    r = next(iter(group.values()))
    return {"grid": [r.finest, r.finest], "base_grid": settings.certified_values[0],
            "levels": settings.certified_values[1], "width": settings.certified_values[2],
            "shares": out}


def _shares_json(group, keyfmt) -> dict:
    out = {}
    for key, r in group.items():
        d = out
        for part in keyfmt(key)[:-1]:
            d = d.setdefault(part, {})
        d[keyfmt(key)[-1]] = r.to_dict()
    return out


def build_summary(*, settings, mode, study, studies, runs, shares, check5, timings,
                  figures=()) -> dict:
    """The ``summary.json`` dict (see :data:`SCHEMA`)."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.table import build_table

    es = [float(e) for e in PAPER["e"]]
    checks = _checks(shares, es, settings, check5)
    r123, reading_evidence = _readings_123(shares, es, settings)
    readings = {**r123, 4: readings_4(study.intervals, settings.m2_range, runs),
                5: _readings_5(study)}
    measured = [{"m2": r.m2, "verdict": r.verdict_4, "window": list(r.basin_window),
                 "grid": list(settings.basin)} for r in runs
                if all(o.exists and o.stable for o in r.orbits.values())]
    finest = {g: (next(iter(shares[g].values())).finest,) * 2
              for g in ("main", "limit", "mu_ends", "mu_values") if shares.get(g)}
    table = build_table(checks=checks, readings=readings, basins_measured=measured,
                        grids=finest)
    conclusions = []
    for k in range(1, 6):
        ev = checks.get(k) if k != 4 else {
            "by_convention": {f"{r.m2:g}": {"verdict": r.verdict_4, "grids": r.basin_grids,
                                            "run_grid": r.check_4,
                                            "check_grid": r.check_4_check_grid}
                              for r in runs}}
        conclusions.append({"id": k, "statement": C.STATEMENTS[k],
                            "verdict": table[k - 1]["verdict"], "evidence": ev,
                            "m2_readings": readings[k]})
    remarks = [{"id": rid, "statement": C.REMARKS[rid], "verdict": checks[rid]["verdict"],
                "evidence": checks[rid]} for rid in ("mu-existence", "mu-small")]
    ivs = {case: {f"{e:g}": [i.bounds() for i in lst] for e, lst in d.items()}
           for case, d in study.intervals.items()}
    ends = {case: {f"{e:g}": [i.to_dict() for i in lst] for e, lst in d.items()}
            for case, d in study.intervals.items()}
    out = {
        "schema_version": 2, "mode": mode,
        "paper": dict(PAPER, e=list(PAPER["e"])),
        "conventions": {"m2": [r.m2 for r in runs], "x10": settings.x10,
                        "gamma": PAPER["gamma"], "L": settings.L,
                        "chosen_m2": study.chosen_m2, "chosen_m2_rule": RULE,
                        "feedback_at_chosen_m2": _feedback(study.chosen_m2, settings),
                        "basin_window": [v * settings.x10 for v in settings.basin_window]},
        "table": table,
        "certified": _certified_section(shares, settings),
        "certified_shares": _shares_json(shares["main"], lambda k: (k[0], f"{k[1]:g}")),
        "certified_studies": {
            "limit": _shares_json(shares["limit"], lambda k: (k[0], f"{k[1]:g}")),
            "mu_ends": _shares_json(shares["mu_ends"], lambda k: (k[0], f"{k[2]:g}",
                                                                  f"{k[1]:g}")),
            "readings": _shares_json(shares["readings"], lambda k: (k[0], f"{k[2]:g}",
                                                                    f"{k[1]:g}")),
            **{g: _shares_json(shares.get(g, {}), lambda k: (k[0], f"{k[2]:.6g}", f"{k[1]:g}"))
               for g in ("mu_moves", "mu_values", "gamma_values")}},
        "gamma_certified": gamma_certified(shares, settings),
        "conclusions": conclusions, "remarks": remarks,
        "m2_stable_intervals": ivs, "m2_interval_ends": ends,
        "m2_study": {"range": list(settings.m2_range), "bracketing_points": settings.m2_grid,
                     "readings": reading_evidence,
                     "robust_grid": list(study.robust_grid), "robust": study.robust},
        "runs": [_run_dict(r) for r in runs],
        "studies": {k: v.to_dict() for k, v in studies.items()},
        "thresholds": {"much_smaller": C.MUCH_SMALLER, "large": C.LARGE,
                       "similar": list(C.SIMILAR),
                       "basin_window_growths": settings.basin_extensions,
                       "check_scale": settings.check_scale,
                       "basin_check_scale": settings.basin_check_scale},
        "figures": [str(f) for f in figures],
        "timings": timings}
    return _clean(out)


def _feedback(m2, settings) -> dict | None:
    """How strong the feedback is at the chosen ``m2``: scaled gains and spectral radii."""
    if m2 is None:
        return None
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.orbits import symmetric_orbits

    P = PAPER
    rho = {}
    for case in CASES:
        r = symmetric_orbits(P["kp"], P["kv"], mu=P["mu"], e=np.asarray(P["e"], float),
                             L=settings.L, x10=settings.x10, omega=P["omega"], m2=m2,
                             n=P["n"], case=case)
        rho[case] = [float(v) for v in np.asarray(r.spectral_radius)]
    return {"m2": m2, "kp_over_m2": P["kp"] / m2, "kv_over_m2": P["kv"] / m2,
            "spectral_radius": rho}


def write_summary(out, data=None, **kw) -> Path:
    """Write ``summary.json`` and ``summary.md`` into ``out``; return the markdown's path.

    ``data`` is a :func:`build_summary` dict; without it one is built from ``kw``."""
    out = Path(out)
    data = build_summary(**kw) if data is None else data
    errs = validate(data)
    if errs:
        raise RuntimeError("summary.json does not match its schema: " + "; ".join(errs[:5]))
    (out / "summary.json").write_text(json.dumps(data, indent=1))
    path = out / "summary.md"
    path.write_text(render_markdown(data))
    return path


def _f(x, nd=4):
    return "-" if x is None else f"{x:.{nd}g}"


def render_markdown(d: dict) -> str:
    """``summary.md`` from the ``summary.json`` dict."""
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.reproduce.markdown import render

    return render(d)
