"""One application of the impact map with its impact pattern (walls, flight times, grazing
touches, sticking) and the flight margins, by the names of the continuation package (they live
with the map, :mod:`hybridpd.pair.impactmap`, whose hooks use them)."""
from __future__ import annotations

from hybridpd.pair.impactmap import (
    ImpactStep,
    MapTrace,
    orbit_quantities,
    trace_map,
    trace_orbit,
)

__all__ = ["ImpactStep", "MapTrace", "orbit_quantities", "trace_map", "trace_orbit"]
