"""Closed-form references: exact solutions and formulas that share no code with modelsrc (numpy, scipy.special).

The torque-free body (``free_symmetric``, ``free_asymmetric``), the Lagrange top
(``heavy_top``), the moving reference point (``free_flight``), the dual-spin gyrostat
(``dual_spin``), the orbit (``gravity_gradient``, ``kepler``), the MIT 2.003J examples
(``frame_kinematics``, ``skewed_bar``), the sampled-data slew (``slew``) and the speed-command
motor's lag (``motor_lag``).
"""
