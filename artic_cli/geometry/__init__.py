"""Geometry: tongue mesh, cylinder truss, vocal-tract wall, hexahedron measures."""
