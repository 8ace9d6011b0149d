"""Tunables of the feature extractor, in one place (documented in docs/features.md)."""
from __future__ import annotations

from rotordiag.core.conventions import BEARINGS, MAX_BEARING
from rotordiag.core.units import ALLOWED_UNITS, UNITS_TO_UM

__all__ = ["ALLOWED_UNITS", "UNITS_TO_UM", "BEARINGS", "MAX_BEARING", "PROBE_BEARINGS"]  # re-exported for the package's modules

# BEARINGS (rotordiag.core.conventions): the feature vector always covers all four.
#: bearing numbers a probe channel may carry (1 … MAX_BEARING: a train's bearings along it)
PROBE_BEARINGS: tuple[int, ...] = tuple(range(1, MAX_BEARING + 1))
#: bearing pairs whose 1X / 2X phase differences are features: across the coupling, then
#: along the generator and along the exciter
PHASE_PAIRS: tuple[tuple[int, int], ...] = ((2, 3), (1, 2), (3, 4))
#: bearing pairs whose static positions and 1X / 2X orbit sizes are compared (``centre_ecc_*_ratio``, ``dcentre_*``,
#: ``*x_major_*_ratio``): across the coupling, then each coupling-end bearing against its rotor's outboard bearing.
#: An offset coupling moves load between a rotor's bearings; a ratio divides out the oil film's factors common
#: to the pair (speed, viscosity, the plant's size), which a tree reads only piecewise from the per-bearing columns.
ACROSS_PAIRS: tuple[tuple[int, int], ...] = ((2, 3), (2, 1), (3, 4))
#: floors of the ratios' denominators (a journal at the bearing's centre, an orbit in the noise): per clearance
#: for the eccentricity, µm pk-pk for the orbit majors
ACROSS_ECC_FLOOR = 1e-3
ACROSS_MAJOR_FLOOR_UM = 1e-3

#: minimum whole revolutions analysed. With 8 revolutions the 1X..3X least-squares fit is
#: well conditioned and a 2X line 40 dB below 1X is still resolved from 1X leakage-free;
#: below that the orders and especially the sub-harmonic bands are not reliable.
MIN_REVS = 8
#: minimum samples per revolution: 3X must lie below 0.75 × Nyquist (anti-alias filters
#: of acquisition systems roll off above ~0.8 × Nyquist).
MIN_SAMPLES_PER_REV = 8.0
#: highest order fitted and removed before the non-synchronous analysis (limited further to
#: below 0.9 × Nyquist)
MAX_SYNC_ORDER = 10
#: orders reported as features
REPORTED_ORDERS: tuple[int, ...] = (1, 2, 3)

#: sub-synchronous band (orders of running speed), lower edge above slow drift
SUBSYNC_BAND: tuple[float, float] = (0.05, 0.95)
#: oil-whirl band (orders)
WHIRL_BAND: tuple[float, float] = (0.38, 0.49)
#: call-out lines (orders) and the half-width of their bands: max(order width, 2 FFT bins)
CALLOUT_ORDERS: dict[str, float] = {"half_x": 0.5, "third_x": 1.0 / 3.0}
CALLOUT_HALF_WIDTH_ORDERS = 0.02
CALLOUT_MIN_HALF_WIDTH_BINS = 2
#: records shorter than this many revolutions get a warning that the sub-harmonic band
#: features are coarse (FFT resolution 1/n_revs orders)
MIN_REVS_SUBHARMONIC = 32
#: a sub-synchronous peak order is reported only when its bin stands this many times
#: above the median power of the band
SUBSYNC_PEAK_MIN_RATIO = 10.0
#: … and holds at least this fraction of the orbit's AC mean-square (amplitude ≳ 0.1 % of RMS)
SUBSYNC_PEAK_MIN_FRAC = 1e-6

#: a warning that puts an estimated running speed in doubt is a ``doubt`` note of the warnings catalogue
#: (rotordiag.core.notes); ``models.status`` turns each into the ``speed_ambiguous`` reason (never a ``confident``
#: verdict), found by its code with ``rotordiag.core.notes.speed_in_doubt``, so that rewording a warning cannot
#: change a verdict


