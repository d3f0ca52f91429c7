"""The command line explains itself: help texts, descriptions, examples, clear errors."""
import argparse

import pytest

from hybridpd.cli import COMMANDS, build_parser, main


def _subparsers():
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return parser, action.choices


def test_every_command_is_listed_with_one_line():
    parser, subs = _subparsers()
    assert set(subs) == set(COMMANDS)
    text = parser.format_help()
    for name in COMMANDS:
        assert name in text
    assert "collocated" in text and "noncollocated" in text
    assert "``" not in text  # no raw reST


@pytest.mark.parametrize("name", COMMANDS)
def test_every_option_has_help_and_the_command_an_example(name):
    _, subs = _subparsers()
    p = subs[name]
    assert p.description and len(p.description) > 60
    assert p.epilog and "example" in p.epilog and f"hybridpd {name}" in p.epilog
    for action in p._actions:
        if action.option_strings and action.dest != "help":
            assert action.help, f"{name} {action.option_strings} has no help text"


def test_unknown_flag_is_named_with_a_suggestion(capsys):
    rc = main(["orbit", "--case", "collocated", "--mu", "0.1", "--e", "0.5", "--gamma", "0.75",
               "--omega", "5", "--Kp", "10", "--kv", "20"])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1
    assert "--Kp" in err and "did you mean --kp" in err


def test_the_papers_spelling_of_the_noncollocated_case(capsys):
    rc = main(["orbit", "--case", "non-collocated", "--mu", "0.1", "--e", "0.5", "--gamma",
               "0.75", "--omega", "5", "--kp", "10", "--kv", "20", "--json"])
    assert rc == 0
    assert '"case": "noncollocated"' in capsys.readouterr().out


def test_a_bad_case_is_one_line(capsys):
    rc = main(["orbit", "--case", "colocated", "--mu", "0.1", "--e", "0.5", "--gamma", "0.75",
               "--omega", "5", "--kp", "10", "--kv", "20"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "collocated" in err
