"""Region maps of a model continue each cell's orbit from its neighbours: the cells agree with
cold orbits on the map's own section, the section used is recorded, the example file's orbit
is a fixed point of an independent period map, and seeds of one family are tried once."""
from pathlib import Path

import numpy as np
import pytest
from _drivetrain_reference import naive_period_map

from hybridpd.analysis.model_orbits import SectionSpec, Seed, orbit_from_model, solve_at
from hybridpd.analysis.model_sections import fix_section
from hybridpd.mechanics.modelfile import load_model
from hybridpd.mechanics.params import ModelTemplate
from hybridpd.sweeps.model_regions import ModelSearch
from hybridpd.sweeps.regions import region_map

FILE = Path(__file__).resolve().parents[1] / "examples" / "models" / "drivetrain_stops.toml"


@pytest.fixture(scope="module")
def small_map():
    return region_map(ModelSearch(FILE), ("controller.kp", 30.0, 70.0, 3),
                      ("controller.kv", 4.0, 10.0, 3), progress=False)


def test_the_example_orbit_is_a_fixed_point_of_an_independent_period_map():
    po, P = orbit_from_model(load_model(FILE))
    assert po.converged and po.stable, po.reason
    data = ModelTemplate.load(FILE).data
    img = naive_period_map(data, data["controller"]["kp"], data["controller"]["kv"])(
        np.asarray(po.s), P.phase)
    np.testing.assert_allclose(img, po.s, rtol=0, atol=1e-8)
    # the held torque is overwritten at every sample: one structural zero, not noise
    assert len(po.s) - len(po.multipliers) == 1
    # every period the load enters and leaves the rubber stop and hits the hard stop once,
    # between the 1000 samples of the 500 Hz controller
    jumps = [g for g, kind in po.signature if kind == "crossing"]
    assert jumps.count("enter0+") == jumps.count("leave0+") == 1
    assert jumps.count("contact1-") == 1 and jumps.count("sample") == 1000


def test_the_command_records_and_titles_the_section_it_used(tmp_path, capsys):
    import json

    from hybridpd.cli import main
    from hybridpd.plotting.regions import _subject
    from hybridpd.sweeps.regions import load_region_map

    out = tmp_path / "map.nc"
    assert main(["regions", "--model", str(FILE), "--x", "controller.kp", "40", "60", "2",
                 "--y", "controller.kv", "5", "7", "2", "--out", str(out), "--json",
                 "--quiet"]) == 0
    d = json.loads(capsys.readouterr().out)
    # the phase the section fixes from a simulation at the file's values, found anew
    phase = fix_section(load_model(FILE), SectionSpec())[0].phase
    for fixed in (d["fixed"], load_region_map(out).fixed):
        assert fixed["section_event"] == "stroboscopic"
        assert abs(fixed["section_phase"] - phase) <= 1e-12 * max(1.0, phase)
    assert d["metadata"]["repair_stopped"].startswith("no cell gained an orbit in round")
    text = _subject(load_region_map(out))
    assert f"stroboscopic section at phi0 = {phase:g}" in text and "auto" not in text


def test_every_cell_agrees_with_a_cold_orbit_on_the_maps_section(small_map):
    rm = small_map
    assert rm.fixed["section_event"] == "stroboscopic"
    phase = rm.fixed["section_phase"]
    assert phase is not None and 0.0 <= phase < 2.0
    tpl = ModelTemplate.load(FILE)
    same = 0
    for iy, kv in enumerate(rm.y):
        for ix, kp in enumerate(rm.x):
            po, _ = orbit_from_model(tpl.model({"controller.kp": kp, "controller.kv": kv}),
                                     phase=phase)
            assert po.converged and rm.exists[0, iy, ix]
            for k, rho in (("", rm.spectral_radius), ("2", rm.spectral_radius2)):
                s = getattr(rm, f"section_point{k}")[0, iy, ix]
                if np.all(np.isfinite(s)) and np.max(np.abs(s - po.s)) <= 1e-7:
                    assert abs(rho[0, iy, ix] - po.spectral_radius) <= 1e-8
                    same += 1
                    break
    assert same >= rm.x.size * rm.y.size - 1     # at most one cell with another orbit


def test_the_map_records_and_titles_the_section_it_used(small_map):
    from hybridpd.plotting.regions import _subject

    text = _subject(small_map)
    assert "stroboscopic section at phi0 = " in text and "contact" not in text


def test_seeds_of_one_family_are_tried_once():
    m = load_model(FILE)
    spec, _, _ = fix_section(m, SectionSpec())
    po, P = orbit_from_model(m, phase=spec.phase)
    seed = Seed.of(po, P)
    far = Seed(seed.z * 1.5, seed.t, seed.signature, seed.period, seed.mode, True)
    both = solve_at(m, spec, [seed, far], simulate=False)
    once = solve_at(m, spec, [seed, far], simulate=False, families=["a", "a"])
    assert len(both.orbits) == len(once.orbits) == 1
    # the far seed costs no Newton run: chord steps land it on the orbit found first ...
    assert once.attempts == both.attempts == 1
    assert both.also and both.also[0] == (far, 0)
    # ... and with a family label it is not even tested
    assert once.also == ()
    with pytest.raises(ValueError, match="families"):
        solve_at(m, spec, [seed], families=["a", "b"])


def test_chord_landing_agrees_with_newton():
    from hybridpd.analysis.model_orbits import SEED_DAMPING, _lands_on
    from hybridpd.analysis.periodic import find_orbit

    m = load_model(FILE)
    spec, _, _ = fix_section(m, SectionSpec())
    po, P = orbit_from_model(m, phase=spec.phase)
    seed = Seed.of(po, P)
    assert seed.jacobian is not None and seed.jacobian.shape == (P.dim, P.dim)
    far = Seed(seed.z * 1.5, seed.t, seed.signature, seed.period, seed.mode, True)
    s0 = far.point(P)
    # Newton from the far seed, independently, lands on the same orbit (with the shallow
    # line search of a seeded attempt too)
    newton = find_orbit(P, s0, 1)
    assert newton.converged and np.max(np.abs(newton.s - po.s)) <= 1e-8
    shallow = find_orbit(P, s0, 1, min_lambda=SEED_DAMPING)
    assert shallow.converged and np.max(np.abs(shallow.s - po.s)) <= 1e-8
    for bad in (0.0, 1.5, -1e-3, True):
        with pytest.raises(ValueError, match="min_lambda"):
            find_orbit(P, s0, 1, min_lambda=bad)
    assert _lands_on(P, s0, 1, seed)
    # the orbit at other gains is no landing place for this model's seeds
    other, P2 = orbit_from_model(ModelTemplate.load(FILE).model({"controller.kp": 70.0}),
                                 phase=spec.phase)
    assert other.converged and np.max(np.abs(other.s - po.s)) > 1e-3
    assert not _lands_on(P, po.s, 1, Seed.of(other, P2))
    # another return count or no Jacobian: never landed
    assert not _lands_on(P, s0, 2, seed)
    assert not _lands_on(P, s0, 1, Seed(seed.z, seed.t, seed.signature, 1, seed.mode, True))
