"""The build of an FMU: generated C, its compilation for each platform, modelDescription.xml, the archive.

From a scene's CasADi model (modelsrc) to SCENE.fmu: ``codegen`` (CasADi -> C),
``model_data`` (the header the C layer reads), ``compile`` and ``cross_compile`` (gcc, zig cc;
``platforms``), ``model_description`` (modelDescription.xml, buildDescription.xml),
``source_fmu`` (CMakeLists.txt), ``archive_docs``, ``build_check``, ``icon``, ``licensing``
(documentation/, icon, licence), ``versions`` (the tools' versions) and ``build_fmu``, which
zips it all. The C layer itself is fmu/c/.
"""
