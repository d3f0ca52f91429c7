"""Command-line options shared by the examples: ``--out DIR`` and ``--quick``.

Every example parses its options before computing anything, so ``--help`` only prints the
example's description. Figures go to ``--out`` (default ``examples/out/``, ignored by git).
The examples live in topic folders (``examples/<topic>/plot_*.py``, the documentation's
gallery); each puts this folder on ``sys.path`` to import this module.
"""
import argparse
import sys
from pathlib import Path

DEFAULT_OUT = Path(__file__).resolve().parent / "out"


def example_args(doc: str, argv=None) -> argparse.Namespace:
    """Parse ``--out`` (created) and ``--quick`` (small settings, for tests) for an example.

    ``doc`` is the example's docstring: its title (the first line) describes the example, the
    text below the title's underline is the epilog of ``--help``.
    """
    lines = (doc or "").strip().split("\n")
    body = "\n".join(lines[2:] if len(lines) > 1 and set(lines[1]) == {"="} else lines[1:])
    p = argparse.ArgumentParser(description=lines[0], epilog=body.strip(),
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", type=Path, default=DEFAULT_OUT,
                   help=f"directory for the figures (default: {DEFAULT_OUT})")
    p.add_argument("--quick", action="store_true",
                   help="small grids and short runs: a smoke test of the example, not its "
                        "figures")
    args = p.parse_args(sys.argv[1:] if argv is None else argv)
    args.out.mkdir(parents=True, exist_ok=True)
    return args


def out_dir() -> Path:
    """The output directory of an example that has no other option."""
    return example_args(sys.modules["__main__"].__doc__ or "").out
