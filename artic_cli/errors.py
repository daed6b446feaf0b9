"""Errors a user can act on.  The CLI turns them into one line and exit 2."""


class ArticError(Exception):
    """Bad input, missing or stale artefact: the message names problem and fix."""

    exit_code = 2


class UnreachableTarget(ArticError):
    """A target outside the reachable region (exit status 3)."""

    exit_code = 3
