"""Fragility curves of the 40-stone Sacsayhuaman wall (issue 15, item 1): a multiple-stripe
study under the FEMA P695 far-field set with the friction coefficient and K_n drawn per
run, lognormal fragility fitted by binomial maximum likelihood (Baker 2015) with
bootstrap bands (the fit: drystone/analyses/fragility_fit.py); ``plan`` (records, stripes, draws -> sweep
file), ``study`` (run, collect, fit, report); ``python -m drystone.studies.fragility``."""
