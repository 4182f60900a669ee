"""The rigid-body equations, written once in CasADi, and the scenes that use them.

Modules:
- ``errors``       the exception raised for bad user input
- ``quaternion``   unit-quaternion algebra and z-x-z Euler angles (docs/theory.md §1)
- ``inertia``      inertia tensors: shapes, point masses, parallel axis, rotation,
                   principal axes and the validity conditions (docs/theory.md §3)
- ``rigid_body``   Euler's equations and the torques acting on the body (docs/theory.md §2, §4)
- ``scene``        scene files (``modelsrc/scenes/*.toml``) -> validated ``Scene`` objects
- ``features/``    one unit per capability (rotors, orbit, free motion, ...), each declaring
                   a ``feature.Feature``; ``registry`` collects them (docs/features.md)
- ``model``        a scene -> CasADi functions (rhs, outputs, checks) + FMI variable metadata
- ``integrators``  integrator steps built from the rhs (RK4 with quaternion projection)
"""
