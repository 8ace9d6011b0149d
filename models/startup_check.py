"""A start-up or coast-down as evidence beside the steady verdict (issue 46, item 4).

From a tracked run (``features.transient``): each probe's 1X critical (``OrderTrack.peaks``) and each bearing's
shaft-centreline rise — the speed by which the journal has made half its rise from the slowest step
(``half_rise_rpm``, a lift-off speed) and where it stands at the top speed (``top_um``, from the slowest step's
position). Against the asset's baseline start-up: how far each critical moved (an entry only) and how the
coupling-end bearings' rise changed. :func:`startup_reasons` (context in, reasons out) turns that into evidence
entries and at most one reason: ``startup_changed`` (uncertain) when the coupling-end centreline rise changed since
the baseline and the steady verdict says "aligned" — a change the verdict does not explain —, or a supporting
entry when the verdict is a misalignment call. It never changes a band. How much it adds, measured on simulated held-out plants: docs/transient.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotordiag.core.conventions import COUPLING_BEARINGS

from .status import UNCERTAIN, Reason

__all__ = ["StartupEvidence", "startup_evidence", "compare_startups", "startup_reasons",
           "CRITICAL_MOVED_FRACTION", "RISE_CHANGED_FRACTION"]

#: a 1X peak has moved when its speed differs from the baseline's by more than this fraction; reported as an entry
#: only: on simulated healthy re-runs of the same plant (another unbalance phase, or another ramp rate) the 1X peak
#: of a probe jumped between the plant's nearby modes by 10–50 % (docs/transient.md)
CRITICAL_MOVED_FRACTION = 0.05
#: a coupling-end bearing's centreline changed when its half-rise speed moved by this fraction, or its position at
#: the top speed by this fraction of the clearance
RISE_CHANGED_FRACTION = 0.10


@dataclass
class StartupEvidence:
    """What a start-up shows: ``criticals`` {(bearing, angle_deg): speed_rpm} of the 1X peaks, ``half_rise_rpm``
    {bearing: speed}, ``top_um`` {bearing: (x, y) at the top speed from the slowest step}, ``clearance_um``
    {bearing: radial clearance} (empty when not known), the run's speed range."""

    criticals: dict[tuple[int, float], float]
    half_rise_rpm: dict[int, float] = field(default_factory=dict)
    top_um: dict[int, tuple[float, float]] = field(default_factory=dict)
    clearance_um: dict[int, float] = field(default_factory=dict)
    speed_range_rpm: tuple[float, float] = (math.nan, math.nan)


