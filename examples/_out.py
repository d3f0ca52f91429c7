"""Where the examples write their figures: ``argv[1]`` or ``examples/out/``."""
import sys
from pathlib import Path


def out_dir() -> Path:
    d = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent / "out"
    d.mkdir(parents=True, exist_ok=True)
    return d