#: speed search range without keyphasor / given speed (r/min)
SPEED_SEARCH_RPM: tuple[float, float] = (60.0, 12000.0)
#: how many spectral peaks are tried as (multiples of) the running speed
SPEED_CANDIDATE_PEAKS = 24
#: a peak must stand this many times above the median spectrum to count as a line
SPEED_LINE_MIN_SNR = 10.0
#: ``speed_alternatives_rpm``: the largest peaks whose frequency (and half of it) are offered as other running
#: speeds besides the estimate, and how far apart (relative) two offered speeds must be (the 0.5 % of issue 15,
#: item 6: closer ones are the same reading)
SPEED_ALTERNATIVE_PEAKS = 8
SPEED_ALTERNATIVE_MIN_SEPARATION = 0.005
#: a harmonic counts as present when its amplitude is at least this fraction of the largest line
SPEED_HARMONIC_MIN_REL = 0.01
#: a candidate speed's m-th harmonic line may lie m times this many FFT bins from m × the candidate (its
#: interpolated peak's error grows m-fold), at most ``SPEED_HARMONIC_MAX_TOL_BINS`` (measured: docs/features.md,
#: "Measurements behind the speed estimate's thresholds")
SPEED_HARMONIC_TOL_BINS = 0.5
SPEED_HARMONIC_MAX_TOL_BINS = 1.0
#: a best-ranked line family below this fraction of a higher family's frequency may be a
#: sub-synchronous whirl / whip (features._families._above_subsynchronous) …
SPEED_SUBSYNC_MAX_RATIO = 0.55
#: … when their refined frequency ratio r is further than this fraction of r from an integer
#: (oil whirl / whip lines are not locked to the running speed)
SPEED_INTEGER_RATIO_TOL = 2e-3
#: … and whose own line's orbits are not nearly straight lines: backward / forward circular component at
#: most this (a combination line of the whirl with the running speed beats in a flat orbit; docs/features.md)
SPEED_RUNNING_MAX_BACKWARD = 0.5
#: a spectral peak that is not a harmonic of the chosen speed makes the estimate "ambiguous" when
#: its power is this many times the median spectrum (noise alone: probability 2^-30) …
SPEED_FOREIGN_MIN_SNR = 30.0
#: … and its amplitude at least this fraction of the largest line
SPEED_FOREIGN_MIN_REL = 0.002
#: a weak line above a possible whirl / whip that could be the running speed's hidden 1X
#: (features._families._weak_lines_above) needs at least this amplitude relative to the largest line
SPEED_WEAK_LINE_MIN_REL = 5e-4
#: a line of a whirl / whip's combination lattice mΩ + kω (features._families._combination_partners)
#: counts when it is a local maximum this many times above the median spectrum (8 channels of
#: noise: probability < 1e-6 per bin; 2 channels: ~1e-3, and a candidate needs two such lines) …
SPEED_PARTNER_LINE_SNR = 4.0
#: … within this many FFT bins of where the lattice puts it
SPEED_PARTNER_TOL_BINS = 0.5
#: … and is not "ambiguous" only when its own 1X line stands this many times above the median spectrum
SPEED_PARTNER_CLEAR_SNR = 100.0
#: the speed from a whirl's combination lines is "ambiguous" when the runner-up candidate scores
#: at least this fraction of the best
SPEED_PARTNER_RIVAL_REL = 0.8
#: … and a candidate running speed must explain at least this many combination lines (Ω ± kω,
#: 2Ω − kω, k ≠ 0): with one, the true 1X read as a whirl finds a spurious partner (docs/features.md)
SPEED_PARTNER_MIN_COMBINATIONS = 2
#: a line family is read as a whirl / whip whose running speed is sought among its combination lines
#: only when its orbits are at most this elliptical (backward / forward): a flatter line is the running
#: speed's own 1X, not a whirl (docs/features.md)
SPEED_PARTNER_MAX_BACKWARD = 0.2
#: the estimate is "ambiguous" when its 1X is the largest line and the orbits there are nearly
#: circular: the median over bearings of backward / forward circular component (or its inverse)
#: below this (a whip's orbits are near circles, a 1X's flatter; docs/features.md)
SPEED_WHIRL_MAX_BACKWARD = 0.1
#: a line family with a family at twice its frequency (as many harmonics present) is taken for a
#: half-speed whirl / sub-harmonic, and the double family for the running speed, when its orbits are
#: this circular (backward / forward; docs/features.md)
SPEED_HALF_WHIRL_MAX_BACKWARD = 0.15
#: ... and regardless of its orbits when its line is below this fraction of the double family's
#: (amplitude: a flexible coupling's 2X can be many times its 1X; docs/features.md)
SPEED_HALF_MAX_REL = 0.03
#: the comb of a line family reads as period-3 motion (features._families._period_n) only when its 3X
#: holds at least … at most this fraction of its 1X (amplitude: a machine's own 3X is larger; docs/features.md)
SPEED_PERIOD3_MIN_REL = 0.1
SPEED_PERIOD3_MAX_REL = 0.5
#: … tried for period-n motion up to this n (features._families._period_n)
SPEED_PERIOD_MAX_N = 8
#: a running speed's harmonics fall off, a 1/nX sub-harmonic's comb (its k/nX lines) stays flat: the estimate is
#: flagged (features._speed._flat_comb_warning) when its 2X … this order are all lines of their own, each at least
#: SPEED_FLAT_COMB_MIN_REL of its 1X (amplitude, −30 dB: between the wrong estimates' combs and the right ones';
#: docs/features.md, "Measurements behind the speed estimate's thresholds")
SPEED_FLAT_COMB_ORDER = 6
SPEED_FLAT_COMB_MIN_REL = 10 ** (-30 / 20)
#: the running speed's 1X hidden in the main lobe of an oil whirl's 2nd harmonic (features._families._hidden_running_line)
#: is sought between these many record bins (fs / n) above that harmonic …
SPEED_HIDDEN_MIN_BINS = 0.3
SPEED_HIDDEN_MAX_BINS = 6.0
#: … and accepted when the two-line fit leaves at most this fraction of the one-line fit's residual
SPEED_HIDDEN_MAX_RESIDUAL = 0.2
#: a peak within this fraction of a stronger line's frequency, with a mirror image across it, is a
#: modulation sideband, not a line of its own (features._lines._modulation_sidebands) …
SPEED_SIDEBAND_MAX_REL = 0.03
#: … and at least this many FFT bins from it (closer, a pair is not resolved from the line's main lobe) …
SPEED_SIDEBAND_MIN_BINS = 3
#: … when that line's power is at least this many times each of the pair's …
SPEED_SIDEBAND_MIN_DROP = 2.0
#: … and the pair's powers lie within this factor of each other
SPEED_SIDEBAND_MIRROR = 4.0
#: … following the comb of pairs out to this many times the first pair's spacing
SPEED_SIDEBAND_MAX_ORDER = 4
#: … tried for this many of the strongest lines, each with this many of its nearest peaks as the first pair
SPEED_SIDEBAND_MAX_CARRIERS = 64
SPEED_SIDEBAND_MAX_TRIES = 8
#: phase-difference refinement iterations of the estimated / given speed
SPEED_REFINE_ITERATIONS = 3
#: a given ``speed_rpm`` that differs from the signal's refined 1X line by more than this
#: fraction gets a warning (and one locked to the signal's lines, ``_speed_lock``, further than this is said so)
SPEED_MISMATCH_WARN = 1e-3
#: … when the other synchronous lines confirm the reading within this fraction of it (``_extract._given_speed_mismatch``)
SPEED_CHECK_LOCK_REL = 0.002
#: a given ``speed_rpm`` is locked to the signal's synchronous lines within this fraction of it
#: (``_speed_lock.locked_speed_hz``: grid frequency, rounding and drift put a stated speed 0.1–0.5 % off)
SPEED_LOCK_MAX_REL = 0.01
#: … on the largest of these orders' lines near their stated frequency …
SPEED_LOCK_ORDERS: tuple[int, ...] = (1, 2, 3)
#: … when the other orders' lines read the same speed within this fraction (else the stated speed is kept)
SPEED_LOCK_AGREE_REL = 5e-4
#: … and at least this many orders show such a line (one line alone may be a whirl harmonic next to 1X)
SPEED_LOCK_MIN_LINES = 2
#: … and it replaces the stated speed only when they differ by more than this: the refinement's own bias on a
#: stated speed that is right (up to 2.4e-5 on 11-revolution records of 1X–3X lines, where the harmonics leak into
#: each other's half-record windows); 5e-5 drifts by 0.01 revolution over 200
SPEED_LOCK_MIN_REL = 5e-5
#: keyphasor revolutions whose period differs from the mean by more than this get a warning
SPEED_VARIATION_WARN = 0.01

