"""Errors a user can act on.  The CLI turns each into one line and its exit status."""


class ArticError(Exception):
    """Bad input, missing or stale artefact: the message names problem and fix."""

    exit_code = 2


class UnreachableTarget(ArticError):
    """A target outside the reachable region (exit status 3)."""

    exit_code = 3


class OffGrid(ArticError):
    """A shape whose midline the tract's grid cannot trace (the tongue left the grid)."""


class NotPhysical(ArticError):
    """A result that is not physical (NaN, an inverted brick, a Newton failure, lost volume): its file is
    written and marked invalid (exit status 4)."""

    exit_code = 4
