"""Fragility curves of the 40-stone Sacsayhuaman wall: a multiple-stripe study under the FEMA
P695 far-field set with the friction coefficient and K_n drawn per run, run by the
``fragility`` analysis (``--method stripes``, the draws given run by run), lognormal fragility
fitted by binomial maximum likelihood (Baker 2015) with bootstrap bands (the fit:
drystone/analyses/fragility_fit.py); ``plan`` (records, stripes, draws), ``study`` (run,
collect, fit, report); ``python -m drystone.studies.fragility``."""
