"""Render ``summary.md`` from the ``summary.json`` dict (nothing here computes a verdict)."""
from __future__ import annotations

__all__ = ["render"]

_Q = {"exists": "existence alone", "stability": "stability alone", "both": "both (shaded)"}


def _f(x, nd=4):
    return "-" if x is None else f"{x:.{nd}g}"


def _p(x):
    from hybridpd._format import pct as _pct

    return "-" if x is None else _pct(x)


def _ps(a):
    return ", ".join(_p(v) for v in a)


def _conventions(d, w):
    c, P = d["conventions"], d["paper"]
    w("# hybridpd reproduction of Mata-Jimenez, Brogliato & Goswami (Figs 3-7)\n")
    w(f"Mode **{d['mode']}**. Paper: mu = {P['mu']}, gamma = {P['gamma']}, n = {P['n']}, "
      f"omega = {P['omega']}, e in {P['e']}, kp = {P['kp']:g}, kv = {P['kv']:g} (Figs 6-7). "
      f"Open conventions: x10 = {c['x10']:g} (L = {c['L']:g}), basin window x1 in "
      f"{c['basin_window'][:2]}, y1 in {c['basin_window'][2:]}, and **m2 in "
      f"{[float(f'{v:g}') for v in c['m2']]}**.\n")
    w("Existence = conditions (13)-(14) solvable with xm > 0 and the flight viable (18); "
      "stability = all multipliers of DP inside the unit circle. *Stability alone* is that of "
      "the orbit candidate with viability ignored. Every number below is computed in this run "
      "(`summary.json` holds them all).\n")


def _m2_section(d, w):
    c = d["conventions"]
    w("## The result depends on m2, which the paper does not give\n")
    w("At fixed mu only kp/m2 and kv/m2 matter. For the paper's gains kp = 10, kv = 20 the "
      "orbits exist and are stable on these intervals of m2 (within "
      f"{d['m2_study']['range']}; ends located by Brent's method on the exact test function "
      "after bracketing on a log grid of "
      f"{d['m2_study']['bracketing_points']} points, each verified by recomputation):\n")
    w("| case | e | intervals of m2 | ends (kind, residual) |")
    w("|---|---|---|---|")
    for case in ("noncollocated", "collocated"):
        for e, lst in d["m2_interval_ends"][case].items():
            iv = "; ".join(f"[{i['lo']['m2']:.7g}, {i['hi']['m2']:.7g}]" for i in lst) or "none"
            ends = "; ".join(
                f"{x['m2']:.7g} ({x['kind']}{', ' + format(x['residual'], '.1e') if x['residual'] is not None else ''})"
                for i in lst for x in (i["lo"], i["hi"]) if x["kind"] != "window") or "-"
            w(f"| {case} | {e} | {iv} | {ends} |")
    w("")
    if c["chosen_m2"] is None:
        w("No m2 in the range makes all three non-collocated orbits stable: only m2 = 1 is "
          "run.\n")
    else:
        w(f"Second convention: **m2 = {c['chosen_m2']:g}**, the {c['chosen_m2_rule']}. Under "
          "it the non-collocated orbits of Fig. 7 exist and are stable, so Fig. 7 shows real "
          "basins at the paper's gains. Both conventions use the gain box of Figs 4-5 scaled "
          "by m2, so their region maps are the same picture in kp/m2, kv/m2.\n")
    w("Verdicts against m2, on the paper's gain box as printed (kp, kv in "
      f"[{d['m2_study']['gain_box']['kp'][0]}, {d['m2_study']['gain_box']['kp'][1]}], not "
      "scaled; conclusion 4 from the orbits only: a missing or unstable orbit on one side "
      "means an empty basin; conclusion 5 on a coarser grid):\n")
    grid = d["m2_study"]["grid"]
    w("| conclusion | " + " | ".join(f"m2 = {m:.3g}" for m in grid) + " |")
    w("|---" * (len(grid) + 1) + "|")
    for con in d["conclusions"]:
        vs = con["vs_m2"]
        if len(vs["m2"]) == len(grid):
            cells = vs["verdict"]
        else:
            at = dict(zip((f"{m:.3g}" for m in vs["m2"]), vs["verdict"]))
            cells = [at.get(f"{m:.3g}", "") for m in grid]
        w(f"| {con['id']} | " + " | ".join(cells) + " |")
    w("")


