"""The command line on users' own model files: parameters listed, strict JSON, exit statuses,
the orbit's jump sequence summarised, the sticking tail counted honestly."""
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridpd.cli import build_parser, main
from hybridpd.cli._common import dumps_json, json_ready

try:
    import tomllib
except ModuleNotFoundError:     # Python 3.10
    import tomli as tomllib

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"
DRIVETRAIN = str(MODELS / "drivetrain.toml")
ROBOT = str(MODELS / "robot_joint.toml")
PAIR = ["--case", "collocated", "--mu", "0.1", "--e", "0.5", "--omega", "5"]
#: commands that take --model and set or sweep its parameters
MODEL_COMMANDS = ("orbit", "regions", "basin", "bifurcation", "simulate")


def strict(text: str):
    """``json.loads`` refusing NaN and Infinity (what JSON itself does not have)."""
    def refuse(token):
        raise ValueError(f"not JSON: {token}")
    return json.loads(text, parse_constant=refuse)


def _walk(node, prefix=""):
    """Dotted paths of the numbers of a TOML table, written here independently."""
    if isinstance(node, bool):
        return {}
    if isinstance(node, (int, float)):
        return {prefix: float(node)}
    out = {}
    items = node.items() if isinstance(node, dict) else enumerate(node) \
        if isinstance(node, list) else ()
    for k, v in items:
        out.update(_walk(v, f"{prefix}.{k}" if prefix else str(k)))
    return out


def _subparser(name):
    parser = build_parser()
    return parser._subparsers._group_actions[0].choices[name]


@pytest.mark.parametrize("name", MODEL_COMMANDS)
def test_list_params_prints_every_numeric_entry_of_the_file(name, capsys):
    assert main([name, "--model", ROBOT, "--list-params"]) == 0
    lines = capsys.readouterr().out.splitlines()
    with open(ROBOT, "rb") as fh:
        expected = _walk(tomllib.load(fh))
    got = {}
    for line in lines:
        key, value = line.split(" = ")
        got[key] = float(value)
    assert list(got) == list(expected)
    np.testing.assert_allclose([got[k] for k in expected], list(expected.values()),
                               rtol=0, atol=0)
    assert "controller.ki" in got and "contact.0.restitution" in got
    assert main([name, "--model", ROBOT, "--list-params", "--json"]) == 0
    doc = strict(capsys.readouterr().out)
    assert doc["parameters"] == got


@pytest.mark.parametrize("name", MODEL_COMMANDS)
def test_help_says_where_the_parameters_are_and_what_is_written(name):
    text = _subparser(name).format_help()
    assert "--list-params" in text and "controller.kp" in text
    if name in ("regions", "basin", "bifurcation"):
        flat = " ".join(text.split())
        assert "by suffix (.nc, .zarr or .npz)" in flat
    if name == "bifurcation":
        assert "with --model a dotted path" in " ".join(text.split())


def test_list_params_needs_a_model(capsys):
    assert main(["orbit", "--list-params"]) == 2
    assert "--model" in capsys.readouterr().err


def test_shared_options_are_declared_once():
    # one declaration in _common: the same help text in every command
    helps = {n: {a.dest: a.help for a in _subparser(n)._actions} for n in MODEL_COMMANDS}
    assert len({h["list_params"] for h in helps.values()}) == 1
    # --model's help differs only by how the command takes the parameters
    assert len({h["model"].rsplit("; ", 1)[0] for h in helps.values()}) == 1
    assert len({helps[n]["set"] for n in ("orbit", "basin", "simulate")}) == 1
    src = (Path(__file__).resolve().parents[1] / "hybridpd" / "cli")
    for f in src.glob("*.py"):
        if f.name != "_common.py":
            text = f.read_text()
            assert '"--model"' not in text and '"--set"' not in text, f.name


@settings(max_examples=60, deadline=None)
@given(st.recursive(st.floats(allow_nan=True, allow_infinity=True) | st.integers()
                    | st.booleans() | st.none() | st.text(max_size=4),
                    lambda c: st.lists(c, max_size=4)
                    | st.dictionaries(st.text(max_size=4), c, max_size=4), max_leaves=20))
