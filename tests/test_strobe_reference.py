"""``hybridpd orbit --model`` on the stroboscopic section of a robot joint with backlash,
against an independent period map written from the equations (``tests/_joint_reference.py``).

The joint: a motor (inertia ``M1``, damping ``B1``) driven by the controller's torque and a
link (inertia ``M2``, damping ``B2``) coupled only through a rigid gear backlash
``|motor - link| <= L`` with restitution ``E``; the controller measures the motor and tracks
``xd = A cos(2 pi t)`` (period ``T = 1``), sampled with a zero-order hold at ``dt = 1/50,
1/200, 1/1000`` or continuous. In every period the motor's impacts on each flank accumulate and
the two bodies then move together for a good part of the half-period until the contact force
changes sign, at a sampling instant (when the held torque jumps) or, for the continuous loop,
between them: the orbit sticks, releases, flies across the clearance and impacts again.

The package's answer is read from the command's JSON (``subprocess``, as a user runs it); the
reference finds its own orbit from rest (a transient of its map), its own number of returns
per orbit, its fixed point by Newton's method with central differences, and its multipliers as
the eigenvalues of the central-difference Jacobian, on the section the package chose (its
phase ``phi0`` and mode, free or stuck) or on a phase given to both in free flight.

Parameters: the orbit sticks on both flanks for about 0.37 of every period (PD, PID and
each sampling period); sampled at 1/200 the PD's orbit returns after two periods (its two
sticking phases alternate in length) and the PID's after three, which the reference finds by
itself. A third family replaces the rigid backlash by a Kelvin-Voigt one (stiffness 200,
damping 0.8: apparent restitution about 0.5), closed on each flank for about 0.44 s.

Tolerances. The reference's flows are closed forms (or eigen-decompositions checked against
``expm`` to 1e-12), its events are located by ``brentq`` to 1e-15 s, an accumulation is summed
once the relative velocity is below 1e-10 (an error O(1e-20) in the state), and releases take
no margin (O(margin^2)). Its map rounds to ~1e-14 (rigid) and a few 1e-14 (compliant), measured
by differences along a line; central differences with the relative step 1e-5 (rigid), and
Richardson-extrapolated ones with 1e-4 (compliant), put the multipliers within ~5e-9 (rigid)
and ~5e-10 (compliant) of their limits (steps from 1e-4 to 1e-7 scanned). Measured, the
package's and the reference's spectral radii agree to 2e-9 relative or better and the fixed
points to below 1e-9. The comparison uses ``RTOL = 1e-6`` for the multipliers (over 100 times
the reference's error) and ``ATOL_STATE = 1e-9`` for the fixed point (Newton's residual is
below 1e-12). Each case runs in 2-6 s on an idle machine (the command 1-3 s of it); the
compliant loop sampled at 1 kHz (10-20 s: 1000 matrix exponentials per period) is marked slow.
"""
import json
import math
import re
import subprocess
import sys
import time

import numpy as np
import pytest
from _joint_reference import CompliantJointStrobe, JointStrobe

M1, M2 = 0.02, 0.10          # motor and link inertias
B1, B2 = 0.01, 0.02          # their viscous damping
L, E = 0.02, 0.5             # half the backlash, restitution
AMPLITUDE, OMEGA = 0.3, 2 * math.pi
PD = {"type": "pd", "kp": 8.0, "kv": 0.4}
PID = {"type": "pid", "kp": 8.0, "ki": 4.0, "kd": 0.4, "filter_time": 0.005}
RTOL = 1e-6                  # multipliers (module docstring)
ATOL_STATE = 1e-9            # fixed point
TINY = 1e-6                  # multipliers below: zero for central differences
#: periods of the reference's transient from rest before Newton (the slowest orbit here,
#: the PID's, contracts by 0.6 per period: 0.6^25 = 3e-6, far below the distance 1e-2
#: between the points of the orbits that return after several periods)
TRANSIENT = 25
#: returns to the section per orbit (both find them; 1 where not listed): sampled at 1/200
#: the PD's orbit alternates between two sticking phases of different lengths, the PID's
#: takes three periods
PD_RETURNS = {1 / 200: 2}
PID_RETURNS = {1 / 200: 3}
#: the package's coordinate names -> the reference's
NAMES = {"motor": "q1", "motor_dot": "v1", "link": "q2", "link_dot": "v2", "h0": "u",
         "c1": "I", "c2": "d"}