def _conclusion(con, d, w):
    k = con["id"]
    by = ", ".join(f"m2 = {m}: {v}" for m, v in con["by_convention"].items())
    w(f"### {k}. *{con['statement']}*\n")
    w(f"**Verdict: {con['verdict']}** (by convention: {by}).\n")
    ev = con["evidence"]["by_convention"]
    es = d["paper"]["e"]
    for m2, chk in ev.items():
        if k in (1, 2, 3):
            w(f"- m2 = {m2} (shares of the scaled gain box, e = {es}):")
            for q, r in chk["by_quantity"].items():
                if k == 1:
                    ratio = ", ".join(_f(x, 3) for x in r["ratio"])
                    w(f"  - {_Q[q]}: collocated {_ps(r['collocated'])}; non-collocated "
                      f"{_ps(r['noncollocated'])}; ratio {ratio} -> {r['verdict']}")
                elif k == 2:
                    w(f"  - {_Q[q]}: non-collocated {_ps(r['noncollocated'])} "
                      f"({'decreases' if r['noncollocated_decreases'] else 'does not decrease'}"
                      f"); collocated {_ps(r['collocated'])} "
                      f"({'increases' if r['collocated_increases'] else 'does not increase'}"
                      f"{', saturated steps ' + str(r['collocated_saturated_steps']) if any(r['collocated_saturated_steps']) else ''}"
                      f") -> {r['verdict']}")
                else:
                    w(f"  - {_Q[q]}: collocated {_ps(r['collocated'])} -> {r['verdict']}")
        elif k == 4:
            area = lambda v: ", ".join("-" if x is None else _f(x, 4) for x in v)
            w(f"- m2 = {m2}: area of the symmetric orbit's basin in the (x1, y1) slice (the "
              f"windows may have been extended), collocated {area(chk['collocated'])}, "
              f"non-collocated {area(chk['noncollocated'])} "
              f"(ratio {', '.join(_f(x, 3) for x in chk['ratio'])}) -> {chk['verdict']}")
        else:
            rs, ra = chk["robust_stable_fraction"], chk["robust_fraction_with_amplitude"]
            w(f"- m2 = {m2}: share of the gain box staying existing and stable over e in "
              f"[0.3, 0.7] x mu in [0.08, 0.12]: collocated {_p(rs['collocated'])}, "
              f"non-collocated {_p(rs['noncollocated'])} -> {chk['verdict']}; with the "
              f"primary amplitude also within 10 %: collocated {_p(ra['collocated'])}, "
              f"non-collocated {_p(ra['noncollocated'])} -> {chk['amplitude_verdict']}")
    w("")


def _runs(d, w):
    w("## Orbits at kp = 10, kv = 20\n")
    w("| m2 | case | e | exists | xm | spectral radius | stable | viability margin |")
    w("|---|---|---|---|---|---|---|---|")
    for r in d["runs"]:
        for o in r["orbits"]:
            ex = "yes" if o["exists"] else "no: " + o["reason"]
            st = "-" if o["stable"] is None else ("yes" if o["stable"] else "no")
            w(f"| {r['m2']:g} | {o['case']} | {o['e']:g} | {ex} | {_f(o['xm'], 6)} | "
              f"{_f(o['spectral_radius'], 6)} | {st} | {_f(o['viability_margin'], 4)} |")
    w("")
    w("## Basins (Figs 6-7)\n")
    w("Each point of the slice is labelled by the attractor it reaches (the symmetric orbit "
      "by the paper's criterion, other periodic orbits of P found and refined by Newton on "
      "P^k); the window is extended while the symmetric orbit's basin reaches its edge.\n")
    w("| m2 | case | e | window (x1; y1) | symmetric orbit | attractors (share of the window) |")
    w("|---|---|---|---|---|---|")
    for r in d["runs"]:
        for b in r["basins"]:
            if not b["measured"]:
                w(f"| {r['m2']:g} | {b['case']} | {b['e']:g} | - | - | empty: "
                  f"{b['why_empty']} |")
                continue
            x0, x1, y0, y1 = b["window"]
            win = f"[{x0:.3g}, {x1:.3g}]; [{y0:.3g}, {y1:.3g}]"
            if b.get("reaches_edge"):
                win += " (basin reaches the edge)"
            att = ", ".join(f"{a['name']}: {a['percent']}" for a in b.get("attractors", ())
                            if a.get("count"))
            w(f"| {r['m2']:g} | {b['case']} | {b['e']:g} | {win} | "
              f"{_p(b['converged_fraction'])} | {att} |")
    w("")


