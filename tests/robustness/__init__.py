"""Bad input, misuse and extreme cases: clear refusals, no crash, no hang, no silent non-finite value."""
