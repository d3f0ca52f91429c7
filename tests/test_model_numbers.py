"""Every number of a model file is a TOML integer or float: a string ("8") or a boolean
(true) is refused, naming the entry, by the API and by the command line (one line, status 2);
the command line's --set values, parsed from text on purpose, still work."""
import re
from pathlib import Path

import pytest

import hybridpd
from hybridpd.cli import build_parser, main
from hybridpd.cli._common import model_of

ROBOT = Path(__file__).resolve().parents[1] / "examples" / "models" / "robot_joint.toml"
TEXT = ROBOT.read_text(encoding="utf-8")


def _edit(old: str, new: str) -> str:
    """The robot joint's file with the one line starting `old` replaced by `new`."""
    lines = TEXT.splitlines()
    hits = [i for i, ln in enumerate(lines) if ln.startswith(old)]
    assert len(hits) == 1, old
    lines[hits[0]] = new
    return "\n".join(lines) + "\n"


#: (line replaced, its replacement, the entry named in the error, what the error says it got)
BAD = [
    ("kp = ", 'kp = "8"', "controller.kp", "string"),
    ("kp = ", "kp = true", "controller.kp", "boolean"),
    ("masses = ", 'masses = [0.05, "1e-3", 0.5]', "system.masses[1]", "string"),
    ("q = ", "q = [0.0, false, 0.0]", "initial.q[1]", "boolean"),
    ("restitution = ", 'restitution = "0.3"', "contact[0].restitution", "string"),
    ("hi = ", "hi = true", "contact[0].hi", "boolean"),
    ("omega = ", 'omega = "2.0"', "reference.omega", "string"),
    ("dt = ", 'dt = "0.001"', "controller.dt", "string"),
    ("input = ", 'input = [true, 0.0, 0.0]', "system.input[0]", "boolean"),
    ("stiffness = [[200.0", 'stiffness = [[200.0, "-200", 0.0],', "system.stiffness[0][1]",
     "string"),
]


@pytest.mark.parametrize("old, new, entry, got", BAD, ids=[b[2] for b in BAD])
def test_load_model_refuses_strings_and_booleans(tmp_path, old, new, entry, got):
    f = tmp_path / "m.toml"
    f.write_text(_edit(old, new), encoding="utf-8")
    with pytest.raises(ValueError, match=re.escape(entry) + r": must be a number .*" + got):
        hybridpd.load_model(f)


@pytest.mark.parametrize("old, new, entry, got", BAD[:4], ids=[b[2] for b in BAD[:4]])
def test_cli_prints_one_line_and_exits_2(tmp_path, capsys, old, new, entry, got):
    f = tmp_path / "m.toml"
    f.write_text(_edit(old, new), encoding="utf-8")
    assert main(["orbit", "--model", str(f)]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1
    assert f"{entry}: must be a number (a TOML integer or float" in err and got in err


def test_sum_of_sines_feedforward_is_a_number_too(tmp_path):
    text = TEXT.replace('type = "sine"\namplitude = 0.5\nomega = 2.0',
                        'type = "sum_of_sines"\namplitudes = [0.5]\nomegas = [2.0]\n'
                        'feedforward_mass = "1"')
    f = tmp_path / "m.toml"
    f.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match=r"reference\.feedforward_mass: must be a number"):
        hybridpd.load_model(f)


def test_set_values_from_the_command_line_still_work(tmp_path, capsys):
    # --set KEY VALUE: VALUE is text on the command line, converted to a number first
    f = tmp_path / "m.toml"
    f.write_text(TEXT, encoding="utf-8")
    assert main(["orbit", "--model", str(f), "--list-params"]) == 0
    assert "controller.kp = 20.0" in capsys.readouterr().out
    args = build_parser().parse_args(["orbit", "--model", str(f), "--set", "controller.kp",
                                      "8", "--set", "contact.0.restitution", "0.5"])
    m = model_of(args)
    assert m.automaton.contacts[0].restitution == 0.5
    # the file's own numbers, integers included, are accepted as they are
    g = tmp_path / "int.toml"
    g.write_text(_edit("kp = ", "kp = 8"), encoding="utf-8")
    hybridpd.load_model(g)
