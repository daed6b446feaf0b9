"""The ``artic`` command line (typer)."""