def startup_evidence(track: Any, centreline: Any = None) -> StartupEvidence:
    """The evidence of a tracked run (``OrderTrack``) and its ``Centreline`` (None for AC-coupled probes)."""
    crit = {(int(p["bearing"]), float(p["angle_deg"])): float(p["speed_rpm"]) for p in track.peaks(1)}
    ev = StartupEvidence(crit, speed_range_rpm=(float(np.min(track.speed_rpm)), float(np.max(track.speed_rpm))))
    if centreline is None:
        return ev
    order = np.argsort(centreline.speed_rpm)
    sp = centreline.speed_rpm[order]
    n_end = max(1, sp.size // 20)  # the slowest and fastest 5 % of the steps, averaged against noise
    for j, b in enumerate(centreline.bearings):
        x, y = centreline.x_um[order, j], centreline.y_um[order, j]
        x0, y0 = float(np.mean(x[:n_end])), float(np.mean(y[:n_end]))
        x1, y1 = float(np.mean(x[-n_end:])), float(np.mean(y[-n_end:]))
        ev.top_um[int(b)] = (x1 - x0, y1 - y0)
        rise = np.hypot(x - x0, y - y0)
        total = math.hypot(x1 - x0, y1 - y0)
        if total > 0:
            i = int(np.argmax(rise >= 0.5 * total))
            ev.half_rise_rpm[int(b)] = float(sp[i])
        if int(b) in centreline.clearance_um:
            ev.clearance_um[int(b)] = float(centreline.clearance_um[int(b)])
    return ev


def compare_startups(now: StartupEvidence, baseline: StartupEvidence) -> dict[str, Any]:
    """How the run differs from the baseline: ``critical_shift`` {probe: (baseline, now, fraction)} for the probes
    with a 1X critical in both; ``half_rise_shift`` {coupling bearing: (baseline, now, fraction)};
    ``top_change_per_clearance`` {coupling bearing: |Δ position at the top speed| / clearance}."""
    crit = {p: (baseline.criticals[p], s, (s - baseline.criticals[p]) / baseline.criticals[p])
            for p, s in now.criticals.items() if p in baseline.criticals}
    rise = {b: (baseline.half_rise_rpm[b], now.half_rise_rpm[b],
                (now.half_rise_rpm[b] - baseline.half_rise_rpm[b]) / baseline.half_rise_rpm[b])
            for b in COUPLING_BEARINGS if b in now.half_rise_rpm and b in baseline.half_rise_rpm}
    top = {}
    for b in COUPLING_BEARINGS:
        c = now.clearance_um.get(b) or baseline.clearance_um.get(b)
        if b in now.top_um and b in baseline.top_um and c:
            d = np.subtract(now.top_um[b], baseline.top_um[b])
            top[b] = float(np.hypot(*d) / c)
    return {"critical_shift": crit, "half_rise_shift": rise, "top_change_per_clearance": top}


def startup_reasons(context: dict[str, Any]) -> tuple[list[dict[str, Any]], list[Reason]]:
    """Evidence entries and reasons from a start-up.

    ``context``: ``startup`` (:class:`StartupEvidence`), ``baseline`` (the asset's baseline start-up's, or None),
    ``misaligned_call`` (the steady verdict calls misalignment). Returns (evidence entries — each
    ``{"code", "value", "text", "effect"}`` with effect ``"supports"`` / ``"doubts"`` / ``"none"`` —, reasons: at
    most ``startup_changed`` (uncertain) for an "aligned" call on a run that changed since the baseline)."""
    now: StartupEvidence = context["startup"]
    base: StartupEvidence | None = context.get("baseline")
    call = bool(context.get("misaligned_call"))
    entries: list[dict[str, Any]] = [{
        "code": "startup_criticals", "effect": "none",
        "value": {f"b{b}@{a:g}": s for (b, a), s in sorted(now.criticals.items())},
        "text": "1X criticals of the start-up: " + (", ".join(
            f"b{b}@{a:g} {s:.0f} r/min" for (b, a), s in sorted(now.criticals.items())) or "none in the run")}]
    if base is None:
        entries.append({"code": "startup_no_baseline", "effect": "none", "value": None,
                        "text": "no baseline start-up of this asset: nothing to compare the criticals and the "
                                "centreline rise with"})
        return entries, []
    cmp_ = compare_startups(now, base)
    moved = [f"the 1X peak at b{b}@{a:g} moved from {s0:.0f} to {s1:.0f} r/min ({100 * f:+.0f} %)"
             for (b, a), (s0, s1, f) in sorted(cmp_["critical_shift"].items()) if abs(f) > CRITICAL_MOVED_FRACTION]
    if moved:  # reported, never a doubt by itself: see CRITICAL_MOVED_FRACTION
        entries.append({"code": "startup_criticals_moved", "effect": "none", "value": None,
                        "text": "; ".join(moved) + " (a 1X peak's speed also moves with the unbalance's phase and "
                                "the ramp rate between nearby modes: not a doubt by itself)"})
    found = []
    for b, (s0, s1, f) in sorted(cmp_["half_rise_shift"].items()):
        if abs(f) > RISE_CHANGED_FRACTION:
            found.append(f"bearing {b} (coupling end) makes half its centreline rise at {s1:.0f} r/min against "
                         f"{s0:.0f} in the baseline ({100 * f:+.0f} %)")
    for b, v in sorted(cmp_["top_change_per_clearance"].items()):
        if v > RISE_CHANGED_FRACTION:
            found.append(f"bearing {b} (coupling end) stands {100 * v:.0f} % of its clearance away from where it "
                         "stood at the top speed in the baseline")
    value = {"critical_shift": {f"b{b}@{a:g}": f for (b, a), (_, _, f) in cmp_["critical_shift"].items()},
             "half_rise_shift": {str(b): v[2] for b, v in cmp_["half_rise_shift"].items()},
             "top_change_per_clearance": {str(b): v for b, v in cmp_["top_change_per_clearance"].items()}}
    if not found:
        entries.append({"code": "startup_unchanged", "effect": "none", "value": value,
                        "text": "the coupling-end centreline rise matches the baseline start-up's (within "
                                f"{100 * RISE_CHANGED_FRACTION:.0f} %)"})
        return entries, []
    text = "; ".join(found)
    if call:
        entries.append({"code": "startup_changed", "effect": "supports", "value": value,
                        "text": f"the start-up changed since the baseline, as a misalignment would change it: {text}"})
        return entries, []
    entries.append({"code": "startup_changed", "effect": "doubts", "value": value, "text": text})
    return entries, [Reason("startup_changed", UNCERTAIN,
                            f"called aligned, but the start-up changed since the asset's baseline start-up: {text}. "
                            "A moved bearing, a changed coupling or a rub changes a run-up so; compare the two "
                            "start-ups' Bode and centreline plots before accepting the verdict")]
