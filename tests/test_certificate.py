"""Certified maps: every proved cell confirmed in arb, certificates re-proved in arb alone, cells
proved where they are of one class (adaptive subdivision) against a dense sampler.

The sampler (``_sampled_classes``) uses the package's float closed forms
(:func:`hybridpd.symmetric_orbits`: the orbit of (13)-(14), viability by guaranteed contact
location, multipliers of ``DP``) at 8 x 8 interior points of every cell and its four corners;
a cell is "of one class" when all 68 points agree.
"""
import copy
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hybridpd as hp
from hybridpd.pair import arbcheck as ac
from hybridpd.pair import arbforms, proofs
from hybridpd.pair.certificate import Certificate, load_certificate, verify_certificate
from hybridpd.pair.certified import R_ARB, REASONS, cell_edges, certified_map
from hybridpd.pair.flowintervals import FLOAT_OPS
from hybridpd.pair.interval_kernels import interval_kernel
from hybridpd.pair.prooftree import prove_cells

flint = pytest.importorskip("flint")
arb = flint.arb

FIXED = dict(mu=0.1, gamma=0.75, omega=5.0)
SMALL = dict(x=("kp", 10, 13, 3), y=("kv", 19.5, 23.5, 3), e=[0.5], **FIXED)


# ---------------------------------------------------------------------------------------------
# the dense sampler (package closed forms, floats)

def _sampled_classes(case, e, x, y, k=8):
    """Per cell (row = y): 1/2/3 if all 8 x 8 interior points and the 4 corners agree, else 0."""
    xs, ys = np.linspace(*x[1:3], x[3]), np.linspace(*y[1:3], y[3])
    xe, ye = cell_edges(xs), cell_edges(ys)
    out = np.zeros((ys.size, xs.size), int)
    for j in range(ys.size):
        for i in range(xs.size):
            px = np.linspace(xe[i], xe[i + 1], k + 2)[1:-1]
            py = np.linspace(ye[j], ye[j + 1], k + 2)[1:-1]
            P, Q = np.meshgrid(px, py)
            P = np.concatenate([P.ravel(), [xe[i], xe[i], xe[i + 1], xe[i + 1]]])
            Q = np.concatenate([Q.ravel(), [ye[j], ye[j + 1], ye[j], ye[j + 1]]])
            r = hp.symmetric_orbits(P, Q, mu=0.1, e=e, L=0.75, omega=5.0, case=case)
            c = np.where(~r.exists, 3, np.where(r.stable, 1, 2))
            out[j, i] = c[0] if (c == c[0]).all() else 0
    return out


COARSE = [
    # the default depth and budget ("auto": depth 10 for 9 x 9 cells, 512 parts) must do it
    pytest.param("noncollocated", 0.5, ("kp", 5, 9, 9), ("kv", 0.1, 4, 9), "auto",
                 id="noncollocated"),
    pytest.param("collocated", 0.1, ("kp", 0.1, 20, 9), ("kv", 0.1, 50, 9), "auto",
                 id="collocated", marks=pytest.mark.slow),   # ~10 s (2 s of arb)
]


@pytest.mark.parametrize("case, e, x, y, depth", COARSE)
def test_coarse_grid_proves_two_thirds_of_the_cells_of_one_class(case, e, x, y, depth):
    cm = certified_map(case, x=x, y=y, e=[e], depth=depth, **FIXED)
    flags = cm.flags[0]
    sampled = _sampled_classes(case, e, x, y)
    one_class = int((sampled != 0).sum())
    proved = flags != 0
    assert proved.sum() >= math.ceil(2 * one_class / 3), (proved.sum(), one_class)
    assert (flags[proved] == sampled[proved]).all()     # no proved cell contradicted
    assert cm.arb_unconfirmed.tolist() == [0]


