"""Command-line interface: ``hybridpd COMMAND``.

Each command lives in its own module exposing ``register(subparsers)``; it validates its
input through the library. A bad value prints one line on stderr and exits with status 2 (an
infeasible design exits with 3). Machine-readable output (``--json``) goes to stdout as one
JSON object; progress goes to stderr.
"""
from __future__ import annotations

import importlib
import sys

from hybridpd._version import __version__
from hybridpd.cli._common import EXIT_BAD_INPUT, Parser, UsageError

#: Command modules, in the order the help lists them.
COMMANDS = ("simulate", "orbit", "regions", "basin", "boundaries", "bifurcation", "design",
            "reproduce")


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
        return int(args.func(args) or 0)
    except UsageError as exc:
        print(f"hybridpd: error: {exc}", file=sys.stderr)
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
