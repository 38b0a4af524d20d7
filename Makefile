# drystone: every target installs what is missing first (make setup is idempotent and quick).
SHELL   := /bin/bash
VENV    := .venv
PY      := $(VENV)/bin/python
JOBS    ?= 2
# YADE threads of one run: 1 is bitwise reproducible (docs: reproducibility); JOBS is the number of parallel runs
THREADS ?= 1
PYTEST_ARGS ?= -n $(JOBS)
# make test hands each worker whole test files, the longest first (tests/conftest.py orders them): the
# workers finish together and a module's shared runs are made once
PYTEST_DIST ?= --dist loadfile --no-loadscope-reorder
SUDO    := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
DEB_PKGS := yade python3-matplotlib python3-venv
STAMP   := $(VENV)/.setup-stamp
RUN     := $(PY) -m drystone

.PHONY: setup system-deps test demo run gravity4 settlement4 bench clean help records spectrum ogawa3d ogawa \
        reference sweep tilt tilt-rate tilt-sensitivity tilt-report sacsayhuaman sacsayhuaman-report vtk ogawa-pga readme docs free-decay pulse-overturning \
        fragility fragility-small fragility-report crosscheck shape-study shape-study-small shape-study-report \
        site-study site-study-small site-study-report report analyse limit

help:
	@echo "make setup        install Debian's YADE, make .venv, install PyPI dependencies"
	@echo "make demo         the main job: verification cases + the 40-stone wall under one record at two PGAs (~3 min)"
	@echo "make test         the test suite"
	@echo "make run CASE=cases/x.toml [SET='key=value ...'] [THREADS=1]   run any case file (one thread: bitwise reproducible)"
	@echo "make analyse ANALYSIS=tilt|collapse|... CASE=cases/x.toml [ARGS='--towards all'] [DASK=...]   an analysis of any case (python -m drystone ANALYSIS CASE ARGS) -> results/<case name>/<analysis>/"
	@echo "make gravity4 | settlement4   the paper's four-block verification cases"
	@echo "make limit [CASE=cases/sacsayhuaman/sine.toml] [ARGS='--towards all']   rigid-block limit analysis: collapse multiplier, tilt angle and mechanism, both frictions (seconds, no YADE) -> results/<case name>/limit/"
	@echo "make bench [BENCH='--only scale --sizes 500']   speed figures (not a test; every section but fragility_ida ~12 min on 2 cores; fragility_ida, the 22-record IDA, hours: pick sections with --only)"
	@echo "                  BENCH='--only fragility_ida --records 2 --tolerance 0.2': fragility by IDA of the Sacsayhuaman wall over N far-field records, extrapolated to 22"
	@echo "                  BENCH='--only profile --sizes 500 --walls polygonal': the step's time per kernel and phase, sampled by perf inside the compiled loop (needs linux-perf)"
	@echo "                  BENCH='--baseline e18ca1f --sizes 500 --walls polygonal': this tree's scale section and an earlier commit's, back to back in alternating rounds (~8 min)"
	@echo "make reference    regenerate tests/data/reference/ (stored histories of test_regression.py) after an intended change"
	@echo "make pulse-overturning   least one-sine pulse that overturns a slender block, damping 0.8 and Housner's, beside Zhang & Makris's rigid block (~20 min)"
	@echo "make free-decay   damping ratio per mode of one block, both contact geometries, and a slender block's rocking restitution per impact vs Housner at 3 K_n x 4 dampings (~3 min)"
	@echo "make ogawa        Ogawa et al.: Tables 1-3 check and figure, 1D friction studies and report (~15 min)"
	@echo "make ogawa3d      the same five blocks in 3D (YADE) for the named friction sets (~4 min per set) + make ogawa-pga"
	@echo "make ogawa-pga    3D: both block readings, PGA sweep (end-block overturning), reset vs cumulative (~30 min on 2 cores)"
	@echo "make docs         regenerate the result tables of README.md and docs/*.md from results/*/ (skips missing reports), the case keys and layout tables"
	@echo "make readme       the same as make docs"
	@echo "make records      papers' records (user files or FEMA P695 analogues) -> results/records/catalogue.json"
	@echo "make spectrum FILE=path [ARGS=...]   PGA, PGV, Arias, Sa(T), duration, predominant frequencies (JSON) + PNG"
	@echo "make sweep SWEEP=cases/sweeps/x.toml [DASK=tcp://host:8786|local]   a sweep, parallel and resumable"
	@echo "make modal CASE=cases/x.toml [ARGS='--identify --modes 8']   frequencies and mode shapes of any wall, settled (results/<case name>/modal/)"
	@echo "make tilt         tilt-table validation, the tilt analysis of 5 generated walls + the same 5 with a constant section (~20 min) + report"
	@echo "make tilt-rate    the paper's 0.2 deg/s protocol on wall seed 0 (~10 min) + report"
	@echo "make tilt-sensitivity   mu, K_n and Table 1's DEM calibration on wall seed 0 (7 runs) + report"
	@echo "make tilt-report  rewrite results/tilt/ from the tilt analyses made so far"
	@echo "make sacsayhuaman [DASK=...]   40-stone wall: white noise, sine sweeps, resonance PGAs, Table 3 (~1 h on 2 cores)"
	@echo "make sacsayhuaman-report       rewrite results/sacsayhuaman/ from the runs made so far"
	@echo "make report DIR=results/<run>   one self-contained HTML page of a finished run: <run>/report.html (a study's folder: report.md as HTML)"
	@echo "make vtk DIR=results/<run> [EVERY=5]   VTK files of a finished run for ParaView (<run>/vtk/blocks.pvd)"
	@echo "make fragility [DASK=...]      fragility curves: FEMA P695 far field (22 records) x PGA 0.1-1.0 g, mu and K_n drawn per run, by the fragility analysis, stripes (220 runs; cost in results/fragility/report.md)"
	@echo "make fragility-small           the fragility pipeline on 4 short runs (~2 min on 2 cores; not a result)"
	@echo "make fragility-report          rewrite results/fragility/ from the runs made so far"
	@echo "make shape-study [DASK=...]     stone shape: coursed, polygonal, interlocking (multi-part) and split walls of the Sacsayhuaman section's size, 3 seeds: the tilt and collapse analyses of each wall under 3 records (cost in results/shape/report.md)"
	@echo "make shape-study-small          the shape study's pipeline on 2 variants, 1 seed, 1 short record (~20 s; not a result)"
	@echo "make shape-study-report         rewrite results/shape/ from the analyses made so far"
	@echo "make site-study [DASK=...]      retained soil and the site: the Sacsayhuaman section free-standing and retaining soil (ASSUMED): tilt angle, PGA at collapse under 3 records at rock and at the surface of the example profile (collapse analyses), water level at static failure (cost in results/site/report.md)"
	@echo "make site-study-small           the site study's pipeline on 1 short record, coarse brackets (~30 s; not a result)"
	@echo "make site-study-report          rewrite results/site/ from the runs made so far"
	@echo "make crosscheck [XC=all]   LMGC90 (rigid) vs this package: toppling block + half-sine pulse (~3 min); XC=all adds the 40-block wall (~10 min) and the 5 tilt walls (hours); skipped without compas_lmgc90"
	@echo "make clean        delete what the package wrote in results/ (its runs, sweeps, studies) and .numba_cache/; says what it left (the kernels shared by your checkouts in ~/.cache/drystone/numba stay)"