def test_a_stable_cell_proved_by_splitting_the_sensitive_gain():
    # collocated, e = 0.1: the orbit comes back to within 1-2 % of L of the +L wall; over
    # this box the gap's margin depends almost only on kv, which the subdivision splits first
    boxes, _ = proofs.scaled_boxes(kp=(8.81, 10.05), kv=(9.46, 12.57), mu=0.1, e=0.1,
                                   gamma=0.75, omega=5.0, m2=1.0)
    tree = prove_cells("collocated", 1, boxes, depth=3)
    assert tree.cls.tolist() == [1]
    lv = tree.leaves
    area = sum((lv.hi["kpt"][i] - lv.lo["kpt"][i]) * (lv.hi["kvt"][i] - lv.lo["kvt"][i])
               for i in range(tree.leaf_cell.size))
    np.testing.assert_allclose(area, (10.05 - 8.81) * (12.57 - 9.46), rtol=1e-12, atol=0)
    widths = lv.hi["kvt"] - lv.lo["kvt"]
    assert widths.max() < 12.57 - 9.46   # kv was split
    pieces = tree.record["pieces"]
    for j in range(tree.leaf_cell.size):   # the flight of every leaf is covered
        sel = pieces["owner"] == j
        a, b = np.sort(pieces["a"][sel]), np.sort(pieces["b"][sel])
        assert a[0] == 0 and b[-1] == 1 and (a[1:] == b[:-1]).all()


# ---------------------------------------------------------------------------------------------
# arb confirmation

def test_every_proved_cell_is_confirmed_in_arb():
    cm = certified_map("noncollocated", **SMALL)
    assert cm.arb_unconfirmed.tolist() == [0] and cm.arb_seconds > 0
    assert {2, 3} <= set(cm.flags.ravel().tolist())
    plain = certified_map("noncollocated", confirm=False, **SMALL)
    np.testing.assert_array_equal(plain.flags, cm.flags)
    assert plain.arb_seconds == 0
    assert REASONS[R_ARB].startswith("undecided") and "arb" in REASONS[R_ARB]


def test_arb_refuses_a_wrong_claim():
    cm = certified_map("noncollocated", certificate=True, **SMALL)
    m = cm.certificate.maps[0]
    flags = m["flags"].ravel().copy()
    lv = m["leaves"]
    leaves = {"cell": lv["cell"], "lo": lv["lo"], "hi": lv["hi"], "cls": lv["cls"].copy(),
              "witness_s": lv["witness_s"], "witness_wall": lv["witness_wall"]}
    ok, _ = ac.confirm_map("noncollocated", 1, (3, 3), m["cells"]["lo"], m["cells"]["hi"],
                           flags, leaves)
    assert ok[flags != 0].all()
    wrong = flags.copy()
    unstable = np.flatnonzero(flags == 2)
    wrong[unstable] = 1                               # claim "stable" where it is unstable
    leaves["cls"] = np.where(leaves["cls"] == 2, 1, leaves["cls"])
    ok, _ = ac.confirm_map("noncollocated", 1, (3, 3), m["cells"]["lo"], m["cells"]["hi"],
                           wrong, leaves)
    assert not ok[unstable].any()
    assert ok[flags == 3].all()


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kp=st.floats(0.5, 45), kv=st.floats(0.5, 45), h=st.floats(0.05, 0.6),
       e=st.sampled_from([0.1, 0.5, 0.9]), case=st.sampled_from(["collocated", "noncollocated"]))
