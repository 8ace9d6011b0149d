"""The other running speeds a record's spectrum allows besides the estimate (issue 15, item 6).

A spectral estimate of the running speed can be wrong in whirl, whip and period-n motion: it reads a
whirl partner, a 2X or a sub-harmonic as the 1X and says so (``SPEED_AMBIGUOUS``). No rule on the
spectrum alone tells these readings apart (docs/features.md, "Estimated speed"); a caller that knows
the machine family can (``models.checks.speed_choice``: the reading at which the recording looks like the
machines its model was trained on). This module lists the readings to try.
"""
from __future__ import annotations

from . import _config as cfg
from ._lines import refine_line_hz
from ._recording import Recording
from ._speed import _spectrum


def speed_alternatives_rpm(recording: Recording, estimate_rpm: float) -> list[float]:
    """Running speeds other than ``estimate_rpm`` that the recording's spectrum allows, r/min.

    Parameters
    ----------
    recording : Recording
        Without keyphasor or ``speed_rpm`` (with either, the speed is known and the list is empty).
    estimate_rpm : float
        The estimate (``extract_features(recording).speed_rpm``).

    Returns
    -------
    list of float
        Twice and half the estimate (a 2X or a 1/2X read as the 1X), then each of the
        ``SPEED_ALTERNATIVE_PEAKS`` largest spectral peaks (refined by :func:`refine_line_hz`; the
        1X of a running speed that was passed over for a whirl's or a sub-harmonic's line) and half its
        frequency (a 2X whose 1X is weak); inside the estimator's search range and the recording's
        ``speed_range_rpm``, each more than ``SPEED_ALTERNATIVE_MIN_SEPARATION`` (relative) from the
        estimate and from the ones before it. Whether a speed leaves the record enough revolutions and
        samples per revolution is left to :func:`extract_features` (a caller skips the ones it refuses).
    """
    if recording.keyphasor_times_s is not None or recording.speed_rpm is not None:
        return []
    fs = recording.sample_rate_hz
    rng = recording.speed_range_rpm
    s = _spectrum(recording.xy_all_um(), fs, None if rng is None else (rng[0] / 60.0, rng[1] / 60.0))
    f_est = float(estimate_rpm) / 60.0
    tried = [2.0 * f_est, 0.5 * f_est]
    for k in s.peak_idx[:cfg.SPEED_ALTERNATIVE_PEAKS]:
        f_peak = refine_line_hz(s.x, fs, k * s.df)
        if abs(f_peak - k * s.df) > 2 * s.df:       # refinement wandered off (a line on another's skirt)
            f_peak = k * s.df
        tried += [f_peak, 0.5 * f_peak]
    kept = [f_est]
    for f in tried:
        if s.c_lo <= f <= s.c_hi and all(abs(f / g - 1.0) > cfg.SPEED_ALTERNATIVE_MIN_SEPARATION for g in kept):
            kept.append(f)
    return [60.0 * f for f in kept[1:]]
