"""Probe waveforms → a fixed, named feature vector for misalignment diagnosis (issue 5).

Public API
----------
ProbeChannel(bearing, angle_deg, units, data)
    One proximity probe (bearing 1–8 along the train, mounting angle from horizontal +x toward +y, units
    "um" / "mm" / "m" / "mil").
Recording(sample_rate_hz, channels, speed_rpm=None, keyphasor_times_s=None, clearance_um=None, speed_range_rpm=None,
          dc_removed=False, acquisitions=None)
    An x/y probe pair per bearing present, sampled together; validated on construction.
    ``speed_range_rpm=(min, max)``: the operator's knowledge of the speed (nominal speed),
    restricting the estimate when neither speed nor keyphasor is given. ``acquisitions="1,2;3,4"``:
    the bearings were recorded in separate takes; the phase differences between takes are then not measured
    (``split_pairs(acquisitions, pairs)`` names those pairs, ``format_acquisitions`` writes the groups back) —
    unless ``keyphasor_times_s`` gives one pulse train per take (``parse_keyphasor_takes`` reads
    ``"t0,t1;t0,t1"``): every take is then referenced to the same mark (``features._takes``).
extract_features(recording, *, speed_estimate_rpm=None, speed_notes=()) -> FeatureResult
    Running speed, order analysis (1X–3X amplitude/phase, ratios, forward/reverse),
    cross-coupling phase differences, orbit shape, sub-harmonic and non-synchronous
    energy, Poincaré dispersion and motion type. ``fr.names`` / ``fr.values`` /
    ``fr.as_dict()`` give the vector; ``fr.bearings`` the per-bearing details.
speed_alternatives_rpm(recording, estimate_rpm) -> list of float
    The other running speeds the spectrum allows besides an estimate (2X / 1/2X readings, the largest
    peaks): for a caller that can judge them (``models.checks.speed_choice``), re-extracted with
    ``extract_features(recording, speed_estimate_rpm=...)``.
check_recording(recording, feature_result) -> tuple of SanityFinding
    Physics sanity checks (flat / clipped / all-zero channels, orbit vs clearance and probe
    range, implausible DC gap, all-reverse whirl, no 1X above noise, a 1X / 2X common to every
    probe); ``extract_features`` runs them and puts the findings in ``FeatureResult.sanity``.
with_sanity(recording, feature_result) -> FeatureResult
    The features with those findings: what ``extract_features`` does after extracting, for a caller that
    extracts with ``sanity=False`` and runs the checks as a stage of its own (``models.pipeline``).
common_mode(feature_result, order) -> CommonMode or None
    The signal common to every probe at 1X / 2X and its share of the order's power (electrical
    pickup at a grid-synchronous machine's 1X / 2X reads the same at every probe; no orbit does);
    ``without_common_mode(recording, feature_result, found)`` removes it, to read the recording again.
with_scale(feature_result, length_factor=1, clearance_factor=1) -> FeatureResult
    The features as extracted with the numbers and the stated clearances scaled (a row transform; exact).
slow_roll_vectors(slow_roll_recording) -> SlowRollVectors
    Per-probe 1X/2X runout vectors of a slow-roll recording (keyphasor-referenced; an order in
    the noise is absent).
apply_slow_roll(recording, slow_roll) -> (Recording, SlowRollVectors)
    The running recording with those vectors set for subtraction (``ProbeChannel.slow_roll_um_pp``);
    refuses without a keyphasor in both, with different probes, or a slow roll above
    ``SLOW_ROLL_MAX_SPEED_FRACTION`` of the running speed.
evidence(feature_result) -> list of EvidenceItem
    The model-independent evidence: 1X/2X vectors, 2X/1X, phase across the coupling, orbit
    shape, shaft centreline, each with what it usually means.
signature(feature_result) -> dict; change_features(base_signature, signature) -> ChangeResult
    Change against an asset's baseline (issue 17): 1X/2X vector changes per probe, centreline
    displacement, orbit-shape change, compared within ``SPEED_BAND_FRAC`` of the baseline's speed.
FEATURE_NAMES, FEATURE_SPECS, feature_names()
    The fixed schema (always bearings 1–4; absent bearings give NaN), with units and
    definitions (docs/features.md).

Every amplitude is in µm whatever the input units; ``*_per_c`` twins divide by the radial
clearance (NaN when it is unknown).

Importing the package raises glibc's malloc mmap/trim thresholds (see ``features._alloc``;
``ROTORDIAG_MALLOC_TUNING=0`` disables it) and each extraction runs with one BLAS thread
(``features._config.BLAS_THREADS``): both measured to matter more than the arithmetic.
"""
from rotordiag.core.notes import Note, speed_in_doubt

from ._acquisitions import format_acquisitions, parse_acquisitions, parse_keyphasor_takes, split_pairs
from ._across import ACROSS_FEATURES, across_bearings
from ._alloc import tune_malloc
from ._change import (
    CHANGE_QUANTITIES,
    SPEED_BAND_FRAC,
    ChangeResult,
    average_signatures,
    change_array,
    change_features,
    signature,
    speed_comparable,
)
from ._common_mode import (
    COMMON_MODE_NOTABLE_SHARE,
    CommonMode,
    common_mode,
    common_mode_share,
    without_common_mode,
)
from ._config import (
    ALLOWED_UNITS,
    MIN_REVS,
    MIN_REVS_MOTION,
    WHIRL_BAND,
)
from ._evidence import EvidenceItem, evidence
from ._extract import BearingDetail, FeatureResult
from ._extraction import extract_features, with_sanity, with_speed_notes
from ._lines import LINE_CLASSES, running_speed_line
from ._names import FEATURE_NAMES, FEATURE_SPECS, FeatureSpec, feature_names
from ._orbit import OrbitShape
from ._recording import ProbeChannel, Recording, parse_speed_range
from ._sanity import REVERSE_WHIRL_INDEX, SanityFinding, check_recording
from ._scale import with_scale
from ._slow_roll import SLOW_ROLL_MAX_SPEED_FRACTION, SlowRollVectors, apply_slow_roll, slow_roll_vectors
from ._speed_alternatives import speed_alternatives_rpm

tune_malloc()

__all__ = [
    "ProbeChannel", "Recording", "parse_speed_range", "extract_features", "with_sanity", "with_speed_notes", "FeatureResult", "BearingDetail", "OrbitShape",
    "FEATURE_NAMES", "FEATURE_SPECS", "FeatureSpec", "feature_names", "ACROSS_FEATURES", "across_bearings",
    "ALLOWED_UNITS", "MIN_REVS",
    "MIN_REVS_MOTION", "WHIRL_BAND", "REVERSE_WHIRL_INDEX", "SanityFinding", "check_recording", "EvidenceItem", "evidence",
    "signature", "average_signatures", "change_features", "change_array", "speed_comparable", "ChangeResult", "SPEED_BAND_FRAC",
    "CHANGE_QUANTITIES", "SlowRollVectors", "slow_roll_vectors", "apply_slow_roll", "SLOW_ROLL_MAX_SPEED_FRACTION",
    "Note", "speed_in_doubt", "speed_alternatives_rpm",
    "CommonMode", "common_mode", "common_mode_share", "without_common_mode", "with_scale", "COMMON_MODE_NOTABLE_SHARE",
    "parse_acquisitions", "parse_keyphasor_takes", "format_acquisitions", "split_pairs",
    "running_speed_line", "LINE_CLASSES",
]
