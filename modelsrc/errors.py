"""The one exception type for bad user input (scene files, parameters, start values)."""


class ModelInputError(ValueError):
    """Raised for invalid user input; the message names the value and what is allowed."""
