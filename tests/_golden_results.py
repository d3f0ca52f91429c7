"""Record (``--write``) or recompute the golden result files.

Cases: each result type written to every file suffix it takes and read back: a sweep
(``.zarr``, ``.nc``, ``.npz``), the impact pair's region map (``.nc``, ``.zarr``, ``.npz``), a
basin with two attractors and an outcome (``.nc``, ``.zarr``, ``.npz``), a bifurcation diagram
and a continued branch of the logistic map (``.nc``, ``.zarr``). Recorded per read-back
result: every field (arrays as they are, dicts of arrays per key, anything else as JSON) and
its ``to_dict()`` as JSON text; plus the ``to_dict()`` JSON of results built from their fields
(``EndPoint``, ``StableInterval``, ``BoxCertificate``, ``OrbitCertificate``, ``Attractor``,
``RobustnessComparison``, ``OptimizerRun``, ``ParamStudy``).

Run from outside the repository with the package to record on the path:
``python tests/_golden_results.py --write``.
"""
from __future__ import annotations

import dataclasses
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import _golden

PATH = _golden.DATA / "golden_results.npz"


def square(chunk):
    """The swept function of the sweep case (module level: the sweep names it)."""
    a, b = chunk["a"], chunk["b"]
    return {"sq": a * a + b, "pair": np.stack([a, -b], axis=-1)}


def _logistic():
    import hybridpd as hp

    class Logistic(hp.PoincareMap):
        names = ("x",)

        def __init__(self, r):
            self.r = r

        def apply(self, s, k=1, jacobian=False):
            x, J = s[0], 1.0
            for _ in range(k):
                J, x = self.r * (1 - 2 * x) * J, self.r * x * (1 - x)
            return hp.MapResult(np.array([x]), DP=np.array([[J]]) if jacobian else None)

    return Logistic


def _text(v) -> np.ndarray:
    from hybridpd._results import jsonable

    return np.array(json.dumps(jsonable(v)))


def _fields(name, obj) -> dict:
    """Every field of a read-back result: arrays, dicts of arrays per key, the rest as JSON."""
    out = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if f.name in ("path", "wall_time", "compute_time"):
            continue     # where and how long: not what the file holds
        if isinstance(v, np.ndarray):
            out[f"{name}.{f.name}"] = v
        elif isinstance(v, dict) and v and all(isinstance(a, np.ndarray) for a in v.values()):
            out[f"{name}.{f.name}.keys"] = np.array(list(v))
            out.update({f"{name}.{f.name}.{k}": a for k, a in v.items()})
        else:
            out[f"{name}.{f.name}"] = _text(v)
    if hasattr(obj, "to_dict"):
        out[f"{name}.to_dict"] = np.array(json.dumps(obj.to_dict()))
    return out


def _results():
    """One small result of each type (the region map, diagram and branch computed)."""
    import hybridpd as hp
    from hybridpd.analysis.basins import Attractor, BasinResult, outcome
    from hybridpd.pair.regions import SymmetricFamily
    from hybridpd.sweeps.sweep import run_sweep

    grid = {"a": np.repeat(np.linspace(0.0, 1.0, 3), 2), "b": np.tile([0.5, 2.0], 3)}
    sweep = run_sweep(square, grid, executor="serial", progress=False, chunk_size=4,
                      metadata={"note": "golden", "weights": [1.0, 2.5]})
    fam = SymmetricFamily("collocated", e=[0.3, 0.5], mu=0.1, gamma=0.75, omega=5.0)
    rm = hp.region_map(fam, x=("kp", 1, 40, 4), y=("kv", 1, 40, 3), progress=False)
    atts = (Attractor(0, "period-1 orbit", 1, np.array([[0.25, -1.5, 3.0, 0.125]]),
                      np.array([0.5 + 0.25j, 0.5 - 0.25j, 0.1, 0.0]), 0.559, True,
                      "symmetric"),
            Attractor(1, "period-2 orbit", 2, np.arange(8.0).reshape(2, 4) / 7,
                      np.array([-0.9, 0.3, 0.0, 0.0]), 0.9, True),
            outcome(-2))
    labels = np.array([[0, 0, 1, -2], [0, 1, 1, -2], [0, 0, 0, 1]])
    basin = BasinResult(np.linspace(-3.0, 5.0, 4), np.linspace(-2.0, 10.0, 3), labels,
                        atts, iterations=np.arange(12).reshape(3, 4) * 7, x_name="x1",
                        y_name="y1", metadata={"n_iter": 300, "criterion": 1e-3})
    Logistic = _logistic()
    diagram = hp.bifurcation_diagram(Logistic, np.linspace(2.8, 3.6, 7), s0=[0.4],
                                     iterations=200, keep=16)
    branch = hp.continue_orbit(Logistic, 2.5, 3.2, [0.6])
    return {"sweep": (sweep, (".zarr", ".nc", ".npz")),
            "region_map": (rm, (".nc", ".zarr", ".npz")),
            "basin": (basin, (".nc", ".zarr", ".npz")),
            "diagram": (diagram, (".nc", ".zarr")), "branch": (branch, (".nc", ".zarr"))}


