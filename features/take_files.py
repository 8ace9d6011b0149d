"""Takes recorded as separate files, merged into one recording with ``acquisitions`` (and a keyphasor per take).

A portable analyser saves each take — a bearing pair or two, with its tachometer or keyphasor — as a file of its own.
:func:`merge_takes` puts the files' recordings together as one :class:`features.Recording`: each file's bearings
are one acquisition, each file's keyphasor that take's pulse train (``features._takes``), every channel cut to the
shortest take. Used by ``rotordiag diagnose --takes``.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ._acquisitions import format_acquisitions
from ._recording import ProbeChannel, Recording
from .reader import ReadResult

__all__ = ["merge_takes", "SAMPLE_RATE_RTOL", "SPEED_RTOL"]

#: the takes' sample rates must agree this closely (relative): the merged recording has one
SAMPLE_RATE_RTOL = 1e-6
#: stated speeds of the takes must agree this closely (relative); the keyphasors' are compared by the features
SPEED_RTOL = 0.01


def _one_value(values: list[float | None], rtol: float, what: str, labels: Sequence[str]) -> float | None:
    given = [(v, lab) for v, lab in zip(values, labels) if v is not None]
    if not given:
        return None
    lo, hi = min(v for v, _ in given), max(v for v, _ in given)
    if hi > lo * (1.0 + rtol):
        raise ValueError(f"the takes give different {what}: " + ", ".join(f"{lab}: {v:g}" for v, lab in given)
                         + f"; they must agree within {100 * rtol:g} % to make one recording")
    return given[0][0]


def _clearances(recs: Sequence[Recording]) -> float | dict[int, float] | None:
    """Each take's clearance for its own bearings; one value when they are all the same."""
    per_bearing: dict[int, float] = {}
    for rec in recs:
        for b in rec.bearings:
            c = rec.clearance_for(b)
            if np.isfinite(c):
                per_bearing[b] = c
    if not per_bearing:
        return None
    values = set(per_bearing.values())
    return values.pop() if len(values) == 1 and len(per_bearing) == sum(len(r.bearings) for r in recs) else per_bearing


def merge_takes(results: Sequence[ReadResult], labels: Sequence[str]) -> ReadResult:
    """One recording from takes read separately (``features.reader.read_recording`` each).

    Parameters
    ----------
    results : sequence of ReadResult
        Two or more takes, each with bearings of its own, at one sample rate; a keyphasor in every take or in none.
    labels : sequence of str
        A name per take for the messages (the file names).

    Returns
    -------
    ReadResult
        ``recording`` with ``acquisitions`` = each take's bearings and, when every take has a keyphasor, one pulse
        train per take; every channel cut to the shortest take; the takes' notes prefixed with their label.

    Raises
    ------
    ValueError
        Fewer than two takes, a bearing in two takes, sample rates or stated speeds that differ, a keyphasor in some
        takes only, or a take that is itself recorded in separate acquisitions.
    """
    if len(results) < 2:
        raise ValueError("--takes: give two or more files, one per take")
    recs = [r.recording for r in results]
    seen: dict[int, str] = {}
    for rec, lab in zip(recs, labels):
        if rec.acquisition_groups:
            raise ValueError(f"{lab}: is itself recorded in separate acquisitions; give each take as its own file")
        for b in rec.bearings:
            if b in seen:
                raise ValueError(f"bearing {b} is in two takes ({seen[b]} and {lab}); each take must record other "
                                 "bearings")
            seen[b] = lab
    _one_value([r.sample_rate_hz for r in recs], SAMPLE_RATE_RTOL, "sample rates (Hz)", labels)
    speed = _one_value([r.speed_rpm for r in recs], SPEED_RTOL, "running speeds (r/min)", labels)
    with_kp = [r.keyphasor_times_s is not None for r in recs]
    if any(with_kp) and not all(with_kp):
        raise ValueError("a keyphasor in some takes only (" + ", ".join(
            f"{lab}: {'yes' if k else 'no'}" for lab, k in zip(labels, with_kp)) + "): give one in every take — "
            "the phases across the takes are referenced to it — or in none")
    ranges = {r.speed_range_rpm for r in recs if r.speed_range_rpm is not None}
    if len(ranges) > 1:
        raise ValueError(f"the takes give different speed ranges ({sorted(ranges)}); give one")
    n = min(r.n_points for r in recs)
    notes = [f"{len(recs)} takes merged into one recording, each its own acquisition ("
             + format_acquisitions([r.bearings for r in recs]) + ")"
             + (", each with its keyphasor" if all(with_kp) else ": no keyphasor, so the phases across the takes "
                "are not measured")
             + (f"; every channel cut to the shortest take's {n} samples" if any(r.n_points > n for r in recs) else "")]
    for res, lab in zip(results, labels):
        notes += [f"{lab}: {note}" for note in res.notes]
    channels = [ProbeChannel(c.bearing, c.angle_deg, c.units, c.data[:n], slow_roll_um_pp=c.slow_roll_um_pp)
                for rec in recs for c in rec.channels]
    trains = tuple(np.asarray(r.keyphasor_times_s) for r in recs) if all(with_kp) else None
    merged = Recording(sample_rate_hz=recs[0].sample_rate_hz, channels=channels, speed_rpm=speed,
                       keyphasor_times_s=trains, clearance_um=_clearances(recs),
                       speed_range_rpm=ranges.pop() if ranges else None,
                       dc_removed=any(r.dc_removed for r in recs),
                       acquisitions=[list(r.bearings) for r in recs])
    first = results[0]
    return ReadResult(recording=merged, format="+".join(r.format for r in results), notes=notes,
                      asset_id=first.asset_id, plant=first.plant)
