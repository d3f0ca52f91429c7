"""Analyses on the impact map: symmetric orbits, the map and its Jacobian, any-LTI orbits,
continuation and controller design."""
