"""Modes on demand: a chain with many clearances loads in O(m) and builds only the modes a
run visits; the visited modes reproduce a fully built automaton."""
import numpy as np
import pytest

from hybridpd.mechanics import simulate
from hybridpd.mechanics.samples import mass_chain


def test_a_thirty_clearance_chain_builds_only_what_it_visits():
    ma = mass_chain(31)
    assert ma.automaton.n_built == 1                      # the free mode only
    assert ma.automaton.table_bytes < 50e6
    tr = simulate(ma, np.zeros(62), (0.0, 100.0), max_impacts=300)
    assert tr.termination == "jump_limit" and tr.n_impacts > 200
    visited = set(tr.hybrid.segments.mode)
    assert ma.automaton.n_built <= len(visited) + 1     # (+1: a mode entered at the end)
    assert ma.automaton.table_bytes < 200e6
    # any valid mode name can be looked up without building it
    assert "stick0+29-" in ma.modes and ma.modes["stick0+29-"].stick == ((0, 1), (29, -1))
    assert "stick0+0-" not in ma.modes and "free/c0+" not in ma.modes
    with pytest.raises(KeyError):
        ma.modes["stick30+"]


def test_on_demand_matches_a_materialized_automaton():
    """The same run on a chain whose every reachable mode was built first (at most
    3^3 = 27) gives the same jumps bit for bit."""
    lazy = mass_chain(4)
    full = mass_chain(4)
    n_all = full.automaton.materialize()
    assert 8 <= n_all <= 27 and full.automaton.n_built == n_all
    x0 = np.zeros(8)
    a = simulate(lazy, x0, (0.0, 20.0), max_impacts=400)
    b = simulate(full, x0, (0.0, 20.0), max_impacts=400)
    assert lazy.automaton.n_built < n_all
    assert a.hybrid.jumps.guard == b.hybrid.jumps.guard
    np.testing.assert_allclose(a.hybrid.jumps.t, b.hybrid.jumps.t, rtol=0, atol=0)
    np.testing.assert_allclose(a.post, b.post, rtol=0, atol=0)


def test_an_automaton_built_on_demand_pickles_for_workers():
    """Worker processes receive the automaton by pickle: the mode builder goes with it and
    builds the modes the copy visits, with the same jumps."""
    import pickle

    ma = mass_chain(4)
    simulate(ma, np.zeros(8), (0.0, 5.0), max_impacts=300)
    ha = pickle.loads(pickle.dumps(ma.automaton))
    assert ha.n_built == ma.automaton.n_built
    z0 = ma.initial_state(np.zeros(4), np.zeros(4))
    a = ma.automaton.simulate(z0, "free", (0.0, 5.0), max_jumps=2000)
    b = ha.simulate(z0, "free", (0.0, 5.0), max_jumps=2000)
    assert len(b.jumps) > 100 and b.jumps.guard == a.jumps.guard
    np.testing.assert_allclose(b.jumps.t, a.jumps.t, rtol=0, atol=0)
