"""``extract_features``: the features package's one entry point, one recording → its features and sanity findings.

A recording whose probes were recorded in several takes, each with its own keyphasor, is read take by take
(``features._takes``); any other in one pass (``features._extract``). The physics checks
(``features._sanity``) then read the recording with its features.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from . import _config as cfg
from ._extract import FeatureResult, _blas_limit, _extract
from ._recording import Recording
from ._sanity import check_recording
from ._takes import extract_by_take

__all__ = ["extract_features"]


def extract_features(recording: Recording, *, speed_estimate_rpm: float | None = None,
                     speed_notes: Sequence[str] = ()) -> FeatureResult:
    """Features of one recording: order analysis, orbit shape, sub-harmonics, motion type.

    Parameters
    ----------
    recording : Recording
        x/y probe pairs of one or more bearings, sample rate, units, optional speed,
        keyphasor and clearance.
    speed_estimate_rpm : float, optional
        For a recording without keyphasor or ``speed_rpm``: a running speed estimated elsewhere, used
        instead of this package's estimate (``speed_source`` stays ``"estimated"``) — a caller that chose
        among :func:`speed_alternatives_rpm` (``models.speed_choice``). Ignored otherwise.
    speed_notes : sequence of str
        The warnings that go with ``speed_estimate_rpm`` (in place of the estimator's). A speed from
        elsewhere is never the signal's own reading: when no note puts it in doubt
        (:func:`speed_in_doubt`), one that does is added, so a verdict at it is never ``confident``.

    Returns
    -------
    FeatureResult

    Raises
    ------
    ValueError
        With a message saying what to fix: fewer than ``MIN_REVS`` (8) revolutions, fewer than
        8 samples per revolution (3X too close to Nyquist), an unestimable speed, keyphasor
        pulses off the record. (Bad channels are refused when the ``Recording`` is built.)
    """
    if not isinstance(recording, Recording):
        raise ValueError(f"extract_features expects a features.Recording, got {type(recording).__name__}")
    estimate = None
    if speed_estimate_rpm is not None:
        if not (np.isfinite(speed_estimate_rpm) and speed_estimate_rpm > 0):
            raise ValueError(f"speed_estimate_rpm: must be a positive number of r/min, got {speed_estimate_rpm!r}")
        notes = list(speed_notes)
        if not any(cfg.speed_in_doubt(w) for w in notes):
            notes.append(f"{cfg.SPEED_AMBIGUOUS}: {float(speed_estimate_rpm):.1f} r/min was estimated outside this "
                         "package's reading of the spectrum (speed_estimate_rpm); confirm it with speed_rpm or "
                         "keyphasor_times_s")
        estimate = (float(speed_estimate_rpm), notes)
    with _blas_limit:
        if recording.keyphasor_takes is not None:
            result = extract_by_take(recording, _extract)
        else:
            result = _extract(recording, estimate)
        return replace(result, sanity=check_recording(recording, result))
