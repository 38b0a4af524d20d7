"""What stone shape does to a wall's collapse (issue 25, item 7): walls of the Sacsayhuaman
section's footprint, height and weight built of coursed, polygonal convex, polygonal
interlocking (multi-part stones) and split interlocking stones; tilt collapse angle and
PGA at collapse bracketed by bisection. ``plan`` (geometries, records), the bisection's pure
logic (drystone/analyses/bisect.py), ``study`` (rounds of sweeps, report); ``python -m drystone.studies.shape``."""
