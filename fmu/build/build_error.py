"""The error of a build that cannot go on: a compiler failed or is missing, or a build setting is invalid."""

from __future__ import annotations


class BuildError(RuntimeError):
    """A compiler failed, warned on the hand-written layer, or is missing; or a build setting
    (an environment variable the build reads) has a value it cannot take."""
