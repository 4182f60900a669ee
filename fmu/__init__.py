"""From a scene's CasADi model to a real FMU, and fmpy driving it.

Rooms (docs/architecture.md):
- ``build``     the build: CasADi -> C (never hand-written), model_data.h, compilation for
                every platform, modelDescription.xml, source FMU, documentation, the archive
- ``c``         the generic FMI C layer (hand-written, model-agnostic)
- ``drive``     the single-FMU driver: fmpy co-simulation of a scene's FMU, its input plan
- ``bench``     C-level benchmarks of the generated step and fmi3DoStep
- ``gendocs``   the generated parts of docs/ and the README
- ``sweep``     grids and Monte Carlo runs on dask
- ``terminal``  progress bars of the long commands
- ``cli``       the ``rbfmu`` command
The modules left at this level besides ``cli`` are aliases of moved modules, kept until
0.5.0 (CHANGELOG.md).
"""

# The package version (pyproject.toml reads it from here); the FMU's modelDescription.xml
# carries it as `version`. Bump it when an FMU's interface changes (CHANGELOG.md).
__version__ = "0.4.0"
