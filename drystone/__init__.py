"""drystone: seismic analysis of dry-stone masonry with rigid polyhedral blocks in YADE.

Units are SI throughout (m, kg, s, N, Pa, rad) unless a name says otherwise (``_deg``, ``_mm``, ``_g``).
Axes: x along the wall (in plane), y through the thickness (out of plane), z vertical, up.
"""
__version__ = "0.1.0"
