"""Slow-roll (runout) compensation from a slow-roll recording (issue 15, item 3).

At slow roll (typically 100–300 r/min on a 3000/3600 r/min machine) the shaft hardly vibrates:
the 1X and 2X a proximity probe reads there are mechanical and electrical runout of the shaft
surface under the probe (scratches, out-of-roundness, conductivity and permeability variations)
plus any bow. That runout is fixed to the shaft surface, so at running speed it is still there at
the same shaft angle; subtracting it as a vector, per probe and per order, leaves the vibration.

Two things make the subtraction meaningful, and both are checked here:

- **A common phase reference.** The phase of an order is only fixed to the shaft when it is
  measured from a once-per-revolution mark on the shaft (the keyphasor). Without a keyphasor in
  *both* recordings the two phases have arbitrary origins and a vector subtraction adds runout
  as often as it removes it, so it is refused.
- **Slow enough.** The synchronous response to unbalance (force ``m·e·ω²``) of a rotor below its
  first critical grows as ``ω²``, so at ``SLOW_ROLL_MAX_SPEED_FRACTION`` (20 %) of the running
  speed it is at most 0.2² = 4 % of the running-speed response of the same rotor; for a rotor
  running above its first critical the slow roll must also be below about 20 % of that critical
  (then the single-mode response ``r²/(1 − r²)`` of the unbalance eccentricity is ≤ 4.4 %),
  which this module cannot check without the critical speed — docs/recordings.md says so.

An order whose slow-roll amplitude does not stand ``PHASE_MIN_SNR`` times above the local noise
floor of the slow-roll recording (the same gate as every phase feature) has no vector: it is
left out (not subtracted), and the evidence says so — subtracting noise would add noise.

The subtraction itself is :class:`features.ProbeChannel`'s ``slow_roll_um_pp`` path
(``features._extract._subtract_slow_roll``): this module only measures the vectors and sets them.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from . import _config as cfg
from ._extraction import extract_features
from ._recording import Recording
from ._sanity import FAIL

__all__ = ["SlowRollVectors", "slow_roll_vectors", "apply_slow_roll", "SLOW_ROLL_MAX_SPEED_FRACTION",
           "SLOW_ROLL_ANGLE_TOL_DEG"]

#: the slow-roll speed may be at most this fraction of the running speed (module docstring: the
#: unbalance response there is ≤ 0.2² = 4 % of the running one for a rotor below its first critical)
SLOW_ROLL_MAX_SPEED_FRACTION = 0.2
#: two probes are the same probe when their bearing is the same and their angles agree to this (deg)
SLOW_ROLL_ANGLE_TOL_DEG = 0.5
#: sanity findings of the slow-roll recording that do not make its runout unusable: a slow roll has
#: (by design) little or no vibration, and runout has no whirl direction
_IRRELEVANT_AT_SLOW_ROLL = frozenset({"no_sync_signal", "reverse_whirl_all", "reverse_whirl"})

_NO_KEYPHASOR = ("slow-roll compensation needs a once-per-revolution reference (keyphasor) in both "
                 "recordings: runout is fixed to the shaft surface, and only keyphasor-referenced phases "
                 "are comparable between the slow-roll and the running recording (without it the "
                 "subtraction adds runout as often as it removes it). Give the {which} recording's "
                 "keyphasor_times_s (or a keyphasor column/channel), or give slow-roll 1X/2X vectors "
                 "measured by your own monitoring system (slow_roll_um_pp per probe, API channels[].slow_roll) "
                 "instead of a slow-roll recording")


@dataclass(frozen=True)
class SlowRollVectors:
    """Runout vectors measured from a slow-roll recording.

    Attributes
    ----------
    speed_rpm : float
        Slow-roll speed (from its keyphasor).
    n_revs : int
        Whole revolutions analysed.
    vectors_um_pp : dict {(bearing, angle_deg): {order: (amplitude µm pk-pk, phase lag deg)}}
        Per probe, the orders 1 and 2 that stand above the noise (an order in the noise is absent,
        not a number). Phase lag from the keyphasor, same convention as ``ProbeChannel.slow_roll_um_pp``.
    noise_um_pp : dict {(bearing, angle_deg): {order: float}}
        Noise-equivalent amplitude of each probe's order fit (µm pk-pk; NaN when not estimable).
    notes : tuple of str
        What was left out and why.
    """

    speed_rpm: float
    n_revs: int
    vectors_um_pp: dict[tuple[int, float], dict[int, tuple[float, float]]]
    noise_um_pp: dict[tuple[int, float], dict[int, float]] = field(default_factory=dict)
    notes: tuple[str, ...] = ()


def _probe_name(bearing: int, angle_deg: float) -> str:
    return f"b{bearing}@{angle_deg:g}"


def _speed_from_keyphasor_rpm(kp: np.ndarray) -> float:
    return 60.0 * (kp.size - 1) / float(kp[-1] - kp[0])


def slow_roll_vectors(slow_roll: Recording) -> SlowRollVectors:
    """The 1X and 2X runout vectors of each probe of a slow-roll recording.

    Parameters
    ----------
    slow_roll : Recording
        Taken at slow-roll speed with a keyphasor (``keyphasor_times_s``), read like any recording
        (``features.reader``).

    Returns
    -------
    SlowRollVectors

    Raises
    ------
    ValueError
        No keyphasor; a channel unusable as given (flat, zero, clipped, out of the probe range: the
        sanity checks' failures); the extractor's own refusals (too few revolutions, ...).
    """
    if not isinstance(slow_roll, Recording):
        raise ValueError(f"slow_roll_vectors expects a features.Recording, got {type(slow_roll).__name__}")
    if slow_roll.keyphasor_times_s is None:
        raise ValueError(_NO_KEYPHASOR.format(which="slow-roll"))
    if any(c.slow_roll_um_pp for c in slow_roll.channels):
        raise ValueError("the slow-roll recording itself carries slow-roll vectors; give a plain recording")
    try:
        fr = extract_features(slow_roll)
    except ValueError as exc:
        raise ValueError(f"slow-roll recording: {exc}") from None
    bad = [f for f in fr.sanity if f.level == FAIL and f.code not in _IRRELEVANT_AT_SLOW_ROLL]
    if bad:
        raise ValueError("slow-roll recording: " + "; ".join(f.message for f in bad))
    if fr.phase_reference != "keyphasor":       # a faulty pulse train (features._keyphasor): no reference
        raise ValueError(f"slow-roll recording: {fr.warnings[0]}. Its vectors need the keyphasor's phase reference: "
                         "fix the keyphasor signal and record the slow roll again")
    rel_floor = cfg.PHASE_MIN_REL_AMPLITUDE * max(
        float(np.max(np.abs(np.concatenate([d.x_coeffs_um, d.y_coeffs_um])))) for d in fr.bearings.values())
    vectors: dict[tuple[int, float], dict[int, tuple[float, float]]] = {}
    noise: dict[tuple[int, float], dict[int, float]] = {}
    notes: list[str] = []
    for b, det in sorted(fr.bearings.items()):
        for j, angle in enumerate(det.probe_angles_deg):
            key = (b, float(angle))
            vectors[key], noise[key] = {}, {}
            th = np.deg2rad(angle)
            for k in (1, 2):
                c = complex(det.probe_coeffs_um[j, k - 1])
                # noise of p = x cos θ + y sin θ from that of x and y (exact for an orthogonal pair
                # with equal, independent probe noise: x and y are then a rotation of the probes)
                lx, ly = (np.nan, np.nan) if det.line_noise_um is None else det.line_noise_um[:, k - 1]
                n0p = float(np.hypot(np.cos(th) * lx, np.sin(th) * ly))
                noise[key][k] = 2.0 * n0p
                amp = abs(c)
                if not (amp > rel_floor) or amp < cfg.PHASE_MIN_SNR * n0p:
                    notes.append(f"slow roll {_probe_name(*key)}: {k}X runout {2 * amp:.3g} µm pk-pk is in the "
                                 f"noise ({2 * n0p:.3g} µm pk-pk noise-equivalent; needs {cfg.PHASE_MIN_SNR:g}×): "
                                 "not subtracted")
                    continue
                vectors[key][k] = (2.0 * amp, float(np.degrees(-np.angle(c)) % 360.0))
    return SlowRollVectors(speed_rpm=float(fr.speed_rpm), n_revs=int(fr.n_revs), vectors_um_pp=vectors,
                           noise_um_pp=noise, notes=tuple(notes))


def _match(recording: Recording, vectors: SlowRollVectors) -> dict[int, tuple[int, float]]:
    """Channel index of ``recording`` → the key of the same probe in ``vectors`` (ValueError if the sets differ)."""
    keys = list(vectors.vectors_um_pp)
    out: dict[int, tuple[int, float]] = {}
    used: set[tuple[int, float]] = set()
    for i, ch in enumerate(recording.channels):
        same = [k for k in keys if k[0] == ch.bearing
                and abs((k[1] - ch.angle_deg + 180.0) % 360.0 - 180.0) <= SLOW_ROLL_ANGLE_TOL_DEG]
        if same:
            out[i] = same[0]
            used.add(same[0])
    missing = [_probe_name(ch.bearing, ch.angle_deg) for i, ch in enumerate(recording.channels) if i not in out]
    extra = [_probe_name(*k) for k in keys if k not in used]
    if missing or extra:
        parts = []
        if missing:
            parts.append(f"probe(s) {', '.join(missing)} of the running recording are not in the slow-roll recording")
        if extra:
            parts.append(f"probe(s) {', '.join(extra)} of the slow-roll recording are not in the running recording")
        raise ValueError("slow-roll compensation needs the same probes (bearing and angle, within "
                         f"{SLOW_ROLL_ANGLE_TOL_DEG:g}°) in both recordings: " + "; ".join(parts)
                         + " — record the slow roll with the same probes and give both files the same channel layout")
    return out


def apply_slow_roll(recording: Recording, slow_roll: Recording | SlowRollVectors) -> tuple[Recording, SlowRollVectors]:
    """The running ``recording`` with each probe's runout vectors set for subtraction.

    The vectors go into ``ProbeChannel.slow_roll_um_pp`` (an empty mapping for a probe whose runout
    is in the noise at both orders), so :func:`features.extract_features` subtracts them from the
    fitted 1X and 2X and :func:`features.evidence` reports what was subtracted.

    Parameters
    ----------
    recording : Recording
        The running recording; needs a keyphasor (``keyphasor_times_s``).
    slow_roll : Recording or SlowRollVectors
        The slow-roll recording (measured with :func:`slow_roll_vectors`) or its vectors.

    Returns
    -------
    (Recording, SlowRollVectors)
        The compensated recording and the vectors used.

    Raises
    ------
    ValueError
        Saying what to fix: no keyphasor in either recording; the probes of the two recordings
        differ; the slow roll faster than ``SLOW_ROLL_MAX_SPEED_FRACTION`` of the running speed;
        slow-roll vectors already given per probe.
    """
    if not isinstance(recording, Recording):
        raise ValueError(f"apply_slow_roll expects a features.Recording, got {type(recording).__name__}")
    if recording.keyphasor_times_s is None:
        raise ValueError(_NO_KEYPHASOR.format(which="running"))
    if isinstance(recording.keyphasor_times_s, tuple):
        raise ValueError("a slow-roll recording with one keyphasor per acquisition is not supported; send each "
                         "acquisition as its own recording with the slow-roll recording")
    if any(c.slow_roll_um_pp is not None for c in recording.channels):
        raise ValueError("the running recording already carries slow-roll vectors per probe; give either those "
                         "or a slow-roll recording, not both")
    vectors = slow_roll if isinstance(slow_roll, SlowRollVectors) else slow_roll_vectors(slow_roll)
    mapping = _match(recording, vectors)
    running_rpm = _speed_from_keyphasor_rpm(recording.keyphasor_times_s)
    limit = SLOW_ROLL_MAX_SPEED_FRACTION * running_rpm
    if not vectors.speed_rpm <= limit:
        raise ValueError(f"the slow-roll recording turns at {vectors.speed_rpm:.1f} r/min, "
                         f"{100 * vectors.speed_rpm / running_rpm:.0f} % of the running speed {running_rpm:.1f} r/min; "
                         f"slow roll must be at most {100 * SLOW_ROLL_MAX_SPEED_FRACTION:.0f} % of it "
                         f"(≤ {limit:.0f} r/min here) and well below the first critical speed, where the shaft's own "
                         "vibration is negligible and the probes read runout only — record the slow roll at a lower "
                         "speed (turning gear or coast-down), or give the running recording instead of the slow-roll one "
                         "if they were swapped")
    chans = [replace(ch, slow_roll_um_pp=dict(vectors.vectors_um_pp[mapping[i]]))
             for i, ch in enumerate(recording.channels)]
    return replace(recording, channels=chans), vectors
