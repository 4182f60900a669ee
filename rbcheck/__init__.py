"""The independent check of the FMU: references that share no physics with modelsrc.

- closed forms (numpy/scipy only): ``rotation_np`` (quaternion/matrix/Euler helpers),
  ``free_symmetric``, ``free_asymmetric`` (Jacobi elliptic + Carlson), ``heavy_top``
  (Lagrange top quadratures), ``frame_kinematics`` (two-frame arm), ``skewed_bar``;
- Exudyn multibody models: ``exudyn_models`` (every scene), ``skewed_bar`` (revolute joint);
- the comparisons: ``checks`` (``rbfmu check``), ``motion_fits``, and the
  work-precision report ``workprecision`` (a package) with ``baselines`` (``rbfmu report``).

The reference modules never import ``modelsrc`` physics or ``fmu``. The comparison
modules drive the FMU through ``fmu.run``/``fmu.build_fmu`` and read scene files with
``modelsrc.scene`` (data, not equations).
"""
