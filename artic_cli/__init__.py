"""artic: a physiological articulatory model of the tongue, jaw and hyoid.

After Dang & Honda (2004), "Construction and control of a physiological
articulatory model", JASA 115(2).  Layers point one way:
``cli -> control/experiments -> mechanics -> geometry -> config``.
"""

__version__ = "0.1.0"