def test_arb_forms_enclose_the_closed_forms_at_points_of_the_box(kp, kv, h, e, case):
    lo = dict(kpt=np.array([kp]), kvt=np.array([kv]), mu=np.array([0.1]), e=np.array([e]),
              gam=np.array([0.75]), w=np.array([5.0]))
    hi = dict(lo, kpt=np.array([kp + h]), kvt=np.array([kv + h]))
    with flint.ctx.workprec(64):
        box = ac.ArbBoxes(lo, hi)
        q = ac.orbit_enclosures(case, 1, box)
        jets = ac.orbit_enclosures(case, 1, box, jets=True)
        w = ac.witness_enclosures(case, 1, box, np.array([0.4]))
    rng = np.random.default_rng(int(kp * 1e3 + kv))
    pts = [(kp, kv), (kp + h, kv + h), (kp + h / 2, kv + h / 2)] + \
        [tuple(rng.uniform([kp, kv], [kp + h, kv + h])) for _ in range(3)]
    slack = lambda v: 1e-9 * (1 + abs(v))
    for a, b in pts:
        args = [a, b, 0.1, e, 0.75, 5.0, 1]
        C, S, det = interval_kernel("existence", case)(FLOAT_OPS, *args)
        M = interval_kernel("halfmap", case)(FLOAT_OPS, C, S, *args)
        z3 = interval_kernel("gap", case)(FLOAT_OPS, 0.4, C, S, *args)[0]
        ref = {"C": C, "S": S, "det": det, "up": 0.75 - z3}
        for name, v in ref.items():
            r = (q if name != "up" else w)[name].r[0]
            if r.is_finite():
                assert float(r.lower()) - slack(v) <= v <= float(r.upper()) + slack(v), name
        Hf = ac.hurwitz(ac.charpoly(M))
        for f, v in zip(q["hurwitz"], Hf):
            if f.r[0].is_finite():
                assert float(f.r[0].lower()) - slack(v) <= v <= float(f.r[0].upper()) + slack(v)
    # the jets: value and gradient at the centre
    cx, cy = kp + h / 2, kv + h / 2
    args = lambda a, b: [a, b, 0.1, e, 0.75, 5.0, 1]
    Cc = interval_kernel("existence", case)(FLOAT_OPS, *args(cx, cy))[0]
    d = 1e-6
    dC = (interval_kernel("existence", case)(FLOAT_OPS, *args(cx + d, cy))[0]
          - interval_kernel("existence", case)(FLOAT_OPS, *args(cx - d, cy))[0]) / (2 * d)
    np.testing.assert_allclose(float(jets["C"].c[0].mid()), Cc, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(float(jets["C"].gc[0][0].mid()), dC, rtol=1e-4,
                               atol=1e-6 * (1 + abs(Cc)))


@pytest.mark.parametrize("name", ["ball_cu", "ball_su", "ball_emq"])
def test_entire_functions_on_balls_enclose_their_points(name):
    f = getattr(arbforms, name)
    rng = np.random.default_rng(7)
    with flint.ctx.workprec(64):
        for mid in (-30.0, -9.0, -3.5, -0.2, 0.0, 0.7, 2.0, 3.9, 4.5, 12.0):
            if name == "ball_emq" and mid < -5:
                continue
            rad = float(rng.uniform(0.01, 0.8))
            ball = arb(mid, rad)
            for j in range(3):
                enc = f(ball, j)
                for p in np.linspace(mid - rad, mid + rad, 7):
                    with flint.ctx.workprec(200):
                        v = f(arb(p), j)
                    assert enc.contains(v) or enc.overlaps(v), (name, mid, rad, j, p)
            # the derivative of order j + 1 against the difference quotient of order j
            for j in range(2):
                with flint.ctx.workprec(200):
                    hh = arb(2) ** -40
                    q = (f(arb(mid) + hh, j) - f(arb(mid) - hh, j)) / (2 * hh)
                    d = f(arb(mid), j + 1)
                assert abs(float((q - d).mid())) < 1e-15 * (1 + abs(float(d.mid())))


# ---------------------------------------------------------------------------------------------
# certificates

def test_certificate_round_trip_and_verification(tmp_path):
    path = tmp_path / "c.json"
    cm = certified_map("noncollocated", certificate=path, **SMALL)
    assert path.exists() and cm.certificate is not None
    back = load_certificate(path)
    assert back.proved_cells == int((cm.flags != 0).sum()) == cm.certificate.proved_cells
    np.testing.assert_array_equal(back.maps[0]["flags"], cm.flags[0])
    d = json.loads(path.read_text())
    assert d["format"] == "hybridpd-certificate" and d["maps"][0]["leaves"]["decision"]
    chk = verify_certificate(path)
    assert chk.ok and chk.reproved == chk.cells == back.proved_cells
    assert chk.failed == [] and chk.structure_errors == [] and chk.disagreements == 0
    assert chk.pieces > 0 and chk.viability
    assert "\n" not in repr(chk) and chk.summary().startswith("OK")
    gz = cm.save_certificate(tmp_path / "c.json.gz")
    assert verify_certificate(gz, viability=False).ok
    assert hp.verify_certificate is verify_certificate


def _tampered(cert, change):
    d = copy.deepcopy(cert.to_dict())
    change(d["maps"][0])
    return Certificate.from_dict(d)


def test_a_tampered_certificate_fails_verification():
    cert = certified_map("noncollocated", certificate=True, **SMALL).certificate
    assert verify_certificate(cert).ok

    def flip(m):                        # a proved-unstable cell claimed stable
        c = next(i for i, v in enumerate(np.ravel(m["flags"])) if v == 2)
        m["flags"][c // 3][c % 3] = 1
        for j, cell in enumerate(m["leaves"]["cell"]):
            if cell == c:
                m["leaves"]["cls"][j] = 1

    def move_leaf(m):                   # a leaf's bound moved: the leaves no longer tile
        m["leaves"]["hi"]["kvt"][0] += 0.5

    def move_cell(m):                   # a cell and its leaf moved together, across the
        c = next(i for i, v in enumerate(np.ravel(m["flags"])) if v == 2)  # existence boundary
        m["cells"]["hi"]["kvt"][c] += 2.0
        for j, cell in enumerate(m["leaves"]["cell"]):
            if cell == c:
                m["leaves"]["hi"]["kvt"][j] += 2.0

    def move_piece(m):                  # a piece of the flight moved: a gap in time
        m["pieces"]["a"][1] += 0.01

    for change in (flip, move_leaf, move_cell, move_piece):
        chk = verify_certificate(_tampered(cert, change))
        assert not chk.ok, change.__name__
        assert chk.reproved < chk.cells and chk.failed, change.__name__
        assert {"e", "ix", "iy", "claimed", "why"} <= set(chk.failed[0])


def test_bad_certificate_input(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        load_certificate(tmp_path / "nope.json")
    (tmp_path / "x.json").write_text(json.dumps({"format": "other"}))
    with pytest.raises(ValueError, match="certificate"):
        load_certificate(tmp_path / "x.json")
    with pytest.raises(ValueError, match="certificate"):
        certified_map("collocated", certificate=3.5, **SMALL)
    cm = certified_map("collocated", x=("kp", 9, 11, 2), y=("kv", 19, 21, 2), e=[0.5], **FIXED)
    with pytest.raises(ValueError, match="certificate"):
        cm.save_certificate(tmp_path / "c.json")


def test_command_line_certify_and_verify(tmp_path, capsys):
    from hybridpd.cli import main

    path = tmp_path / "c.json.gz"
    rc = main(["certify", "--case", "noncollocated", "--mu", "0.1", "--e", "0.5", "--gamma",
               "0.75", "--omega", "5", "--kp", "10", "13", "3", "--kv", "19.5", "23.5", "3",
               "--certificate", str(path)])
    out = capsys.readouterr().out
    assert rc == 0 and "not confirmed in arb: 0" in out and path.exists()
    rc = main(["certify", "--verify", str(path), "--json"])
    res = json.loads(capsys.readouterr().out)
    assert rc == 0 and res["ok"] and res["reproved"] == res["cells"]
    cert = load_certificate(path)
    bad = _tampered(cert, lambda m: m["leaves"]["hi"]["kvt"].__setitem__(
        0, m["leaves"]["hi"]["kvt"][0] + 0.5))
    bad.save(tmp_path / "bad.json")
    assert main(["certify", "--verify", str(tmp_path / "bad.json")]) == 1
    assert "FAILED" in capsys.readouterr().out
