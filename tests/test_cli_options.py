"""Each command-line option is declared once: the same name means the same option (type,
arity, default, choices and help) in every command, and no public name of the command line
shadows one of the library's."""
import argparse
import ast
import pathlib
import re
from collections import defaultdict

import pytest

import hybridpd
from hybridpd.cli import build_parser, main
from hybridpd.cli._common import GRID_HELP, LIST_HELP, PAIR_HELP

# Options whose name means something else in one command, by design: the axes of a grid
# (--x/--y: a coordinate, a file's entry or a parameter with its range), the command's own
# iteration bounds, plot's image (--out) and reproduce's output folder and list of m2
# conventions.
_OWN = {"--x", "--y", "--iterations", "--max-period", "--coordinate"}
_OWN_IN = {("plot", "--out"), ("reproduce", "--out"), ("reproduce", "--m2")}
# Options whose help names what the command writes or draws (one template, one keyword).
_TEMPLATE = {"--out": "write ", "--plot": "draw "}


def _actions():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    by_flag = defaultdict(dict)
    for name, p in sub.choices.items():
        for action in p._actions:
            for flag in action.option_strings:
                if flag.startswith("--") and flag != "--help":
                    by_flag[flag][name] = action
    return by_flag


def _shape(action):
    choices = None if action.choices is None else tuple(action.choices)
    return (action.dest, action.type, choices, action.const, type(action).__name__)


def test_every_shared_option_is_the_same_option_in_every_command():
    shared = 0
    for flag, cmds in _actions().items():
        cmds = {c: a for c, a in cmds.items() if flag not in _OWN and (c, flag) not in _OWN_IN}
        if len(cmds) < 2:
            continue
        shared += 1
        shapes = {c: _shape(a) for c, a in cmds.items()}
        assert len(set(shapes.values())) == 1, (flag, shapes)
        if flag in _TEMPLATE:
            for c, a in cmds.items():
                assert a.help.startswith(_TEMPLATE[flag]), (flag, c, a.help)
            continue
        name = flag[2:]
        if name in PAIR_HELP:
            # one value, or (a keyword of add_pair) a grid or a list with a fixed suffix
            for c, a in cmds.items():
                assert a.help in (PAIR_HELP[name], PAIR_HELP[name] + GRID_HELP,
                                  PAIR_HELP[name] + LIST_HELP), (flag, c, a.help)
                want = {PAIR_HELP[name]: None, PAIR_HELP[name] + GRID_HELP: 3,
                        PAIR_HELP[name] + LIST_HELP: "+"}[a.help]
                assert a.nargs == want, (flag, c, a.nargs)
            continue
        # a command's own default (a keyword of the option's group) may be named in the help
        helps = {c: re.sub(r"default: [^,;)]+", "default: D", a.help) for c, a in cmds.items()}
        assert len(set(helps.values())) == 1, (flag, helps)
        nargs = {c: a.nargs for c, a in cmds.items()}
        assert len(set(map(str, nargs.values()))) == 1, (flag, nargs)
    # the pair's parameters, the model-file, output and executor options are all shared
    assert shared >= 25


@pytest.mark.parametrize("flag", ["--e", "--kp", "--mu", "--gamma", "--omega", "--case",
                                  "--model", "--period", "--mode", "--json", "--executor"])
def test_the_pairs_and_the_model_files_options_are_in_the_commands_that_take_them(flag):
    cmds = _actions()[flag]
    assert len(cmds) >= 3, (flag, sorted(cmds))


@pytest.mark.parametrize("command", ["bifurcation", "boundaries", "orbit"])
def test_the_papers_spelling_of_the_case_is_accepted_everywhere(command):
    # a bad case is one line and status 2 in every command, the alias is no bad case
    parser = build_parser()
    args = parser.parse_args([command, "--case", "non-collocated"]
                             + (["--x", "kp", "1", "2", "--y", "kv", "1", "2"]
                                if command == "boundaries" else []))
    assert args.case == "noncollocated"
    assert main([command, "--case", "colocated"]) == 2


# Every command module defines these two (the protocol build_parser and main call).
_PROTOCOL = {"register", "run"}


def _module_level_public_defs(path):
    tree = ast.parse(path.read_text())
    return {n.name for n in tree.body
            if isinstance(n, (ast.FunctionDef, ast.ClassDef)) and not n.name.startswith("_")
            and n.name not in _PROTOCOL}


def test_no_public_function_of_the_command_line_shares_a_name_with_the_library():
    root = pathlib.Path(hybridpd.__file__).parent
    cli_names = defaultdict(list)
    lib_names = defaultdict(list)
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        target = cli_names if rel.startswith("cli/") else lib_names
        for name in _module_level_public_defs(path):
            target[name].append(rel)
    clash = {n: (cli_names[n], lib_names[n]) for n in cli_names if n in lib_names}
    assert not clash, clash
    twice = {n: where for n, where in cli_names.items() if len(where) > 1}
    assert not twice, twice


def test_grid_axes_and_max_period_have_one_shape_in_every_command(capsys):
    from hybridpd.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices
    for name, word, nargs in (("regions", "KEY", 4), ("basin", "COORD", 4),
                              ("boundaries", "NAME", 3), ("explore", "KEY", 4)):
        acts = {a.dest: a for a in sub[name]._actions}
        for ax in ("x", "y"):
            assert acts[ax].nargs == nargs and acts[ax].metavar[0] == word
            assert acts[ax].metavar[1:3] == ("MIN", "MAX")
    assert not {"x1", "y1"} & {a.dest for a in sub["basin"]._actions}
    defaults = {n: next(a.default for a in sub[n]._actions if a.dest == "max_period")
                for n in ("basin", "bifurcation")}
    assert defaults == {"basin": 8, "bifurcation": 32}
    # the pair's basin takes its slice axes by name, x1 and y1 only
    pair = ["basin", "--case", "collocated", "--mu", "0.1", "--e", "0.5", "--gamma", "0.75",
            "--omega", "5", "--kp", "10", "--kv", "20"]
    assert main([*pair, "--x", "motor", "-1", "1", "3"]) == 2
    assert "takes x1, got 'motor'" in capsys.readouterr().err
    assert main([*pair, "--x", "x1", "-1", "1", "3.5"]) == 2
    assert "NUM must be an integer" in capsys.readouterr().err
    assert main([*pair, "--max-period", "65"]) == 2
    assert "--max-period must be in [1, 64]" in capsys.readouterr().err