def _load(name, path):
    import hybridpd as hp
    from hybridpd.analysis.basins import load_basin
    from hybridpd.analysis.continuation import load_branch
    from hybridpd.analysis.diagrams import load_diagram
    from hybridpd.sweeps.sweep import load_sweep

    return {"sweep": load_sweep, "region_map": hp.load_region_map, "basin": load_basin,
            "diagram": load_diagram, "branch": load_branch}[name](path)


def _built() -> dict:
    """``to_dict()`` JSON of results built from their fields."""
    from hybridpd.analysis.basins import Attractor
    from hybridpd.pair.certified import BoxCertificate, OrbitCertificate
    from hybridpd.pair.design.comparison import RobustnessComparison
    from hybridpd.pair.design.results import OptimizerRun
    from hybridpd.reproduce.params import ParamStudy
    from hybridpd.reproduce.study import EndPoint, StableInterval

    lo, hi = EndPoint(0.5, "window", float("nan"), True), EndPoint(1.75, "stability", 2e-9,
                                                                      True, "")
    objs = {
        "end_point": lo, "stable_interval": StableInterval(lo, hi),
        "box_certificate": BoxCertificate("proved_stable", 1, "all parts stable",
                                          "collocated", 1, {"kp": (1.0, 2.0), "kv": (3.0, 4.5)},
                                          4, 9, "decided"),
        "orbit_certificate": OrbitCertificate(
            "undecided", 0, "eigenvalues not isolated", "noncollocated", 1,
            {"kp": 10.0, "kv": 20.0}, (0.5, 0.5000001), {"phi0": (0.1, 0.2)}, None, None, 0),
        "attractor": Attractor(1, "period-2 orbit", 2, np.arange(8.0).reshape(2, 4),
                               np.array([-0.9 + 0.1j, 0.3]), 0.905, True, walls=(1, -1),
                               residual=1e-13),
        "comparison": RobustnessComparison([], {"x10_tol": 0.1, "box": [1, 2]}),
        "optimizer_run": OptimizerRun(1.0, 2.0, 0.5, 1.5, 2.5, 0.75, 40, 20, True, "done"),
        "param_study": ParamStudy("mu", np.array([0.1, 0.2]), np.array([0.5]),
                                  {"collocated": {"both": np.array([[0.25, np.nan]])}},
                                  {"kp": [1, 2, 3]}, np.array([1.0, 2.0]), 4.0,
                                  {"collocated": {"stable": np.zeros((1, 2, 2), bool)}},
                                  {"0.1": {"collocated": {"both": [0.5]}}}, {"e": 0.5}),
    }
    return {f"built.{k}": np.array(json.dumps(v.to_dict())) for k, v in objs.items()}


def compute() -> dict:
    """Every golden array, computed by the package on the path."""
    arrays = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (res, suffixes) in _results().items():
            arrays.update(_fields(f"{name}.made", res))
            for suffix in suffixes:
                path = Path(tmp) / f"{name}{suffix}"
                res.save(path)
                arrays.update(_fields(f"{name}{suffix}", _load(name, path)))
    arrays.update(_built())
    # the .npz writer of earlier versions sorted the keys of a region map's fixed parameters
    # (canonical JSON); the one .npz codec keeps their order, as .nc and .zarr always did:
    # recorded and compared with the keys sorted (the same entries and values)
    for key in ("region_map.npz.fixed", "region_map.npz.to_dict"):
        arrays[key] = np.array(json.dumps(json.loads(str(arrays[key])), sort_keys=True))
    return arrays


if __name__ == "__main__":
    if "--write" not in sys.argv:
        raise SystemExit("usage: python tests/_golden_results.py --write")
    import _golden_results  # the sweep names its function by this module's name

    arrays = _golden_results.compute()
    _golden.save(PATH, arrays)
    print(f"wrote {PATH} ({PATH.stat().st_size} bytes, {len(arrays)} arrays)")
