"""Artefact store: HDF5 files written atomically, with provenance."""
