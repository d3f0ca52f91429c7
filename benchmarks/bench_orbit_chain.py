"""``hybridpd orbit --model`` on a chain of masses with m clearances, m = 1 ... 30.

System (:func:`hybridpd.mechanics.samples.chain_model_text`, the chain of ``mass_chain``):
unit masses, neighbour springs (20) and dampers (0.1) in parallel with rigid clearances of
+-0.05 (e = 0.8), a PD loop (kp 50, kv 5) on the first mass tracking ``cos 3 t``; up to 3^m
modes, built as the runs enter them.

Printed per m, each in a fresh process (the model file written to a temporary directory):
the wall time of the whole command (interpreter start included), its peak memory, its exit
status and outcome (the orbit found, or the one-line reason why not), the modes built and the
memory of their tables; the transient simulation that seeds Newton (its jumps and cost per
jump); and for a few m the naive alternative's cost per impact (:mod:`hybridpd.mechanics.
naive`: a ``solve_ivp`` loop, DOP853, rtol 1e-10, atol 1e-12, terminal events, restarted at
every impact, measured in the same run over ``--naive-impacts`` impacts) with the ratio, and
the time that loop would take for the command's transient alone (its jumps at that cost).

Run: ``python benchmarks/bench_orbit_chain.py [--ms 1,2,...] [--naive-ms 1,2,3,5]``.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from hybridpd.mechanics.naive import naive_mechanical
from hybridpd.mechanics.samples import chain_matrices, chain_model_text

_CHILD = r"""
import contextlib, importlib, io, json, resource, sys, time
mf = importlib.import_module("hybridpd.mechanics.modelfile")
ms = importlib.import_module("hybridpd.mechanics.simulate")
seen = {}
_load, _sim = mf.load_model, ms.simulate

def load(path):
    seen["model"] = _load(path)
    return seen["model"]

def sim(*a, **k):
    t = time.perf_counter()
    tr = _sim(*a, **k)
    seen["sim"] = (time.perf_counter() - t, len(tr.hybrid.jumps))
    return tr

mf.load_model, ms.simulate = load, sim
from hybridpd.cli import main
out, err = io.StringIO(), io.StringIO()
with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
    rc = main(["orbit", "--model", sys.argv[1]])
text = out.getvalue().splitlines() + err.getvalue().splitlines()
ha = seen["model"].automaton.automaton if "model" in seen else None
print(json.dumps({
    "rc": rc, "lines": text,
    "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    "modes": ha.n_built if ha else 0, "table_mb": ha.table_bytes / 1e6 if ha else 0.0,
    "sim": seen.get("sim")}))
"""


def outcome(lines) -> str:
    """The command's verdict in a few words: the orbit's stability, or why there is none."""
    for ln in lines:
        if "spectral radius" in ln:
            return ln.split("->")[-1].strip()
    for ln in lines:
        if ln.strip().startswith("no orbit:"):
            return ln.strip()[len("no orbit:"):].strip().split(":")[0][:60]
    for ln in lines:
        if ": " in ln and " after " in ln:
            return ln.split("): ", 1)[-1].split(" after ")[0][:60]
    return (lines[-1] if lines else "no output")[:60]


def run_orbit(m, d):
    f = Path(d) / f"chain{m}.toml"
    f.write_text(chain_model_text(m + 1))
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", _CHILD, str(f)], capture_output=True, text=True,
                       check=False)
    wall = time.perf_counter() - t0
    if p.returncode != 0 or not p.stdout.strip():
        return {"wall": wall, "rc": p.returncode, "lines": p.stderr.splitlines()[-1:],
                "rss_mb": float("nan"), "modes": 0, "table_mb": float("nan"), "sim": None}
    r = json.loads(p.stdout.strip().splitlines()[-1])
    r["wall"] = wall
    return r


def naive_per_impact(m, n_impacts):
    M, C, K, B = chain_matrices(m + 1)
    eye = np.eye(m + 1)
    contacts = [(eye[i] - eye[i + 1], -0.05, 0.05, 0.8) for i in range(m)]
    t0 = time.perf_counter()
    r = naive_mechanical(M, C, K, B, contacts, 50.0, 5.0, eye[0], 1.0, 3.0, 0.0,
                         np.zeros(2 * (m + 1)), (0.0, 1e4), max_impacts=n_impacts,
                         rtol=1e-10, atol=1e-12)
    return (time.perf_counter() - t0) / max(len(r.impact_times), 1)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ms", default=",".join(str(m) for m in range(1, 31)))
    ap.add_argument("--naive-ms", default="1,2,3,5")
    ap.add_argument("--naive-impacts", type=int, default=60)
    args = ap.parse_args(argv)
    ms = [int(s) for s in args.ms.split(",")]
    naive_ms = {int(s) for s in args.naive_ms.split(",") if s}
    print("hybridpd orbit --model CHAIN.toml, fresh process per m (wall includes start-up)")
    print("  m  wall[s] peak[MB] rc modes table[MB] trans.jumps us/jump  naive[us] ratio "
          "naive_trans[s]  outcome")
    with tempfile.TemporaryDirectory() as d:
        for m in ms:
            r = run_orbit(m, d)
            sim = r.get("sim")
            jumps, us = (sim[1], sim[0] / max(sim[1], 1) * 1e6) if sim else (0, float("nan"))
            nv = naive_per_impact(m, args.naive_impacts) * 1e6 if m in naive_ms else float("nan")
            print(f"{m:3d} {r['wall']:8.2f} {r['rss_mb']:8.0f} {r['rc']:2d} {r['modes']:5d} "
                  f"{r['table_mb']:9.1f} {jumps:11d} {us:7.1f} {nv:10.0f} {nv / us:5.0f}x "
                  f"{nv * jumps / 1e6:14.1f}  {outcome(r['lines'])}", flush=True)


if __name__ == "__main__":
    main()
