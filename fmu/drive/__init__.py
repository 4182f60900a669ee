"""The single-FMU driver: one scene's FMU stepped through fmpy, its inputs, and what a run shows.

``instance`` (an FMI 3.0 Co-Simulation instance through fmpy), ``inputs`` (a run's input
plan, built once per run), ``run`` (`run_fmu`, `simulate`: the communication loop),
``options`` (NAME=VALUE values of `rbfmu run` and `rbfmu sweep`), ``summary`` (the
table, CSV and plot of a run) and ``feature_views`` (each feature's panels and figures in them).
"""
