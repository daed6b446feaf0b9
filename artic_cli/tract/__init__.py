"""The speaker's vocal tract: its midsagittal outline and grid (:mod:`.outline`), the articulators' shapes
frame by frame (:mod:`.shapes`), the lip and velum controls (:mod:`.controls`), and the area functions that
the grid lines read from them (:mod:`.area_function`, :mod:`.band`, :mod:`.areas`)."""
