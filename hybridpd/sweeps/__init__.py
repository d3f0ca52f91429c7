"""Sweeps over the analyses: executors, resumable Zarr stores, progress, labelled results
(xarray, netCDF, Zarr), region maps, basins."""
