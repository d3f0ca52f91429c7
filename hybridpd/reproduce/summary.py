"""``summary.json`` (machine-readable, with a documented schema) and ``summary.md``.

Every verdict in both files comes from :mod:`hybridpd.reproduce.conclusions`; the markdown is
rendered from the same dict that is written as JSON, so the two cannot disagree.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from hybridpd.reproduce import conclusions as C
from hybridpd.reproduce import rules as R
from hybridpd.reproduce.settings import PAPER

__all__ = ["SCHEMA", "build_summary", "render_markdown", "validate", "write_summary"]

_NUM = {"type": ["number", "null"]}
_VERDICT = {"type": "string", "enum": list(R.VERDICTS)}
_RESOLUTION = {"type": "object", "required": ["grids", "verdicts"], "properties": {
    "grids": {"type": "array", "minItems": 2, "maxItems": 2,
              "items": {"type": "array", "items": {"type": "integer"}, "minItems": 2,
                        "maxItems": 2}},
    "verdicts": {"type": "array", "minItems": 2, "maxItems": 2, "items": _VERDICT}}}
_INTERVALS = {"type": "object", "required": [f"{e:g}" for e in PAPER["e"]],
              "additionalProperties": {"type": "array", "items": {
                  "type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}}}

#: JSON schema (draft 2020-12 subset) of ``summary.json``; checked by :func:`validate`.
SCHEMA = {
    "type": "object",
    "required": ["schema_version", "mode", "paper", "conventions", "conclusions",
                 "m2_stable_intervals", "m2_interval_ends", "m2_study", "runs", "studies",
                 "remarks", "timings"],
    "properties": {
        "schema_version": {"type": "integer", "enum": [1]},
        "mode": {"type": "string"},
        "paper": {"type": "object", "required": ["mu", "gamma", "n", "omega", "e", "kp", "kv"]},
        "conventions": {
            "type": "object", "required": ["m2", "x10", "gamma", "L", "chosen_m2",
                                           "chosen_m2_rule"],
            "properties": {"m2": {"type": "array", "items": {"type": "number"}, "minItems": 1},
                           "x10": {"type": "number"}, "gamma": {"type": "number"},
                           "L": {"type": "number"}, "chosen_m2": _NUM,
                           "chosen_m2_rule": {"type": "string"}}},
        "conclusions": {
            "type": "array", "minItems": 5, "maxItems": 5,
            "items": {"type": "object",
                      "required": ["id", "statement", "verdict", "by_convention", "vs_m2",
                                   "evidence", "resolution_check"],
                      "properties": {
                          "id": {"type": "integer", "enum": [1, 2, 3, 4, 5]},
                          "statement": {"type": "string"},
                          "verdict": _VERDICT,
                          "by_convention": {"type": "object",
                                            "additionalProperties": _VERDICT},
                          "resolution_check": _RESOLUTION,
                          "vs_m2": {"type": "object", "required": ["m2", "verdict"],
                                    "properties": {
                                        "m2": {"type": "array", "items": {"type": "number"}},
                                        "verdict": {"type": "array",
                                                    "items": _VERDICT}}},
                          "evidence": {"type": "object"}}}},
        "m2_stable_intervals": {"type": "object", "required": ["noncollocated", "collocated"],
                                "properties": {"noncollocated": _INTERVALS,
                                               "collocated": _INTERVALS}},
        "m2_interval_ends": {"type": "object"},
        "m2_study": {"type": "object", "required": ["range", "grid"]},
        "runs": {"type": "array", "minItems": 1, "items": {
            "type": "object", "required": ["m2", "gain_box_scale", "orbits", "regions",
                                           "basins", "directory"]}},
        "studies": {"type": "object", "required": ["mu", "gamma"], "additionalProperties": {
            "type": "object", "required": ["values", "fractions", "box"]}},
        "remarks": {"type": "array", "items": {
            "type": "object", "required": ["id", "statement", "verdict", "evidence",
                                           "resolution_check"],
            "properties": {"verdict": _VERDICT, "resolution_check": _RESOLUTION}}},
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
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.analysis.labels import LABELS

    basins = []
    for (case, e), b in r.basins.items():
        o = r.orbits[(case, e)]
        row = {"case": case, "e": e, "measured": b is not None,
               "converged_fraction": 0.0 if b is None else b.converged_fraction,
               "window": None if b is None else [float(v) for v in b.window],
               "why_empty": None if b is not None else (
                   o.reason if not o.exists else "orbit unstable")}
        if b is not None:
            cnt = np.bincount(b.criterion_labels.ravel(), minlength=len(LABELS))
            row["label_counts"] = {n: int(c) for n, c in zip(LABELS, cnt)}
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
        if case in r.shares:
            regions[case]["stability_alone_fraction"] = r.shares[case]["stability"]
    return {"m2": r.m2, "x10": r.x10, "gamma": r.gamma, "L": r.L, "gain_box_scale": r.scale,
            "basin_window": list(r.basin_window),
            "basin_windows": [list(w) for w in r.basin_windows],
            "touches_edge": r.touches_edge,
            "directory": r.directory.name, "orbits": [_orbit_row(o) for o in r.orbits.values()],
            "regions": regions, "basins": basins, "timings": r.timings}


def _remark_verdicts(per_key: dict) -> str:
    """A universal statement over cases and ``e``: agrees only if every one agrees."""
    return R.AGREES if all(v == R.AGREES for v in per_key.values()) else R.CONTRADICTED


def remarks(studies) -> list:
    """The paper's remarks on ``mu`` (section 5) as verdicts by the trend rule, per case and
    ``e``, on the study's gain grid and on the resolution-check grid.

    * "existence decreases with mu": the existence share is non-increasing over the whole
      studied range of ``mu``, within two cells (:func:`~hybridpd.reproduce.rules.trend`);
    * "mu -> 0 facilitates control": the exists-and-stable share is non-increasing in ``mu``
      from ``mu = 1e-4`` (the limit point) to the paper's ``mu``, within two cells.
    """
    s = studies["mu"]
    vals = np.asarray(s.values)
    k01 = int(np.argmin(np.abs(np.log(vals / PAPER["mu"]))))
    layers = [(s.box, s.fractions, s.limits)]
    if s.check is not None:
        layers.append((s.check["box"], s.check["fractions"], s.check["limits"]))
    ev_a, ev_b = {}, {}
    va, vb = [], []
    for layer, (box, fr, lim) in enumerate(layers):
        cells = int(box["kp"][2]) * int(box["kv"][2])
        grid = [int(box["kp"][2]), int(box["kv"][2])]
        per_a, per_b = {}, {}
        for case, q in fr.items():
            ex, both = np.asarray(q["exists"]), np.asarray(q["both"])
            lim0, liminf = lim["0.0001"][case], lim["10000"][case]
            for k, e in enumerate(s.e):
                key = f"{case} e={e:g}"
                ta = R.trend(vals, ex[k], cells, direction="decreasing")
                xb = np.r_[1e-4, vals[:k01 + 1]]
                tb = R.trend(xb, np.r_[lim0["both"][k], both[k, :k01 + 1]], cells,
                             direction="decreasing")
                per_a[key], per_b[key] = ta["verdict"], tb["verdict"]
                if layer == 0:
                    ev_a[key] = {"exists_at_min_mu": R.share(ex[k, 0], grid),
                                 "exists_at_max_mu": R.share(ex[k, -1], grid),
                                 "exists_at_1e4": R.share(liminf["exists"][k], grid),
                                 "trend": ta}
                    ev_b[key] = {"both_at_1e-4": R.share(lim0["both"][k], grid),
                                 "mu_paper": float(vals[k01]),
                                 "both_at_mu_paper": R.share(both[k, k01], grid), "trend": tb}
                else:
                    ev_a[key]["verdict_check_grid"] = ta["verdict"]
                    ev_b[key]["verdict_check_grid"] = tb["verdict"]
        va.append(_remark_verdicts(per_a))
        vb.append(_remark_verdicts(per_b))
    for ev in (ev_a, ev_b):
        for row in ev.values():
            v = row["trend"]["verdict"]
            row["verdict"] = R.resolution(v, row.get("verdict_check_grid", v))
    grids = [[int(b["kp"][2]), int(b["kv"][2])] for b, _, _ in layers]
    if len(grids) == 1:
        grids, va, vb = grids * 2, va * 2, vb * 2
    out = []
    for rid, st, v, ev in (
            ("mu-existence", "The existence region tends to decrease with increasing mu.", va,
             ev_a),
            ("mu-small", "As mu tends to zero control becomes easier.", vb, ev_b)):
        out.append({"id": rid, "statement": st, "verdict": R.resolution(*v), "evidence": ev,
                    "resolution_check": {"grids": grids, "verdicts": v}})
    return out


def _conclusion(k, study, runs) -> dict:
    """One conclusion: the verdict by convention and along ``m2``, on both grids."""
    by_conv = {f"{r.m2:g}": r.verdicts[k] for r in runs}
    grid = study.robust_grid if k == 5 else study.grid
    checked = study.checked[k] if study.checked else study.verdicts[k]
    vs_resolved = [R.resolution(a, b) for a, b in zip(study.verdicts[k], checked)]
    v1 = R.combine([r.checks[k]["verdict"] for r in runs] + list(study.verdicts[k]))
    v2 = R.combine([r.check_grid_checks[k]["verdict"] for r in runs] + list(checked))
    evidence = {"by_convention": {f"{r.m2:g}": r.checks[k] for r in runs},
                "by_convention_check_grid": {f"{r.m2:g}": r.check_grid_checks[k]
                                             for r in runs},
                "vs_m2": study.evidence[k]}
    return {"id": k, "statement": C.STATEMENTS[k], "verdict": R.resolution(v1, v2),
            "by_convention": by_conv,
            "vs_m2": {"m2": list(grid), "verdict": vs_resolved,
                      "verdict_run_grid": list(study.verdicts[k]),
                      "verdict_check_grid": list(checked)},
            "evidence": evidence,
            "resolution_check": {"grids": runs[0].check_grids[k], "verdicts": [v1, v2]}}


def _feedback(m2, settings) -> dict | None:
    """How strong the feedback is at the chosen ``m2``: scaled gains and spectral radii."""
    if m2 is None:
        return None
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.pair.orbits import symmetric_orbits

    P = PAPER
    rho = {}
    for case in ("collocated", "noncollocated"):
        r = symmetric_orbits(P["kp"], P["kv"], mu=P["mu"], e=np.asarray(P["e"], float),
                             L=settings.L, x10=settings.x10, omega=P["omega"], m2=m2,
                             n=P["n"], case=case)
        rho[case] = [float(v) for v in np.asarray(r.spectral_radius)]
    return {"m2": m2, "kp_over_m2": P["kp"] / m2, "kv_over_m2": P["kv"] / m2,
            "spectral_radius": rho}


def build_summary(*, settings, mode, study, studies, runs, timings, figures=()) -> dict:
    """The ``summary.json`` dict (see :data:`SCHEMA`)."""
    conclusions = [_conclusion(k, study, runs) for k in range(1, 6)]
    ivs = {case: {f"{e:g}": [i.bounds() for i in lst] for e, lst in d.items()}
           for case, d in study.intervals.items()}
    ends = {case: {f"{e:g}": [i.to_dict() for i in lst] for e, lst in d.items()}
            for case, d in study.intervals.items()}
    out = {
        "schema_version": 1, "mode": mode,
        "paper": dict(PAPER, e=list(PAPER["e"])),
        "conventions": {"m2": [r.m2 for r in runs], "x10": settings.x10,
                        "gamma": PAPER["gamma"], "L": settings.L,
                        "chosen_m2": study.chosen_m2, "chosen_m2_rule": RULE,
                        "feedback_at_chosen_m2": _feedback(study.chosen_m2, settings),
                        "basin_window": [v * settings.x10 for v in settings.basin_window]},
        "conclusions": conclusions,
        "m2_stable_intervals": ivs, "m2_interval_ends": ends,
        "m2_study": {"range": list(settings.m2_range), "grid": list(study.grid),
                     "bracketing_points": settings.m2_grid,
                     "gain_box": {"kp": [0.1, settings.gains[0], settings.verdict_grid],
                                  "kv": [0.1, settings.gains[1], settings.verdict_grid]},
                     "check_grid": settings.check_num(settings.verdict_grid),
                     "robust_grid": list(study.robust_grid)},
        "runs": [_run_dict(r) for r in runs],
        "studies": {k: v.to_dict() for k, v in studies.items()},
        "remarks": remarks(studies),
        "thresholds": {"much_smaller": C.MUCH_SMALLER, "large": C.LARGE,
                       "similar": list(C.SIMILAR),
                       "trend_tolerance_cells": R.TREND_TOLERANCE_CELLS,
                       "basin_window_growths": settings.basin_extensions,
                       "check_scale": settings.check_scale},
        "figures": [str(f) for f in figures],
        "timings": timings}
    return _clean(out)


def write_summary(out, **kw) -> Path:
    """Write ``summary.json`` and ``summary.md`` into ``out``; return the markdown's path."""
    out = Path(out)
    data = build_summary(**kw)
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
