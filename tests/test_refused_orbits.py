"""Where no orbit was found there are no multipliers: a refused orbit reports its spectral
radius, multipliers and stability as null (JSON) and None (``to_dict``), never a verdict
"stable": false or multipliers of a point that is no orbit."""
import json
import math
from pathlib import Path

import numpy as np

import hybridpd as hp
from hybridpd.cli import main

ROBOT = Path(__file__).resolve().parents[1] / "examples" / "models" / "robot_joint.toml"
NO_VERDICT = ("multipliers", "spectral_radius", "stable", "hyperbolic")


def strict(text: str):
    def refuse(token):
        raise ValueError(f"not JSON: {token}")
    return json.loads(text, parse_constant=refuse)


def _nan_free(node) -> bool:
    if isinstance(node, float):
        return math.isfinite(node)
    if isinstance(node, dict):
        return all(_nan_free(v) for v in node.values())
    if isinstance(node, (list, tuple)):
        return all(_nan_free(v) for v in node)
    return True


class Shift(hp.PoincareMap):
    """``P(s) = s + 1``: no fixed point; Newton stops with a Jacobian at its last point."""

    names = ("x",)

    def apply(self, s, k=1, jacobian=False):
        return hp.MapResult(np.asarray(s, float) + float(k), DP=np.eye(1) if jacobian else None)


def test_to_dict_of_a_newton_failure_has_no_verdict():
    po = hp.find_orbit(Shift(), [0.0])
    assert not po.converged
    d = po.to_dict()
    assert d["exists"] is False and all(d[k] is None for k in NO_VERDICT), d
    assert _nan_free(d)


def test_to_dict_of_a_refusal_is_nan_free():
    m = hp.load_model(ROBOT)     # sampled at 1 kHz, T = pi: refused before Newton
    from hybridpd.analysis.model_orbits import orbit_from_model

    po, _ = orbit_from_model(m, transient=3.0)
    assert po.reason == "sampling_incommensurate"
    d = po.to_dict()
    assert all(d[k] is None for k in NO_VERDICT) and _nan_free(d), d


def test_orbit_model_json_of_a_refused_orbit(capsys):
    rc = main(["orbit", "--model", str(ROBOT), "--transient", "3", "--json"])
    out, err = capsys.readouterr()
    d = strict(out)
    assert rc == 3 and d["exists"] is False and "no orbit" in err
    assert all(d[k] is None for k in NO_VERDICT), {k: d[k] for k in NO_VERDICT}


def test_pair_orbit_json_of_a_missing_orbit(capsys):
    rc = main(["orbit", "--case", "noncollocated", "--mu", "0.1", "--e", "0.5", "--gamma",
               "0.75", "--omega", "0.5", "--kp", "50", "--kv", "0.1", "--json"])
    out, err = capsys.readouterr()
    d = strict(out)
    assert rc == 3 and d["exists"] is False and "no orbit" in err
    assert all(d[k] is None for k in NO_VERDICT), {k: d[k] for k in NO_VERDICT}
    orb = hp.symmetric_orbit(hp.ImpactPair(0.1, 0.5, 0.75), hp.PDGains(50, 0.1), 0.5,
                             case="noncollocated")
    assert not orb.exists and all(orb.to_dict()[k] is None for k in NO_VERDICT)
