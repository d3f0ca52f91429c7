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
from hybridpd.reproduce.settings import PAPER

__all__ = ["SCHEMA", "build_summary", "render_markdown", "validate", "write_summary"]

_NUM = {"type": ["number", "null"]}
_VERDICT = {"type": "string", "enum": [C.AGREES, C.CONTRADICTED, C.DEPENDS]}
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
                                   "evidence"],
                      "properties": {
                          "id": {"type": "integer", "enum": [1, 2, 3, 4, 5]},
                          "statement": {"type": "string"},
                          "verdict": _VERDICT,
                          "by_convention": {"type": "object", "additionalProperties": {
                              "type": "string", "enum": [C.AGREES, C.CONTRADICTED]}},
                          "vs_m2": {"type": "object", "required": ["m2", "verdict"],
                                    "properties": {
                                        "m2": {"type": "array", "items": {"type": "number"}},
                                        "verdict": {"type": "array", "items": {
                                            "type": "string",
                                            "enum": [C.AGREES, C.CONTRADICTED,
                                                     C.NOT_MEASURED]}}}},
                          "evidence": {"type": "object"}}}},
        "m2_stable_intervals": {"type": "object", "required": ["noncollocated", "collocated"],
                                "properties": {"noncollocated": _INTERVALS,
                                               "collocated": _INTERVALS}},
        "m2_interval_ends": {"type": "object"},
        "m2_study": {"type": "object", "required": ["range", "grid"]},
        "runs": {"type": "array", "minItems": 1, "items": {
            "type": "object", "required": ["m2", "gain_box_scale", "orbits", "regions",
                                           "basins", "directory"]}},
        "studies": {"type": "object", "required": ["mu", "gamma"]},
        "remarks": {"type": "array", "items": {
            "type": "object", "required": ["id", "statement", "verdict", "evidence"],
            "properties": {"verdict": {"type": "string",
                                       "enum": [C.AGREES, C.CONTRADICTED]}}}},
        "timings": {"type": "object", "additionalProperties": {"type": "number"}},
    },
}

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


RULE = ("geometric centre of the widest common interval (log scale) of m2 in which all three "
        "non-collocated orbits at kp = 10, kv = 20 exist and are stable, within the studied "
        "range, rounded to 3 significant digits")


def _orbit_row(o) -> dict:
    return {"case": o.case.value, "e": o.pair.e, "exists": o.exists, "reason": o.reason,
            "stable": o.stable, "spectral_radius": o.spectral_radius, "xm": o.xm,
            "phi0": o.phi0, "viability_margin": o.viability_margin,
            "fixed_point": list(o.fixed_point),
            "multipliers_abs": None if o.multipliers is None
            else [abs(z) for z in o.multipliers]}


def _run_dict(r) -> dict:
    from hybridpd.sweeps.basins import LABELS

    basins = []
    for (case, e), b in r.basins.items():
        o = r.orbits[(case, e)]
        row = {"case": case, "e": e, "measured": b is not None,
               "converged_fraction": 0.0 if b is None else b.basin.converged_fraction,
               "window": None if b is None else [float(v) for v in b.window],
               "why_empty": None if b is not None else (
                   o.reason if not o.exists else "orbit unstable")}
        if b is not None:
            cnt = np.bincount(b.basin.labels.ravel(), minlength=len(LABELS))
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
            "directory": r.directory.name, "orbits": [_orbit_row(o) for o in r.orbits.values()],
            "regions": regions, "basins": basins, "timings": r.timings}


def remarks(studies) -> list:
    """The paper's remarks on ``mu`` (section 5) as computed verdicts, per case and ``e``.

    * existence shrinks as ``mu`` grows: the existence share at the largest ``mu`` of the
      study is below the one at the smallest, and vanishes at ``mu = 1e4``;
    * ``mu -> 0`` facilitates control: the exists-and-stable share at ``mu = 1e-4`` is at least
      the one at the paper's ``mu = 0.1``.
    """
    s = studies["mu"]
    vals = np.asarray(s.values)
    k01 = int(np.argmin(np.abs(np.log(vals / PAPER["mu"]))))
    out = []
    ev_a, ev_b, ok_a, ok_b = {}, {}, True, True
    for case, q in s.fractions.items():
        ex, both = np.asarray(q["exists"]), np.asarray(q["both"])
        lim0, liminf = s.limits["0.0001"][case], s.limits["10000"][case]
        for k, e in enumerate(s.e):
            a = bool(ex[k, -1] < ex[k, 0] and liminf["exists"][k] == 0)
            b = bool(lim0["both"][k] >= both[k, k01])
            ok_a &= a
            ok_b &= b
            key = f"{case} e={e:g}"
            ev_a[key] = {"exists_at_min_mu": ex[k, 0], "exists_at_max_mu": ex[k, -1],
                         "exists_at_1e4": liminf["exists"][k],
                         "largest_increase": float(np.max(np.diff(ex[k]), initial=0.0)),
                         "verdict": C._v(a)}
            ev_b[key] = {"both_at_1e-4": lim0["both"][k], "mu_paper": float(vals[k01]),
                         "both_at_mu_paper": both[k, k01], "verdict": C._v(b)}
    out.append({"id": "mu-existence", "statement": "The existence region tends to decrease "
                "with increasing mu.", "verdict": C._v(ok_a), "evidence": ev_a})
    out.append({"id": "mu-small", "statement": "As mu tends to zero control becomes easier.",
                "verdict": C._v(ok_b), "evidence": ev_b})
    return out


def build_summary(*, settings, mode, study, studies, runs, timings) -> dict:
    """The ``summary.json`` dict (see :data:`SCHEMA`)."""
    conclusions = []
    for k in range(1, 6):
        by_conv = {f"{r.m2:g}": r.checks[k]["verdict"] for r in runs}
        grid = study.robust_grid if k == 5 else study.grid
        vs = {"m2": list(grid), "verdict": study.verdicts[k]}
        verdict = C.combine(list(by_conv.values()) + list(study.verdicts[k]))
        evidence = {"by_convention": {f"{r.m2:g}": r.checks[k] for r in runs},
                    "vs_m2": study.evidence[k]}
        conclusions.append({"id": k, "statement": C.STATEMENTS[k], "verdict": verdict,
                            "by_convention": by_conv, "vs_m2": vs, "evidence": evidence})
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
                        "basin_window": [v * settings.x10 for v in settings.basin_window]},
        "conclusions": conclusions,
        "m2_stable_intervals": ivs, "m2_interval_ends": ends,
        "m2_study": {"range": list(settings.m2_range), "grid": list(study.grid),
                     "bracketing_points": settings.m2_grid,
                     "gain_box": {"kp": [0.1, settings.gains[0], settings.verdict_grid],
                                  "kv": [0.1, settings.gains[1], settings.verdict_grid]},
                     "robust_grid": list(study.robust_grid)},
        "runs": [_run_dict(r) for r in runs],
        "studies": {k: v.to_dict() for k, v in studies.items()},
        "remarks": remarks(studies),
        "timings": timings,
    }
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


def _pcts(a) -> str:
    from hybridpd._format import pct as _pct

    return ", ".join(_pct(v) for v in a)


def render_markdown(d: dict) -> str:
    """``summary.md`` from the ``summary.json`` dict."""
    from hybridpd.reproduce.markdown import render

    return render(d)
