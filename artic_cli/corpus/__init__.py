"""A corpus: its list of items (:mod:`.listing`), its index (:mod:`.index`), the EMA-style tables (:mod:`.ema`) and
the dataset card (:mod:`.card`).  :mod:`artic_cli.stages.corpus` speaks it on a dask.distributed cluster."""
