"""Mechanics: cylinders, volume constraint, assembly, integrator (CGS units inside)."""
