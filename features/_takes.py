"""Bearings recorded in separate takes, each with its own keyphasor: phases across the takes are measured.

A plant engineer with a two- or four-channel portable analyser records a train bearing pair by bearing pair, with the
same once-per-revolution reference (a keyphasor probe, an optical tachometer on a reflective mark) in every take.
Each take's orders are then phase-referenced to the same mark on the shaft, so the phase of an order at one bearing
can be compared with its phase at a bearing of another take — the classic field measurement of the phase across a
coupling. (Without the reference the takes' start times are not related, and ``features._acquisitions`` leaves
those phase differences out.)

:func:`extract_by_take` extracts each take as its own recording with its pulse train and merges the results: the
per-bearing features of each take, the phase differences of every pair (:func:`features._extract.phase_differences`),
the running speed averaged over the takes' revolutions (a warning when the takes ran at speeds more than
``SPEED_VARIATION_WARN`` apart: the comparison assumes the same operating state), and the least regular motion type
of the takes (one classification of every bearing's Poincaré points together finds the motion not periodic when one
bearing's is not). A take whose pulse train is faulty is tracked at a steady speed with its phases relative to its first
sample (``features._keyphasor``): its phases are then not related to the others', and those differences are missing.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rotordiag.core.notes import Note

from . import _config as cfg
from ._acquisitions import format_acquisitions
from ._across import across_bearings
from ._extract import _NAME_INDEX, _SPEED_INDEX, FeatureResult, _bearing_schema, phase_differences
from ._names import FEATURE_NAMES
from ._recording import Recording

__all__ = ["extract_by_take"]

_MOTION = ("motion_period", "motion_quasi_periodic", "motion_chaotic")
#: motion types from the most regular to the least (period-n ranked further by n)
_MOTION_RANK = {"period-n": 0, "unresolved": 1, "quasi-periodic": 2, "chaotic": 3}


def _motion_text(motion) -> str:
    return f"period-{motion.period}" if motion.kind == "period-n" else motion.kind


def _take_label(group: tuple[int, ...]) -> str:
    return ("bearing " if len(group) == 1 else "bearings ") + ", ".join(map(str, group))


def extract_by_take(rec: Recording, extract_one: Callable[[Recording], FeatureResult]) -> FeatureResult:
    """The features of a recording whose acquisitions each carry a keyphasor (``rec.keyphasor_takes``).

    Parameters
    ----------
    rec : Recording
        With ``acquisition_groups`` and ``keyphasor_takes`` of the same length.
    extract_one : callable
        Extracts one take's recording (sampled together, one pulse train), without the sanity checks.

    Raises
    ------
    ValueError
        A take's own refusal (too few revolutions, pulses off the record …), naming the take.
    """
    groups, trains = rec.acquisition_groups, rec.keyphasor_takes
    if trains is None or len(trains) != len(groups):
        raise ValueError("extract_by_take needs one keyphasor pulse train per acquisition (Recording.keyphasor_takes)")
    results: list[FeatureResult] = []
    for group, train in zip(groups, trains):
        take = Recording(sample_rate_hz=rec.sample_rate_hz, channels=[c for c in rec.channels if c.bearing in group],
                         speed_rpm=rec.speed_rpm, keyphasor_times_s=train, clearance_um=rec.clearance_um,
                         speed_range_rpm=rec.speed_range_rpm, dc_removed=rec.dc_removed)
        try:
            results.append(extract_one(take))
        except ValueError as exc:
            raise ValueError(f"the take of {_take_label(group)}: {exc}") from None

    values = np.full(len(FEATURE_NAMES), np.nan)
    details = {}
    warnings: list[str] = []
    for group, fr in zip(groups, results):
        for b in group:
            _, index = _bearing_schema(b)
            values[index] = fr.values[index]
        details.update(fr.bearings)
        warnings += [Note("take_note", take=_take_label(group), note=w) for w in fr.warnings]

    revs = np.array([fr.n_revs for fr in results], dtype=float)
    speeds = np.array([fr.speed_rpm for fr in results])
    speed = float(np.sum(speeds * revs) / np.sum(revs))
    values[_SPEED_INDEX] = speed
    if speeds.max() / speeds.min() - 1.0 > cfg.SPEED_VARIATION_WARN:
        warnings.append(Note("takes_speeds_differ", speeds=", ".join(
            f"{_take_label(g)}: {s:.1f} r/min" for g, s in zip(groups, speeds))))

    typed = [fr for fr in results if fr.motion_type is not None]
    if typed:
        # the least regular motion any take shows: what one classification of all the bearings' Poincaré points
        # together finds (a bearing that does not repeat itself makes the motion not periodic)
        shown = max(typed, key=lambda fr: (_MOTION_RANK.get(fr.motion_type.kind, 0), fr.motion_type.period or 0))
        for name in _MOTION:
            values[_NAME_INDEX[name]] = shown.values[_NAME_INDEX[name]]
        if len({(fr.motion_type.kind, fr.motion_type.period) for fr in typed}) > 1:
            warnings.append(Note("takes_motion_differ", motions=", ".join(
                f"{_take_label(g)}: {_motion_text(fr.motion_type)}" for g, fr in zip(groups, results)
                if fr.motion_type is not None), shown=_motion_text(shown.motion_type)))
    motion = shown.motion_type if typed else None

    referenced = all(fr.phase_reference == "keyphasor" for fr in results)
    unrelated = () if referenced else groups
    if referenced:
        warnings.append(Note("separate_acquisitions_referenced", groups=format_acquisitions(groups)))
    faulty = " and of the take of ".join(_take_label(g) for g, fr in zip(groups, results)
                                         if fr.phase_reference != "keyphasor")
    warnings += phase_differences(values, details, unrelated, why=(
        f"the keyphasor of the take of {faulty} could not be used, so that take's phases are not referenced to the "
        "mark; see keyphasor_faulty"))
    across_bearings(values)
    return FeatureResult(
        names=FEATURE_NAMES, values=values, bearings=details, speed_rpm=speed,
        speed_source="keyphasor" if referenced else results[0].speed_source,
        phase_reference="keyphasor" if referenced else "first sample", n_revs=int(revs.min()), motion_type=motion,
        warnings=tuple(warnings), acquisitions=tuple(unrelated))
