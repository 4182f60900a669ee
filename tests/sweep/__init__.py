"""Sweeps and Monte Carlo runs (fmu.sweep): in this process and on a dask cluster, their specs and guards."""
