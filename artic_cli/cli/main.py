"""``artic``: the command line.

Each command is a thin shell over a stage module (:mod:`artic_cli.stages`) or a plot, in one module per topic:
:mod:`.mechanics`, :mod:`.maps`, :mod:`.solve`, :mod:`.tract`, :mod:`.speech`, :mod:`.corpus`, :mod:`.plot`, :mod:`.export`.
Exit statuses: 0 done, 2 bad input (one line on stderr), 3 target not reached (the answer is written), 4
result not physical (the file is written and marked invalid), 130 interrupted.
"""

from __future__ import annotations

from .app import app
from . import mechanics, maps, solve, tract, speech, corpus, plot, export  # noqa: E402,F401,I001  (each registers its commands)

__all__ = ["app", "main"]


def main() -> None:  # pragma: no cover - console entry
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
