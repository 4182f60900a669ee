"""The scipy baselines of the report, and until 0.5.0 the alias of the former module rbcheck.baselines.

``rigid_body`` (a body about a fixed point or its centre of mass, the sampled-data loop; the
former rbcheck.baselines, whose names this package re-exports until 0.5.0, CHANGELOG.md),
``gyrostat`` (rotors in torque or speed mode), ``motion`` (a moving reference point, the
central field) and ``orbit`` (the gravity-gradient torque): the equations written again in
numpy, integrated by scipy's ``solve_ivp``.
"""

from rbcheck.baselines.rigid_body import (
    SCIPY_METHODS,
    AttitudePD,
    RigidBodyODE,
    Trajectory,
    closed_loop_scipy,
    comm_grid,
    integrate_scipy,
    run_exudyn,
    scene_has,
    table_value,
)

__all__ = [
    "SCIPY_METHODS",
    "AttitudePD",
    "RigidBodyODE",
    "Trajectory",
    "closed_loop_scipy",
    "comm_grid",
    "integrate_scipy",
    "run_exudyn",
    "scene_has",
    "table_value",
]
