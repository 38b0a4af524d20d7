"""Retained soil and the site: the Sacsayhuaman section free-standing and retaining soil
(earth pressure, ASSUMED soil), its tilt collapse angle, PGA at collapse under the three
Table 3 records at rock and at the surface of the example profile (ASSUMED), and the water
level at which the retained wall fails statically. ``plan`` (walls, records, caps), ``run``
(the ``tilt`` and ``collapse`` analyses and the static runs), ``report``;
``python -m drystone.studies.site``."""