DTS = [pytest.param(1 / 50, id="dt=1/50"), pytest.param(1 / 200, id="dt=1/200"),
       pytest.param(1 / 1000, id="dt=1/1000"), pytest.param(None, id="continuous")]


def _toml(controller, dt, contact=f"restitution = {E!r}"):
    lines = [f"{k} = {v!r}" if isinstance(v, str) else f"{k} = {float(v)!r}"
             for k, v in controller.items()]
    if dt:
        lines.append(f"dt = {dt!r}")
    ctrl = "\n".join(lines).replace("'", '"')
    return f"""
[system]
dofs = ["motor", "link"]
masses = [{M1!r}, {M2!r}]
damping = [[{B1!r}, 0.0], [0.0, {B2!r}]]
input = [1.0, 0.0]

[[contact]]
name = "backlash"
between = ["motor", "link"]
lo = {-L!r}
hi = {L!r}
{contact}

[controller]
{ctrl}
measure = "motor"

[reference]
type = "sine"
amplitude = {AMPLITUDE!r}
omega = {OMEGA!r}

[initial]
q = [0.0, 0.0]
v = [0.0, 0.0]
"""


def _cli(tmp_path, controller, dt, *extra, contact=None):
    """``hybridpd orbit --model FILE --json`` on the joint's file: the JSON and the time."""
    path = tmp_path / "joint.toml"
    path.write_text(_toml(controller, dt) if contact is None
                    else _toml(controller, dt, contact))
    start = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "hybridpd", "orbit", "--model", str(path),
                        "--json", *extra], check=False, capture_output=True, text=True,
                       timeout=300)
    took = time.perf_counter() - start
    assert r.returncode == 0, (r.returncode, r.stderr)
    return json.loads(r.stdout), took


def _mode(section_mode):
    """The contact's state in the section's mode: ``free`` -> 0; held (``stick0+``,
    ``stick0-``) or, compliant, closed (``free/c0+``, ``free/c0-``) on a flank -> +-1."""
    if section_mode == "free":
        return 0
    m = re.fullmatch(r"(?:stick0|free/c0)([+-])", section_mode)
    assert m, section_mode
    return 1 if m.group(1) == "+" else -1


def _reference(controller, dt, phi0, mode):
    """The reference's orbit on the section ``(phi0, mode)``: a dict of its numbers."""
    start = time.perf_counter()
    R = JointStrobe(M1, M2, B1, B2, L, E, controller, AMPLITUDE, OMEGA, dt=dt, phi0=phi0,
                    mode=mode)
    x, u, c, m = R.transient(TRANSIENT)
    assert m == mode, f"the reference's motion is in mode {m} at phi0, the package's {mode}"
    X = R.coordinates(x, u, c)
    scale = max(1.0, np.max(np.abs(X)))
    # its own number of returns per orbit: the smallest n with P^n(X) close to X
    Y, n = X, 0
    for n in range(1, 5):
        Y = R(Y)
        if np.max(np.abs(Y - X)) < 1e-4 * scale:
            break
    else:
        raise AssertionError("the reference's transient returns after no n <= 4")
    Xs = R.fixed_point(X, n)
    J = R.jacobian(Xs, n)
    mult = np.linalg.eigvals(J)
    orbit = [Xs]
    for _ in range(n - 1):
        orbit.append(R(orbit[-1]))
    if n > 1:
        # a true orbit of n returns, not a fixed point of P met n times
        assert np.max(np.abs(orbit[1] - Xs)) > 1e-4 * scale
    # what one period of the orbit does: its events, the time the backlash is held
    R.record = True
    R(Xs, n)
    events = R.events
    return {"R": R, "X": Xs, "orbit": orbit, "n": n, "mult": mult,
            "events": events, "time": time.perf_counter() - start,
            "stuck": _stuck_time(events, phi0, phi0 + n * R.T, mode)}