def test_json_ready_replaces_exactly_the_non_finite_numbers(obj):
    back = strict(dumps_json(obj))

    def same(a, b):
        if isinstance(a, float) and not math.isfinite(a):
            return b is None
        if isinstance(a, dict):
            return list(a) == list(b) and all(same(a[k], b[k]) for k in a)
        if isinstance(a, list):
            return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
        return a == b and type(a) is type(b)
    assert same(obj, back)


def test_json_ready_on_numpy():
    d = json_ready({"a": np.array([[1.0, np.nan], [np.inf, -2.0]]), "b": np.float32(0.5),
                    "c": np.int64(3), "d": (np.bool_(True), complex(1, 2))})
    assert d == {"a": [[1.0, None], [None, -2.0]], "b": 0.5, "c": 3, "d": [True, [1.0, 2.0]]}


def _run(argv, capsys):
    rc = main(argv)
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_every_command_json_is_strict(tmp_path, capsys):
    runs = [
        (["simulate", *PAIR, "--L", "0.75", "--kp", "10", "--kv", "20", "--xm", "1",
          "--x0", "0.3", "0.5", "0", "0", "--t-end", "2", "--json"], 0),
        (["simulate", "--model", DRIVETRAIN, "--t-end", "2", "--json"], 0),
        (["orbit", "--case", "noncollocated", *PAIR[2:], "--gamma", "0.75", "--kp", "0.5",
          "--kv", "50", "--json"], 3),
        # a sampled loop whose period has no common multiple with the reference's: refused
        # before Newton, with NaN fields that strict JSON writes as null
        (["orbit", "--model", ROBOT, "--json"], 3),
        (["regions", *PAIR[:4], "--e", "0.5", "--gamma", "0.75", "--omega", "5", "--kp", "1",
          "50", "3", "--kv", "1", "50", "3", "--quiet", "--json"], 0),
        (["basin", *PAIR, "--gamma", "0.75", "--kp", "10", "--kv", "20", "--x", "x1", "-3", "5",
          "4", "--y", "y1", "-2", "10", "4", "--iterations", "60", "--max-extensions", "0",
          "--quiet", "--json"], 0),
        (["boundaries", "--case", "collocated", "--mu", "0.1", "--e", "0.5", "--gamma",
          "0.75", "--omega", "5", "--x", "kp", "5", "15", "--y", "kv", "15", "25",
          "--seed-grid", "5", "--json"], 0),
        (["bifurcation", *PAIR[:4], "--e", "0.1", "--gamma", "0.75", "--omega", "5", "--kp",
          "10", "--param", "kv", "20", "24", "3", "--iterations", "40", "--keep", "10",
          "--out", str(tmp_path / "d.nc"), "--json"], 0),
    ]
    for argv, status in runs:
        rc, out, _ = _run(argv, capsys)
        assert rc == status, argv
        assert isinstance(strict(out), dict)
    rc, out, _ = _run(["orbit", "--model", ROBOT, "--json"], capsys)
    doc = strict(out)
    assert doc["reason"] == "sampling_incommensurate" and doc["t_period"] is None


def test_orbit_exit_statuses_and_the_epilog(capsys):
    rc, out, err = _run(["orbit", *PAIR, "--gamma", "0.75", "--kp", "10", "--kv", "20"], capsys)
    assert rc == 0 and err == ""
    rc, out, err = _run(["orbit", "--case", "noncollocated", *PAIR[2:], "--gamma", "0.75",
                         "--kp", "0.5", "--kv", "50"], capsys)
    assert rc == 3 and "viability violated" in out
    assert len(err.splitlines()) == 1 and "no orbit" in err
    rc, out, err = _run(["orbit", "--model", ROBOT], capsys)
    assert rc == 3 and "no orbit" in err
    epilog = _subparser("orbit").epilog
    assert all(f"  {k}  " in epilog for k in (0, 2, 3, 4))


def _diverging_simulation(model, t_end):
    """An independent check that the loop with kv = -30 is unstable: the linear flow of the
    free mode (no contact closed) has an eigenvalue with positive real part."""
    from hybridpd.mechanics.params import ModelTemplate

    m = ModelTemplate.load(model).model({"controller.kv": -30.0})
    A = m.automaton.automaton.modes[0].A
    return float(np.max(np.linalg.eigvals(A).real))


