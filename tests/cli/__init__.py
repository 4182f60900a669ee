"""The rbfmu command as a user runs it: subcommands, their errors and what a run shows."""