def _stuck_time(events, t0, t1, mode):
    """Time held on each wall in ``[t0, t1]`` from the reference's events."""
    held = {1: 0.0, -1: 0.0}
    since = t0 if mode else None
    wall = mode
    for t, kind, w in events:
        if kind == "stick":
            since, wall = t, w
        elif kind.startswith("release"):
            held[w] += t - since
            since = None
    if since is not None:
        held[wall] += t1 - since
    return held


def _compare(d, ref):
    """The package's JSON ``d`` against the reference's orbit ``ref``."""
    R = ref["R"]
    assert d["exists"] and d["reason"] == "converged", d["reason"]
    assert d["event"] == "stroboscopic"
    assert d["T"] == pytest.approx(1.0, rel=1e-12)
    assert d["period"] == ref["n"], (d["period"], ref["n"])
    # the section point, in the reference's names, against the nearest point of its orbit
    names = [NAMES[k] for k in d["coordinates"]]
    ours = R.section_names()
    assert sorted(names) == sorted(ours), (d["coordinates"], ours)
    pkg = np.array([d["fixed_point"][names.index(k)] for k in ours])
    gaps = [np.max(np.abs(pkg - Z)) for Z in ref["orbit"]]
    j = int(np.argmin(gaps))
    assert gaps[j] < ATOL_STATE, (pkg, ref["orbit"][j], gaps)
    x = R.embed(ref["orbit"][j])[0]
    np.testing.assert_allclose(d["pre"], x, rtol=0, atol=ATOL_STATE,
                               err_msg="the mechanical state [q1, v1, q2, v2] at phi0")
    # multipliers: the package leaves out the structural zeros; the reference resolves none
    # below ~1e-8 (central differences), so those the package reports below TINY are only
    # checked to be tiny in both
    allm = np.array([complex(a, b) for a, b in d["multipliers"]])
    assert allm.size + (d["structural_zeros"] or 0) == ref["mult"].size, (allm, ref["mult"])
    theirs = allm[np.abs(allm) > TINY]
    mult = ref["mult"][np.argsort(-np.abs(ref["mult"]))]
    k = theirs.size
    assert np.all(np.abs(mult[k:]) < TINY), mult
    for z in theirs:
        nearest = mult[:k][np.argmin(np.abs(mult[:k] - z))]
        assert abs(nearest - z) <= RTOL * max(abs(z), 1e-3), (z, mult[:k])
    rho = float(np.abs(mult[0]))
    assert d["spectral_radius"] == pytest.approx(rho, rel=RTOL)
    assert d["stable"] == (rho < 1)
    return rho


def _report(label, d, ref, took):
    print(f"\n{label}: phi0 = {d['phi0']:.6g} ({d['section_mode']}), {ref['n']} return(s); "
          f"spectral radius package {d['spectral_radius']:.12g}, reference "
          f"{np.abs(ref['mult']).max():.12g}, relative difference "
          f"{abs(d['spectral_radius'] / np.abs(ref['mult']).max() - 1):.2g}; held "
          f"{ref['stuck'][1]:.4f} + {ref['stuck'][-1]:.4f} of {ref['n']}; "
          f"{sum(1 for e in ref['events'] if e[1] == 'impact')} impacts; "
          f"cli {took:.2f} s, reference {ref['time']:.2f} s")


def _sticks(ref):
    """The backlash is held on both flanks in every period, for a good part of it."""
    n = ref["n"]
    kinds = [e[1] for e in ref["events"]]
    assert kinds.count("stick") >= n and sum(k.startswith("release") for k in kinds) >= n
    for wall in (1, -1):
        assert ref["stuck"][wall] > 0.2 * n, ref["stuck"]
    assert sum(k == "impact" for k in kinds) >= 20 * n


