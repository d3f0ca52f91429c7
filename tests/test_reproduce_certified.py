"""The certified shares that decide the region verdicts, against independent point
evaluations: the closed-form orbits (``symmetric_orbits``) at the centres of the finest grid
must give a share inside every certified interval, and every point of a cell proved in (out)
must have (lack) the property."""
import numpy as np
import pytest

from hybridpd.pair.orbits import symmetric_orbits
from hybridpd.reproduce.certified import ShareTarget, certified_shares, merge_shares


def _centres(r):
    lo, hi = r.target.scaled_box
    edges = np.linspace(lo, hi, r.finest + 1)
    c = 0.5 * (edges[1:] + edges[:-1])
    return np.meshgrid(c, c)       # kp along columns, kv along rows


@pytest.fixture(scope="module")
def shares():
    # boxes across the grazing boundary (collocated, kv/m2 = 22), the stability boundary
    # (non-collocated, kv/m2 = 2.3) and, read at m2 = 10, both (non-collocated e = 0.1)
    targets = [ShareTarget("collocated", 0.1, box=(5.0, 40.0)),
               ShareTarget("noncollocated", 0.5, box=(0.5, 5.0)),
               ShareTarget("noncollocated", 0.1, m2=10.0, box=(5.0, 60.0),
                           properties=("exists_stable",))]
    return certified_shares(targets, grid=4, levels=1, width=0.05, keep_leaves=True)


def test_the_share_of_grid_centres_lies_in_the_certified_interval(shares):
    for r in shares:
        KP, KV = _centres(r)
        t = r.target
        o = symmetric_orbits(KP, KV, mu=t.mu, e=t.e, L=0.75, x10=1.0, omega=5.0, m2=1.0,
                             n=1, case=t.case)
        ex = np.asarray(o.exists, bool)
        es = ex & np.asarray(o.stable, bool)
        for name, mask in (("exists", ex), ("exists_stable", es),
                           ("exists_unstable", ex & ~es), ("no_orbit", ~ex)):
            lo, hi = r.interval(name)
            assert lo - 1e-12 <= mask.mean() <= hi + 1e-12, (t, name, lo, mask.mean(), hi)
        assert r.cells == KP.size and r.finest == 8


def test_every_point_of_a_proved_cell_has_the_property(shares):
    rng = np.random.default_rng(3)
    for r in shares:
        lv, t = r.leaves, r.target
        for name in ("exists_stable", "exists"):
            state = lv.state[name]
            for val in (1, -1):
                idx = np.flatnonzero(state == val)
                if idx.size == 0:
                    continue
                # random points of every proved leaf (independent of the cell centres)
                u, v = rng.random((2, idx.size, 4))
                kp = lv.kp[idx, :1] + u * (lv.kp[idx, 1:] - lv.kp[idx, :1])
                kv = lv.kv[idx, :1] + v * (lv.kv[idx, 1:] - lv.kv[idx, :1])
                o = symmetric_orbits(kp, kv, mu=t.mu, e=t.e, L=0.75, x10=1.0, omega=5.0,
                                     m2=1.0, n=1, case=t.case)
                ex = np.asarray(o.exists, bool)
                has = ex & np.asarray(o.stable, bool) if name == "exists_stable" else ex
                assert (has == (val == 1)).all(), (t, name, val)


def test_counts_tile_the_box_and_the_json_names_its_grid(shares):
    for r in shares:
        for c in r.counts.values():
            assert c["in"] + c["out"] + c["undecided"] == r.cells
        d = r.to_dict()
        assert d["grid"] == [8, 8] and d["cells"]["exists_stable"]["of"] == 64
        lo, hi = d["exists_stable"]
        assert 0 <= lo <= hi <= 1 and d["stop"] in ("width", "levels")
    np.testing.assert_allclose(shares[2].target.scaled_box, (0.5, 6.0), rtol=1e-12, atol=0)


def test_a_finer_certification_nests_in_the_coarser_one():
    t = ShareTarget("noncollocated", 0.5, box=(0.5, 5.0), properties=("exists_stable",))
    (a,) = certified_shares([t], grid=4, levels=0, width=0.0)
    (b,) = certified_shares([t], grid=4, levels=2, width=0.0)
    alo, ahi = a.interval("exists_stable")
    blo, bhi = b.interval("exists_stable")
    assert alo - 1e-12 <= blo <= bhi <= ahi + 1e-12 and (bhi - blo) < (ahi - alo)


