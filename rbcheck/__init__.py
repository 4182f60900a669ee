"""The independent check of the FMU: references that share no physics with modelsrc.

Rooms (docs/architecture.md):
- ``closed_forms``  exact solutions and formulas (numpy, scipy.special): the torque-free
  body, the Lagrange top, free flight, the dual spin, the orbit, Kepler, the MIT examples;
- ``exudyn``        Exudyn multibody models of the scenes (Exudyn's own integrators);
- ``baselines``     the equations written again in numpy, integrated by scipy's solve_ivp;
- ``numerics``      numpy helpers they share: rotations, fits of sampled trajectories;
- ``checks``        ``rbfmu check``: FMU vs Exudyn vs closed forms, as a registry of checks;
- ``workprecision`` ``rbfmu report``: error against run time of every method and baseline.
The modules left at this level are aliases of moved modules, kept until 0.5.0 (CHANGELOG.md).

The reference modules never import ``modelsrc`` physics or ``fmu``. The comparison
modules (checks, workprecision) drive the FMU through ``fmu.drive``/``fmu.build`` and read
scene files with ``modelsrc.scene`` (data, not equations).
"""
