"""Figures (matplotlib, Agg backend): axes in cm, legends, written atomically."""
