"""Command-line interface: ``hybridpd COMMAND``.

Each command lives in its own module exposing ``register(subparsers)``; it validates its
input through the library. A bad value prints one line on stderr and exits with status 2; an
infeasible design or a missing orbit exits with 3, a diverged run with 4 and a simulation
stopped early by a bound of the run with 5 (:mod:`hybridpd.cli._common`). Machine-readable
output (``--json``) goes to stdout as one strict JSON object (``null`` for a number that is
not finite); progress goes to stderr. ``--list-params`` (commands taking ``--model``) lists
a model file's parameters before anything else is checked.
"""
from __future__ import annotations

import importlib
import sys

from hybridpd._version import __version__
from hybridpd.cli._common import EXIT_BAD_INPUT, Parser, UsageError, list_params

#: Command modules, in the order the help lists them.
COMMANDS = ("simulate", "orbit", "regions", "certify", "basin", "boundaries", "bifurcation",
            "design", "plot", "reproduce", "explore")


DESCRIPTION = """\
Analysis and design of PD control of mechanical systems with dynamic backlash: the impact
pair of Mata-Jimenez, Brogliato and Goswami (two masses, a clearance 2L, restitution e, a PD
loop with feed-forward tracking xd = xm cos(omega t)) and general linear mechanical systems
with clearances and stops.

Feedback cases: "collocated" measures the secondary mass x2, the one the force acts on;
"noncollocated" (alias "non-collocated") measures the primary mass x1 through the backlash.
Conventions: CONVENTIONS.md in the source distribution."""

EPILOG = """\
Run "hybridpd COMMAND --help" for a command's options and an example. Bad input prints one
line and exits with status 2; "hybridpd orbit" exits with 3 when there is no orbit and 4 when
the run diverged, "regions" and "bifurcation" with --model with 3 when no cell has an answer,
"hybridpd simulate" with 4 or 5 when the run stopped before its end time (see their help). With --model FILE.toml, --list-params lists the file's parameters."""


def build_parser() -> Parser:
    parser = Parser(prog="hybridpd", description=DESCRIPTION, epilog=EPILOG)
    parser.add_argument("--version", action="version", version=f"hybridpd {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser,
                                title="commands", metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"hybridpd.cli.{name}").register(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if getattr(args, "list_params", False):
            return list_params(args)
        return int(args.func(args) or 0)
    except UsageError as exc:
        print(f"hybridpd: error: {_did_you_mean(str(exc))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ValueError as exc:
        print(f"hybridpd: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("hybridpd: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of our stdout went away (e.g. `| head`): not an error of ours
        sys.stderr.close()
        return 0


def _did_you_mean(message: str) -> str:
    """argparse's "invalid choice: 'regoins'" for the command, with the closest command."""
    import difflib
    import re

    m = re.match(r"argument COMMAND: invalid choice: '([^']*)'", message)
    if not m:
        return message
    close = difflib.get_close_matches(m.group(1), COMMANDS, n=1, cutoff=0.5)
    hint = f" (did you mean {close[0]}?)" if close else ""
    return f"unknown command {m.group(1)!r}{hint}; commands: {', '.join(COMMANDS)}"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
