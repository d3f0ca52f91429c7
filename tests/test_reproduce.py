"""The main job end to end on small grids: files, figures and a summary with every check."""
import numpy as np

from hybridpd.reproduce import Settings, reproduce
from hybridpd.sweeps.basins import load_basin
from hybridpd.sweeps.regions import load_region_map


def test_reproduce_small(tmp_path):
    s = Settings(gains=(50.0, 50.0, 9), zoom=(20.0, 6.0, 9), basin=(6, 5), iterations=60,
                 comparison_grid=(10, 10))
    path = reproduce(tmp_path, settings=s, executor="serial", progress=False, log=None)
    text = path.read_text()
    for name in ("fig4_regions_collocated.png", "fig5_regions_noncollocated.png",
                 "fig6_basins_collocated.png", "fig7_basins_noncollocated.png",
                 "regions_collocated.npz", "regions_noncollocated.npz", "robustness.json"):
        assert (tmp_path / name).stat().st_size > 0
    for k in range(1, 6):
        assert f"\n{k}. *" in text            # each of the paper's conclusions is checked
    assert text.count("**") >= 10              # with a verdict in bold
    rm = load_region_map(tmp_path / "regions_collocated.npz")
    assert rm.exists.shape == (3, 9, 9)
    # the summary's table quotes the data files
    assert f"{100 * rm.fraction('stable')[1]:.2f}" in text
    b = load_basin(tmp_path / "basin_collocated_e0.5_paper.npz")
    assert b.labels.shape == (5, 6) and np.isin(b.labels, range(6)).all()
    assert f"{100 * b.converged_fraction:.2f}" in text