setup: system-deps $(STAMP)

system-deps:
	@missing=""; for p in $(DEB_PKGS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "setup: installing Debian packages:$$missing"; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $$missing; \
	fi

$(STAMP): requirements.txt requirements-nodeps.txt requirements-crosscheck.txt constraints.txt pyproject.toml | system-deps
	@# no pip of its own: Debian's (python3-pip, which python3-venv brings) installs into it, 5 s less
	@test -x $(PY) || /usr/bin/python3 -m venv --system-site-packages --without-pip $(VENV)
	$(PY) -m pip install -q --no-compile --disable-pip-version-check -c constraints.txt -r requirements.txt
	$(PY) -m pip install -q --no-compile --disable-pip-version-check --no-deps -r requirements-nodeps.txt
	$(PY) -m pip install -q --no-compile --disable-pip-version-check -c constraints.txt --no-deps -r requirements-crosscheck.txt \
	  || echo "setup: compas_lmgc90 (LMGC90, optional) not installed: make crosscheck will be skipped"
	$(PY) -m pip install -q --no-compile --disable-pip-version-check --no-deps --no-build-isolation -e .
	@# the packages' bytecode on every core at once (pip writes it one file after another: half of its time), but
	@# not of their own test suites (a third of the files, never imported here); a file that does not compile
	@# (pip skips those too) is left to the interpreter
	$(PY) -m compileall -q -j 0 -x '/tests?/' $(VENV)/lib >/dev/null || true
	$(PY) -c "import numpy, scipy; assert numpy.__version__ == '1.24.2' and scipy.__version__ == '1.10.1', 'numpy/scipy are not Debian''s'"
	@touch $@

# the suite's processes keep their bytecode (__pycache__/, ignored by git) where the environment says not to
# (PYTHONDONTWRITEBYTECODE): each worker's collection otherwise rewrites and compiles every test module again
test: setup
	env -u PYTHONDONTWRITEBYTECODE $(PY) -m pytest $(PYTEST_DIST) $(PYTEST_ARGS)

run: setup
	@test -n "$(CASE)" || { echo "usage: make run CASE=path/to/case.toml [SET='key=value ...']"; exit 2; }
	$(RUN) run "$(CASE)" -j $(THREADS) $(foreach s,$(SET),--set $(s))

gravity4: setup
	$(RUN) run cases/gravity4.toml -j $(THREADS)

settlement4: setup
	$(RUN) run cases/settlement4.toml -j $(THREADS)

ogawa: setup
	$(PY) -m drystone.studies.ogawa insitu
	$(PY) -m drystone.studies.ogawa study

ogawa3d: setup
	$(PY) -m drystone.studies.ogawa study3d --workers $(JOBS)
	$(MAKE) ogawa-pga

ogawa-pga: setup
	$(RUN) sweep cases/sweeps/ogawa_pga.toml --workers $(JOBS)
	$(RUN) sweep cases/sweeps/ogawa_cumulative.toml --workers $(JOBS)
	$(PY) -m drystone.studies.ogawa refresh

docs: setup
	$(PY) -m drystone.studies.readme_tables
	$(RUN) keys --update-docs
	$(RUN) layout --update-docs

readme: docs

demo: setup
	$(RUN) run cases/gravity4.toml -j $(THREADS)
	$(RUN) run cases/settlement4.toml -j $(THREADS)
	$(RUN) compare results/gravity4 results/settlement4
	$(PY) -m drystone.studies.sacsayhuaman demo --workers $(JOBS)

reference: setup
	$(PY) tests/make_reference.py

bench: setup
	$(RUN) bench $(BENCH)

LIMIT_CASE ?= cases/sacsayhuaman/sine.toml
limit: setup
	$(RUN) limit $(or $(CASE),$(LIMIT_CASE)) $(or $(ARGS),--towards all)

free-decay: setup
	$(RUN) free-decay

pulse-overturning: setup
	$(PY) -m drystone.studies.pulse_overturning

records: setup
	$(PY) -m drystone.motions records

spectrum: setup
	@test -n "$(FILE)" || { echo "usage: make spectrum FILE=path/to/record [ARGS='--component EW --units gal --dt 0.01']"; exit 2; }
	$(PY) -m drystone.motions spectrum "$(FILE)" $(ARGS)

analyse: setup
	@test -n "$(ANALYSIS)" -a -n "$(CASE)" || { echo "usage: make analyse ANALYSIS=tilt|collapse|... CASE=cases/x.toml [ARGS='...'] [DASK=tcp://host:8786|local]"; exit 2; }
	$(RUN) $(ANALYSIS) $(CASE) --workers $(JOBS) $(if $(DASK),--dask $(DASK)) $(ARGS)

sweep: setup
	@test -n "$(SWEEP)" || { echo "usage: make sweep SWEEP=cases/sweeps/x.toml [DASK=tcp://host:8786|local]"; exit 2; }
	$(RUN) sweep "$(SWEEP)" --workers $(JOBS) $(if $(DASK),--dask "$(DASK)")

.PHONY: modal
modal: setup
	@test -n "$(CASE)" || { echo "usage: make modal CASE=cases/x.toml [ARGS='--identify --modes 8']"; exit 2; }
	$(RUN) modal "$(CASE)" --workers $(JOBS) $(ARGS)

tilt: setup
	$(PY) -m drystone.studies.tilt --run seeds extruded --workers $(JOBS) $(if $(DASK),--dask $(DASK))

tilt-rate: setup
	$(PY) -m drystone.studies.tilt --run rate --workers $(JOBS) $(if $(DASK),--dask $(DASK))

tilt-sensitivity: setup
	$(PY) -m drystone.studies.tilt --run sensitivity --workers $(JOBS) $(if $(DASK),--dask $(DASK))

sacsayhuaman: setup
	$(PY) -m drystone.studies.sacsayhuaman all --workers $(JOBS) $(if $(DASK),--dask $(DASK))

sacsayhuaman-report: setup
	$(PY) -m drystone.studies.sacsayhuaman report

tilt-report: setup
	$(PY) -m drystone.studies.tilt

report: setup
	@test -n "$(DIR)" || { echo "usage: make report DIR=results/<run folder>"; exit 2; }
	$(RUN) report "$(DIR)"

vtk: setup
	@test -n "$(DIR)" || { echo "usage: make vtk DIR=results/<run folder> [EVERY=5]"; exit 2; }
	$(PY) -m drystone.postprocess.vtk "$(DIR)" --every "$(or $(EVERY),1)"

fragility: setup
	$(PY) -m drystone.studies.fragility all --config full --workers $(JOBS) $(if $(DASK),--dask $(DASK))

fragility-small: setup
	$(PY) -m drystone.studies.fragility all --config small --workers $(JOBS)

fragility-report: setup
	$(PY) -m drystone.studies.fragility report --config full

shape-study: setup
	$(PY) -m drystone.studies.shape all --config full --workers $(JOBS) $(if $(DASK),--dask $(DASK))

shape-study-small: setup
	$(PY) -m drystone.studies.shape all --config small --workers $(JOBS)

shape-study-report: setup
	$(PY) -m drystone.studies.shape report --config full

site-study: setup
	$(PY) -m drystone.studies.site all --config full --workers $(JOBS) $(if $(DASK),--dask $(DASK))

site-study-small: setup
	$(PY) -m drystone.studies.site all --config small --workers $(JOBS)

site-study-report: setup
	$(PY) -m drystone.studies.site report --config full

crosscheck: setup
	$(PY) -m drystone.studies.crosscheck $(or $(XC),small)

clean:
	@if [ -x $(PY) ]; then $(PY) -m drystone.clean; else /usr/bin/python3 -m drystone.clean; fi