@pytest.mark.parametrize("dt", DTS)
def test_pd_orbit_on_the_default_section_matches_the_reference(tmp_path, dt):
    d, took = _cli(tmp_path, PD, dt)
    ref = _reference(PD, dt, d["phi0"], _mode(d["section_mode"]))
    _report(f"PD dt={dt}", d, ref, took)
    _compare(d, ref)
    assert ref["n"] == PD_RETURNS.get(dt, 1)
    _sticks(ref)


def _free_phase(dt):
    """A phase in the free flight between a release and the next accumulation (about 0.37 s
    into the period), half a sample from the sampling instants."""
    return 0.37 if not dt else (math.floor(0.37 / dt) + 0.5) * dt


@pytest.mark.parametrize("dt", DTS)
def test_pd_orbit_on_a_free_section_matches_the_reference(tmp_path, dt):
    phi0 = _free_phase(dt)
    d, took = _cli(tmp_path, PD, dt, "--phase", repr(phi0))
    assert d["phi0"] == pytest.approx(phi0, abs=1e-12) and d["section_mode"] == "free"
    ref = _reference(PD, dt, phi0, 0)
    _report(f"PD dt={dt} free", d, ref, took)
    _compare(d, ref)


@pytest.mark.parametrize("dt", DTS[:3])
def test_sampled_pid_orbit_matches_the_reference(tmp_path, dt):
    d, took = _cli(tmp_path, PID, dt)
    ref = _reference(PID, dt, d["phi0"], _mode(d["section_mode"]))
    _report(f"PID dt={dt}", d, ref, took)
    _compare(d, ref)
    assert ref["n"] == PID_RETURNS.get(dt, 1)
    _sticks(ref)


# ---------------------------------------------------------------- a compliant backlash
K_CONTACT, C_CONTACT = 200.0, 0.8      # apparent restitution about 0.5 for the pair


def _compliant_reference(dt, phi0, mode):
    start = time.perf_counter()
    R = CompliantJointStrobe(M1, M2, B1, B2, L, K_CONTACT, C_CONTACT, PD, AMPLITUDE, OMEGA,
                             dt=dt, phi0=phi0, mode=mode)
    X, m = R.transient(TRANSIENT)
    assert m == mode, f"the reference's motion is in mode {m} at phi0, the package's {mode}"
    Y = R(X)
    assert np.max(np.abs(Y - X)) < 1e-4 * max(1.0, np.max(np.abs(X)))
    Xs = R.fixed_point(X)
    mult = np.linalg.eigvals(R.jacobian(Xs))
    R.record = True
    R(Xs)
    closed = {1: 0.0, -1: 0.0}
    since = phi0 if mode else None
    wall = mode
    for t, kind, w in R.events:
        if kind == "enter":
            since, wall = t, w
        else:
            closed[w] += t - since
    if since is not None:
        closed[wall] += phi0 + R.T - since
    return {"R": R, "X": Xs, "orbit": [Xs], "n": 1, "mult": mult, "events": R.events,
            "time": time.perf_counter() - start, "stuck": closed}


@pytest.mark.parametrize("dt", DTS[:2] + [pytest.param(1 / 1000, id="dt=1/1000",
                                                      marks=pytest.mark.slow), DTS[3]])
def test_compliant_backlash_orbit_matches_the_reference(tmp_path, dt):
    """The backlash as a Kelvin-Voigt contact: the same comparison, the gap closed on each
    flank for a good part of every period (several samples long)."""
    contact = f"stiffness = {K_CONTACT!r}\ndamping = {C_CONTACT!r}"
    d, took = _cli(tmp_path, PD, dt, contact=contact)
    ref = _compliant_reference(dt, d["phi0"], _mode(d["section_mode"]))
    _report(f"compliant dt={dt}", d, ref, took)
    _compare(d, ref)
    kinds = [e[1] for e in ref["events"]]
    assert kinds.count("enter") == kinds.count("leave") == 2
    for wall in (1, -1):
        assert ref["stuck"][wall] > 0.2, ref["stuck"]
