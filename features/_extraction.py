"""``extract_features``: the features package's one entry point, one recording → its features and sanity findings.

A recording whose probes were recorded in several takes, each with its own keyphasor, is read take by take
(``features._takes``); any other in one pass (``features._extract``). The physics checks
(``features._sanity``) then read the recording with its features (:func:`with_sanity`); the verdict pipeline
(``models.pipeline``) runs them as a stage of its own (``sanity=False`` here, then :func:`with_sanity`).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from rotordiag.core.notes import Note, speed_in_doubt

from ._extract import FeatureResult, _blas_limit, _extract
from ._recording import Recording
from ._sanity import check_recording
from ._takes import extract_by_take

__all__ = ["extract_features", "with_sanity", "with_speed_notes"]


def extract_features(recording: Recording, *, speed_estimate_rpm: float | None = None,
                     speed_notes: Sequence[str] = (), sanity: bool = True) -> FeatureResult:
    """Features of one recording: order analysis, orbit shape, sub-harmonics, motion type.

    Parameters
    ----------
    recording : Recording
        x/y probe pairs of one or more bearings, sample rate, units, optional speed,
        keyphasor and clearance.
    speed_estimate_rpm : float, optional
        For a recording without keyphasor or ``speed_rpm``: a running speed estimated elsewhere, used
        instead of this package's estimate (``speed_source`` stays ``"estimated"``) — a caller that chose
        among :func:`speed_alternatives_rpm` (``models.checks.speed_choice``). Ignored otherwise.
    speed_notes : sequence of rotordiag.core.notes.Note
        The warnings that go with ``speed_estimate_rpm`` (in place of the estimator's). A speed from
        elsewhere is never the signal's own reading: when no note puts it in doubt
        (:func:`speed_in_doubt`), one that does is added, so a verdict at it is never ``confident``.
    sanity : bool
        Run the physics sanity checks (:func:`with_sanity`) and put their findings in ``FeatureResult.sanity``.
        False leaves ``sanity`` empty for a caller that runs them as a stage of its own (``models.pipeline``).

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
        estimate = (float(speed_estimate_rpm), _speed_notes(float(speed_estimate_rpm), speed_notes))
    with _blas_limit:
        if recording.keyphasor_takes is not None:
            result = extract_by_take(recording, _extract)
        else:
            result = _extract(recording, estimate)
        return with_sanity(recording, result) if sanity else result


def with_sanity(recording: Recording, fr: FeatureResult) -> FeatureResult:
    """``fr`` with the physics sanity findings of ``recording`` read with it (``check_recording``) in ``sanity``.

    The checks read the features as well as the samples (orbit against clearance, whirl direction, the sync lines),
    so they run after extraction, once per reading, under the same BLAS thread limit as the extraction.
    """
    with _blas_limit:
        return replace(fr, sanity=check_recording(recording, fr))


def _speed_notes(speed_rpm: float, notes: Sequence[str]) -> list[str]:
    """The warnings that go with a speed estimated elsewhere: ``notes`` (catalogue notes, as a reading's
    ``warnings``), and one that puts it in doubt when none does.

    Raises
    ------
    TypeError
        For a note that is not a :class:`~rotordiag.core.notes.Note` (a programming error, never the user's).
    """
    out = list(notes)
    if not all(isinstance(w, Note) for w in out):
        raise TypeError("speed_notes: every note must be a rotordiag.core.notes.Note (a warning of the catalogue)")
    if not any(speed_in_doubt(w) for w in out):
        out.append(Note("speed_estimated_elsewhere", speed_rpm=speed_rpm))
    return out


def with_speed_notes(fr: FeatureResult, notes: Sequence[str]) -> FeatureResult | None:
    """``extract_features(recording, speed_estimate_rpm=fr.speed_rpm, speed_notes=notes)`` made from
    ``fr = extract_features(recording, speed_estimate_rpm=fr.speed_rpm)`` without extracting again: the two differ
    in their speed notes alone (the notes lead the warnings, and nothing else reads them). None when ``fr`` is not
    such a result (its speed not estimated elsewhere, or read by take)."""
    if fr.speed_source != "estimated" or fr.speed_rpm is None:
        return None
    own = _speed_notes(float(fr.speed_rpm), ())
    warnings = list(fr.warnings)
    for i in range(len(warnings) - len(own) + 1):
        if warnings[i:i + len(own)] == own:
            return replace(fr, warnings=type(fr.warnings)(warnings[:i] + _speed_notes(float(fr.speed_rpm), notes)
                                                          + warnings[i + len(own):]))
    return None
