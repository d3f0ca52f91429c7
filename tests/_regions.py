"""The tests' calls of the one region map: the impact pair's symmetric family and a model
file's search, with the keywords of their families and of the grid in one call."""
from dataclasses import fields

from hybridpd.pair.regions import SymmetricFamily
from hybridpd.sweeps.model_regions import ModelSearch
from hybridpd.sweeps.regions import region_map

_PAIR = {f.name for f in fields(SymmetricFamily)} - {"case"}
_MODEL = {f.name for f in fields(ModelSearch)} - {"model"}


def pair_region_map(case="collocated", **kw):
    """``region_map(SymmetricFamily(case, ...), x, y, ...)``."""
    fam = SymmetricFamily(case, **{k: kw.pop(k) for k in list(kw) if k in _PAIR})
    return region_map(fam, kw.pop("x", ("kp", 0.1, 50.0, 200)),
                      kw.pop("y", ("kv", 0.1, 50.0, 200)), **kw)


def model_region_map(model, x, y, **kw):
    """``region_map(ModelSearch(model, ...), x, y, ...)``."""
    fam = ModelSearch(model, **{k: kw.pop(k) for k in list(kw) if k in _MODEL})
    return region_map(fam, x, y, **kw)
