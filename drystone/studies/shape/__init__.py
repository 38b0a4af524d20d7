"""What stone shape does to a wall's collapse: walls of the Sacsayhuaman section's footprint,
height and weight built of coursed, polygonal convex, polygonal interlocking (multi-part
stones) and split interlocking stones; tilt collapse angle and PGA at collapse by the
``tilt`` and ``collapse`` analyses. ``plan`` (geometries, records), ``study`` (the walls'
analyses, report); ``python -m drystone.studies.shape``."""
