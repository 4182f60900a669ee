"""The test suite of rbfmu (pytest): the FMU, the model, the checks, the docs and the layout."""