def test_a_diverging_model_exits_4_for_orbit_and_simulate(capsys):
    assert _diverging_simulation(DRIVETRAIN, 50) > 0
    rc, out, err = _run(["orbit", "--model", DRIVETRAIN, "--set", "controller.kv", "-30",
                         "--event", "release"], capsys)
    assert rc == 4 and len(err.splitlines()) == 1 and "diverged" in err
    rc, out, err = _run(["simulate", "--model", DRIVETRAIN, "--set", "controller.kv", "-30",
                         "--t-end", "50", "--json"], capsys)
    doc = strict(out)
    assert rc == 4 and doc["termination"] in ("nonfinite", "diverged")
    assert len(err.splitlines()) == 1 and doc["termination"] in err
    assert doc["t_final"] < 50


def test_simulate_stopped_at_the_jump_limit_exits_5_pair_and_model(capsys):
    rc, out, err = _run(["simulate", "--model", DRIVETRAIN, "--t-end", "20",
                         "--max-impacts", "30", "--json"], capsys)
    doc = strict(out)
    assert rc == 5 and doc["termination"] == "jump_limit" and doc["t_final"] < 20
    assert len(err.splitlines()) == 1 and "jump_limit" in err
    rc, out, err = _run(["simulate", *PAIR, "--L", "0.75", "--kp", "10", "--kv", "20",
                         "--xm", "1", "--x0", "0.3", "0.5", "0", "0", "--t-end", "10",
                         "--max-impacts", "5"], capsys)
    assert rc == 5 and "jump_limit" in out and "jump_limit" in err
    assert len(err.splitlines()) == 1
    rc, *_ = _run(["simulate", "--model", DRIVETRAIN, "--t-end", "2"], capsys)
    assert rc == 0
    epilog = _subparser("simulate").epilog
    assert "jump_limit" in epilog and "  5  " in epilog and "  4  " in epilog


def test_a_sampled_models_orbit_prints_a_summary_of_its_jumps(capsys):
    argv = ["orbit", "--model", ROBOT, "--set", "reference.omega", repr(2 * math.pi / 3),
            "--event", "release"]
    _, out, _ = _run([*argv, "--json"], capsys)
    seq = strict(out)["impact_sequence"]
    assert len(seq) > 3000                   # a sampling instant every 1 ms of a 3 s period
    _, out, _ = _run(argv, capsys)
    line = next(ln for ln in out.splitlines() if "jumps per period" in ln)
    assert len(line) < 400 and f"jumps per period: {len(seq)}" in line
    # the counts of the summary add up to the sequence, kind by kind
    body = line.split(f"jumps per period: {len(seq)}: ", 1)[1].split(" (counts")[0]
    counts = {}
    for part in body.split(", "):
        lab, _, n = part.partition(" x ")
        counts[lab] = counts.get(lab, 0) + (int(n) if n else 1)
    expected = {}
    for g, k in seq:
        lab = g if k == "crossing" else f"{g} ({k})"
        expected[lab] = expected.get(lab, 0) + 1
    assert counts == expected and expected["sample"] >= 2990
    _, out, _ = _run([*argv, "--full-sequence"], capsys)
    full = next(ln for ln in out.splitlines() if "jumps per period" in ln)
    assert len(full.split(": ", 2)[2].split(" ")) >= len(seq)


def test_the_sticking_tail_says_what_it_counts(capsys):
    rc, out, _ = _run(["simulate", "--model", DRIVETRAIN, "--t-end", "20", "--json"], capsys)
    stick = strict(out)["sticking"]
    assert rc == 0
    assert len(stick) > 10
    _, out, _ = _run(["simulate", "--model", DRIVETRAIN, "--t-end", "20"], capsys)
    line = next(ln for ln in out.splitlines() if "more sticking intervals" in ln)
    rest = sum(b - a for a, b, _ in stick[10:])
    total = sum(b - a for a, b, _ in stick)
    assert f"{len(stick) - 10} more sticking intervals ({rest:.6g} time units)" in line
    assert f"{len(stick)} intervals, {total:.6g} time units held in all" in line
