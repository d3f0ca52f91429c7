"""Divergence is named ``diverged`` (exit status 4) wherever it happens: in Newton's iterates
and images, in the simulation that seeds a model's orbit search, in the statuses of sweeps."""
from pathlib import Path

import numpy as np
import pytest

import hybridpd as hp
from hybridpd.analysis.model_orbits import STATUS, solve_at
from hybridpd.analysis.model_sections import DivergedRun, SectionSpec
from hybridpd.analysis.periodic import DIVERGENCE_BOUND
from hybridpd.cli import main

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"
ROBOT = MODELS / "robot_joint.toml"


def _negative_kp(tmp_path, name="robot_joint.toml", kp="20.0"):
    """The example with kp = -5: the loop pushes away from the reference and the motion
    grows without bound."""
    text = (MODELS / name).read_text(encoding="utf-8")
    assert f"\nkp = {kp}\n" in text
    f = tmp_path / f"neg_{name}"
    f.write_text(text.replace(f"\nkp = {kp}\n", "\nkp = -5.0\n"), encoding="utf-8")
    return f


class _Map(hp.PoincareMap):
    names = ("x",)

    def __init__(self, image, dp=1.0, ok=True):
        self.image, self.dp, self.ok = image, dp, ok

    def apply(self, s, k=1, jacobian=False):
        if not self.ok:
            return hp.MapResult(np.full(1, np.nan), ok=False, status="nonfinite")
        return hp.MapResult(np.array([self.image(float(s[0]))]),
                            DP=np.array([[self.dp]]) if jacobian else None)


@pytest.mark.parametrize("P, what", [
    # the image of the start is already past 1e6 times its scale
    (_Map(lambda x: 1e7 * (1 + x * x), dp=0.0), "image"),
    # the map's run overflowed
    (_Map(None, ok=False), "nonfinite"),
    # P(s) = s + 1 with a nearly singular Jacobian: Newton's iterates run off to ~1e11
    (_Map(lambda x: x + 1.0, dp=1.0 + 1e-9), "iterate"),
], ids=["image", "nonfinite", "iterate"])
def test_newton_names_divergence(P, what):
    po = hp.find_orbit(P, [0.5])
    assert not po.converged and po.reason == "diverged", (po.reason, po.detail)
    assert what in po.detail
    d = po.to_dict()
    assert d["stable"] is None and d["spectral_radius"] is None


def test_newton_without_divergence_is_unchanged():
    po = hp.find_orbit(_Map(lambda x: 0.5 * x + 1.0, dp=0.5), [0.0])
    assert po.converged and abs(po.s[0] - 2.0) < 1e-12
    assert DIVERGENCE_BOUND == 1e6


def test_status_codes_keep_their_values_and_add_diverged_last():
    assert [STATUS[k] for k in range(11)] == [
        "stable", "unstable", "not_converged", "degenerate_return", "grazing",
        "not_periodic", "fast_return", "map_undefined", "sampling_incommensurate",
        "no_section_crossing", "invalid_parameters"]
    assert list(STATUS)[-1] == 11 and STATUS[11] == "diverged"


def test_orbit_of_a_diverging_loop_exits_4(tmp_path, capsys):
    # a transient of 3 time units: the simulator's own bound is not reached, the motion
    # has grown past 1e6 times the scale of its start (it read "sampling_incommensurate",
    # exit 3, before)
    f = _negative_kp(tmp_path)
    rc = main(["orbit", "--model", str(f), "--transient", "3"])
    err = capsys.readouterr().err
    assert rc == 4 and len(err.splitlines()) == 1, err
    assert "the run diverged" in err and "diverged" in err.split("the run diverged", 1)[1]


def test_a_sweep_cell_of_a_diverging_loop_is_diverged(tmp_path):
    f = _negative_kp(tmp_path, "robot_joint_sampled.toml", "8.0")
    m = hp.load_model(f)
    res = solve_at(m, SectionSpec())
    assert STATUS[res.status] == "diverged" and not res.orbits, res
    assert "diverged" in res.detail


def test_basin_of_a_diverging_loop_exits_4(tmp_path, capsys):
    f = _negative_kp(tmp_path, "robot_joint_sampled.toml", "8.0")
    rc = main(["basin", "--model", str(f), "--x", "link", "-0.1", "0.1", "3", "--y",
               "link_dot", "-1", "1", "3", "--quiet"])
    err = capsys.readouterr().err
    assert rc == 4 and len(err.splitlines()) == 1 and "diverged" in err, err
    assert issubclass(DivergedRun, ValueError)
