"""One small reproduction shared by the reproduce and figure tests (run once per session)."""
import functools
import tempfile
from pathlib import Path

from hybridpd.reproduce import Settings

SMALL = Settings(gains=(50.0, 50.0, 9), zoom=(20.0, 6.0, 9), basin=(6, 5), iterations=300,
                 comparison_grid=(6, 6), uncertainty_grid=(2, 2), design_search=(1, 10),
                 m2_robust_grid=(6, 6), m2_grid=201, m2_verdicts=3, m2_robust=1,
                 certified=(4, 1, 0.3), certified_readings=(2, 1, 0.5),
                 certified_ends=(2, 2, 0.5), certified_values=(2, 1, 0.5),
                 certify_every_value=True, param_points=5,
                 param_grid=5)


@functools.cache
def small_run():
    """``(summary.md path, {figure path: Figure})`` of a reproduction on :data:`SMALL`."""
    from hybridpd.reproduce import reproduce

    out = Path(tempfile.mkdtemp(prefix="hybridpd-reproduce-"))
    figures = {}
    path = reproduce(out, settings=SMALL, executor="serial", progress=False, log=None,
                     figure_hook=lambda p, f: figures.__setitem__(Path(p), f))
    return path, figures
