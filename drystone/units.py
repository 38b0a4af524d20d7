"""Physical constants with one home each (m/s^2).

Two values of the acceleration of gravity are used, on purpose:

* ``G_STANDARD`` = 9.80665 m/s^2 is standard gravity, the definition of 1 g: every
  conversion of an acceleration from or to g (a record's PGA in g, ``pga_g`` of a case,
  gal = cm/s^2 to g: 818 gal = 8.18 / 9.80665 g = 0.834 g) uses it.
* ``GRAVITY`` = 9.81 m/s^2 is the gravitational acceleration the simulations apply by
  default (the case key ``physics.gravity``, the value of the Sacsayhuaman paper), and
  the default of the analyses that stand beside a run (modal analysis, closed forms,
  generators sizing a wall by its weight). An analysis of a given run takes that run's
  gravity (spec.json ``gravity``), not this default.

They differ by 0.03 %: scaling a record to a PGA in g is independent of the gravity the
blocks feel.
"""
from __future__ import annotations

#: standard gravity (m/s^2): 1 g, for conversions from and to g and gal
G_STANDARD = 9.80665
#: default gravitational acceleration of the simulations (m/s^2), the Sacsayhuaman paper's
GRAVITY = 9.81
