"""Command-line options shared by the examples: ``--out DIR`` and ``--quick``.

Every example parses its options before computing anything, so ``--help`` only prints the
example's description. Figures go to ``--out`` (default ``examples/out/``, ignored by git).
"""
import argparse
import sys
from pathlib import Path

DEFAULT_OUT = Path(__file__).resolve().parent / "out"


def example_args(doc: str, argv=None) -> argparse.Namespace:
    """Parse ``--out`` (created) and ``--quick`` (small settings, for tests) for an example."""
    p = argparse.ArgumentParser(description=doc.split("\n\n")[0],
                                epilog=doc.split("\n\n", 1)[-1],
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