def _studies(d, w):
    for name, label in (("mu", "mu"), ("gamma", "gamma = L / x10")):
        s = d["studies"][name]
        vals = s["values"]
        idx = sorted({0, len(vals) // 4, len(vals) // 2, 3 * len(vals) // 4, len(vals) - 1})
        w(f"## Regions against {label}\n")
        w(f"Share of the gain box kp in [{s['box']['kp'][0]:g}, {s['box']['kp'][1]:g}], kv in "
          f"[{s['box']['kv'][0]:g}, {s['box']['kv'][1]:g}] where the orbit exists and is stable "
          f"(`{name}_study.png` has the curves and the ({name}, kv) map at "
          f"kp = {s['map_kp']:g}):\n")
        w("| case | e | " + " | ".join(f"{name} = {vals[i]:.3g}" for i in idx) + " |")
        w("|---|---|" + "---|" * len(idx))
        for case, q in s["fractions"].items():
            for k, e in enumerate(s["e"]):
                w(f"| {case} | {e:g} | " + " | ".join(_p(q["both"][k][i]) for i in idx) + " |")
        w("")
        w(f"Range of {name} where some gains of the box give an existing stable orbit, and "
          f"where the share peaks:\n")
        for case, q in s["fractions"].items():
            for k, e in enumerate(s["e"]):
                both = q["both"][k]
                on = [v for v, f in zip(vals, both) if f and f > 0]
                peak = max(range(len(vals)), key=lambda i, b=both: b[i] or 0)
                rng = f"[{min(on):.3g}, {max(on):.3g}]" if on else "nowhere"
                w(f"- {case}, e = {e:g}: {rng}; peak {_p(both[peak])} at {name} = "
                  f"{vals[peak]:.3g}")
        w("")
        w("Limits (derived in `symbolic/limits.py`), computed shares (exists / both) per e:\n")
        for v, per in s["limits"].items():
            for case, q in per.items():
                w(f"- {name} = {v}: {case}: exists {_ps(q['exists'])}; exists and stable "
                  f"{_ps(q['both'])}")
        w("")


def render(d: dict) -> str:
    lines = []
    w = lines.append
    _conventions(d, w)
    _m2_section(d, w)
    w("## The paper's conclusions, checked\n")
    w("A verdict is *agrees* or *contradicted* when it is the same under both conventions and "
      "at every m2 studied, *depends* otherwise.\n")
    for con in d["conclusions"]:
        _conclusion(con, d, w)
    _runs(d, w)
    _studies(d, w)
    w("## The paper's remarks on mu, checked\n")
    for r in d.get("remarks", []):
        w(f"- *{r['statement']}* **{r['verdict']}**: " + "; ".join(
            f"{k}: {v['verdict']}" for k, v in r["evidence"].items()))
    w("")
    w("## Files\n")
    w("`m2_study.png`, `mu_study.png`, `gamma_study.png`; per convention `m2=<value>/` with "
      "`fig3_orbit.png`, `fig4_regions_collocated.png`, `fig5_regions_noncollocated.png`, "
      "`fig6_basins_collocated.png`, `fig7_basins_noncollocated.png`, `regions_*.npz` "
      "(`hybridpd.sweeps.regions.load_region_map`), `basin_*.npz` "
      "(`hybridpd.sweeps.attractor_basins.load_attractor_basin`), `robustness.json`.\n")
    w("## Timings (s)\n")
    for k, v in d["timings"].items():
        w(f"- {k}: {v:.2f}")
    for r in d["runs"]:
        for k, v in r["timings"].items():
            w(f"- m2 = {r['m2']:g}, {k}: {v:.2f}")
    w("")
    return "\n".join(lines)
