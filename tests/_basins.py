"""A model file's basin in one call (as ``hybridpd basin --model`` takes it): the section
map and orbit of :func:`~hybridpd.analysis.model_orbits.model_map`, its mapper, and
:func:`~hybridpd.sweeps.basins.basin_of_attraction` on ``(COORD, MIN, MAX, NUM)`` axes (the
slice of :func:`~hybridpd.analysis.model_orbits.default_axes` when not given)."""
from hybridpd.analysis.model_orbits import default_axes, model_map
from hybridpd.sweeps.basins import basin_of_attraction


def model_basin(model, x=None, y=None, *, n_iter=300, max_period=4, values=None,
                executor="serial", max_workers=None, **section):
    ms = model_map(model, values=values, **section)
    if x is None or y is None:
        x, y = default_axes(ms.fixed_point, ms.map.names)
    return basin_of_attraction(ms.mapper(n_iter=n_iter), x[1:], y[1:], axes=(x[0], y[0]),
                               max_period=max_period, executor=executor,
                               max_workers=max_workers)
