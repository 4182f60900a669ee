"""From a scene's CasADi model to a real FMU, and fmpy driving it.

Modules:
- ``codegen``            CasADi -> C of the model functions (never hand-written)
- ``model_data``         the generated header that feeds the generic C layer
- ``model_description``  modelDescription.xml / buildDescription.xml from the metadata
- ``build_fmu``          gcc + zip: scene -> SCENE.fmu
- ``run``                fmpy co-simulation of a scene's FMU
- ``cli``                the ``rbfmu`` command
"""

# The package version (pyproject.toml reads it from here); the FMU's modelDescription.xml
# carries it as `version`. Bump it when an FMU's interface changes (CHANGELOG.md).
__version__ = "0.4.0"
