"""Reproducing the paper: Figs 3-7, the convention study and the verdicts
=======================================================================

``hybridpd reproduce`` recomputes the results section of Mata-Jiménez, Brogliato & Goswami
and writes its figures, data, ``summary.md`` and ``summary.json``. The paper does not give
the secondary mass ``m2``; since only ``kp/m2`` and ``kv/m2`` matter at fixed ``mu``, the run
first locates the intervals of ``m2`` in which the orbits at the paper's gains exist and are
stable, then draws Figs 3-7 at ``m2 = 1`` and at the ``m2`` chosen by a documented rule, and
checks every conclusion of the paper with numbers. This script runs the same command
(``--quick``: the coarse grids; ``--full`` uses the paper's 200 x 200 grids) and prints the
summary it wrote; every number in it is computed in the run.

Run: ``python examples/reproduction/plot_reproduce_paper.py [--out DIR] [--quick]``.
"""
import sys
from pathlib import Path

from hybridpd.cli import main as hybridpd_command

# sphinx_gallery_start_ignore
sys.path.insert(0, str(Path(sys.argv[0]).resolve().parents[1]))  # examples/_out.py
# sphinx_gallery_end_ignore
from _out import example_args

ARGS = example_args(__doc__)
status = hybridpd_command(["reproduce", "--quick" if ARGS.quick else "--full",
                           "--out", str(ARGS.out), "--quiet"])
if status != 0:  # an error, not an exit: the gallery must not stop silently
    raise RuntimeError(f"hybridpd reproduce failed with status {status}")
print((ARGS.out / "summary.md").read_text())
