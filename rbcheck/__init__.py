"""Independent closed-form reference solutions of rigid-body rotation.

numpy/scipy only; deliberately does not import ``modelsrc`` or ``fmu``.
Modules: ``rotation_np`` (quaternion/matrix/Euler helpers), ``free_symmetric``,
``free_asymmetric`` (Jacobi elliptic + Carlson), ``heavy_top`` (Lagrange top).
"""
