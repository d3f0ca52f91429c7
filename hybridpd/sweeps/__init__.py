"""Sweeps over the analyses: executors and resumable stores, region maps, basins."""
