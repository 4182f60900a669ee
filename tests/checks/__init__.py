"""The independent references (closed forms, Exudyn, scipy baselines) and `rbfmu check` against the FMU."""
