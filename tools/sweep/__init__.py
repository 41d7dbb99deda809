"""Sweeps: instances x methods x option grids on local processes or a Dask cluster (``bille sweep``)."""