def test_merge_adds_times_and_keeps_every_group():
    a = {"seconds": {"main": 1.0}, "cpu_seconds": {"main": 0.5}, "main": {1: "x"}}
    b = {"seconds": {"main": 2.0}, "cpu_seconds": {"main": 1.5}, "main": {2: "y"}}
    m = merge_shares([a, b])
    assert m["main"] == {1: "x", 2: "y"}
    np.testing.assert_allclose(m["seconds"]["main"], 3.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kw, name", [(dict(e=1.5), "e"), (dict(mu=0.0), "mu"),
                                      (dict(m2=-1.0), "m2"), (dict(box=(5.0, 1.0)), "box"),
                                      (dict(properties=("stable",)), "properties")])
def test_bad_targets_name_the_parameter(kw, name):
    with pytest.raises(ValueError, match=name):
        ShareTarget(**{"case": "collocated", "e": 0.5, **kw})
    with pytest.raises(ValueError, match="grid"):
        certified_shares([ShareTarget("collocated", 0.5)], grid=1)


@pytest.mark.slow
def test_quick_mode_shares_of_the_scaled_box_are_at_most_0_1_wide():
    # the shares that decide conclusions 1-3 in quick mode, every class, both cases, every e
    from hybridpd.reproduce import PAPER, Settings
    from hybridpd.reproduce.certified import CLASSES, PROPERTIES

    grid, levels, width = Settings.quick().certified
    targets = [ShareTarget(c, e, PAPER["mu"], properties=PROPERTIES)
               for c in ("collocated", "noncollocated") for e in PAPER["e"]]
    for r in certified_shares(targets, grid=grid, levels=levels, width=width):
        for name in CLASSES:
            lo, hi = r.interval(name)
            assert hi - lo <= 0.1, (r.target, name, lo, hi)


def test_the_mu_remark_proves_the_rise_inside_the_range_from_real_proofs():
    # the non-collocated e = 0.5 existence share, certified at the ends of the mu range and
    # at mu = 1.78 inside it: the remark agrees over the range (the end falls below the
    # start) and reports the proved rise to mu = 1.78 with the certified shares, each of
    # which holds the share of its finest grid's cell centres (closed forms, independent)
    from hybridpd.reproduce import conclusions as C

    mus = (0.01, 10 ** 0.25, 10.0)
    res = certified_shares([ShareTarget("noncollocated", 0.5, m, properties=("exists",))
                            for m in mus], grid=8, levels=3, width=0.1)
    ivs = [r.interval("exists") for r in res]
    for r, iv in zip(res, ivs):
        KP, KV = _centres(r)
        o = symmetric_orbits(KP, KV, mu=r.target.mu, e=0.5, L=0.75, x10=1.0, omega=5.0,
                             m2=1.0, n=1, case="noncollocated")
        assert iv[0] - 1e-12 <= np.mean(o.exists) <= iv[1] + 1e-12
    c = C.check_mu_existence((mus[0], mus[2]), {"noncollocated": [ivs[0]]},
                             {"noncollocated": [ivs[2]]}, [0.5],
                             inside={("noncollocated", 0.5): [(mus[1], ivs[1])]})
    t = c["trends"]["noncollocated e=0.5"]
    assert t["verdict"] == "agrees"
    assert t["against"] is not None and t["against"]["interval"] == [mus[0], mus[1]]
    # the move is proved: the later share's lower end above the earlier one's upper end
    assert t["against"]["by"] == pytest.approx(ivs[1][0] - ivs[0][1]) and ivs[1][0] > ivs[0][1]


def test_a_per_target_gamma_is_the_clearance_of_the_box():
    # one batch with two values of gamma: each share holds its own closed-form share
    targets = [ShareTarget("collocated", 0.5, properties=("exists_stable",), gamma=g)
               for g in (0.5, 1.2)]
    res = certified_shares(targets, grid=4, levels=1, width=0.05)
    for r in res:
        KP, KV = _centres(r)
        o = symmetric_orbits(KP, KV, mu=0.1, e=0.5, L=r.target.gamma, x10=1.0, omega=5.0,
                             m2=1.0, n=1, case="collocated")
        lo, hi = r.interval("exists_stable")
        assert lo - 1e-12 <= np.mean(np.asarray(o.stable, bool)) <= hi + 1e-12
    with pytest.raises(ValueError, match="gamma"):
        ShareTarget("collocated", 0.5, gamma=-1.0)