#: the phase of an order (and the phase differences built on it) is reported only when that
#: order's zero-to-peak amplitude is at least this multiple of the noise-equivalent amplitude
#: of the least-squares fit at that order (from the residual spectrum within
#: ``PHASE_NOISE_BAND_ORDERS`` of the order). At 3× the phase's standard error is about 13.5°;
#: below it the phase is mostly noise and is reported as missing (NaN), not as a number.
PHASE_MIN_SNR = 3.0
#: half-width (orders) of the residual-spectrum band around kX that gives the local noise floor
PHASE_NOISE_BAND_ORDERS = 0.25
#: … and an absolute floor: an order whose amplitude is below this fraction of the largest
#: synchronous line of all channels is numerical noise however clean the record (e.g. a
#: noise-free simulation's 2X of 1e-12 µm)
PHASE_MIN_REL_AMPLITUDE = 1e-6

#: grid points per revolution for orbit-shape features
ORBIT_GRID = 360

#: minimum revolutions for the motion type (periods up to MIN_REVS_MOTION // 3 testable)
MIN_REVS_MOTION = 32
#: probability that Gaussian measurement noise alone breaks a truly periodic Poincaré set
#: (sets the period tolerance, see features._poincare.period_tolerance)
POINCARE_FALSE_ALARM = 1e-3

#: BLAS threads during one extraction (its matrix products are 20 × 16 k: threads only add
#: overhead and contend with the caller's own parallelism — 3–4× slower on a busy 2-core
#: machine); None leaves the BLAS setting alone
BLAS_THREADS: int | None = 1

#: a shaft-centreline position (evidence, ``b?_centre_*_per_c`` features) is used only when the mean
#: reading lies within this many clearances of the probes' zero (else the DC part is a raw gap)
CENTRELINE_MAX_ECC = 1.5
#: every channel's mean within this fraction of the largest channel peak-to-peak: the means were removed before the
#: file was written (AC-coupled export, or a V recording read without its gap voltage) — the DC part is no position
DC_REMOVED_MAX_REL = 1e-5
