"""A start-up that changed since the asset's baseline start-up: a doubt on an "aligned" call, never a band.

The check of a start-up or coast-down beside the steady verdict (issue 46, item 4): a :class:`StartupContext` (the
run's ``models.startup.StartupEvidence``, the baseline's, whether the steady verdict calls misalignment) in, the
reasons out (:func:`startup_check`): at most ``startup_changed`` (uncertain), when the coupling-end centreline rise
changed since the baseline and the verdict says "aligned" — a change the verdict does not explain. Its context is
its own, not ``CheckContext``: it reads two stored runs and a stored verdict's call, not a steady recording.
:func:`startup_findings` gives the evidence entries too (what the answer and the report show of the run). What the
evidence is and how it is merged into a verdict: ``models.startup``; what it adds, measured: docs/transient.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rotordiag.core.conventions import COUPLING_BEARINGS

from ..startup import StartupEvidence, compare_startups
from ..status import UNCERTAIN, Reason

__all__ = ["StartupContext", "startup_check", "startup_findings", "CRITICAL_MOVED_FRACTION",
           "RISE_CHANGED_FRACTION"]

#: a 1X peak has moved when its speed differs from the baseline's by more than this fraction; reported as an entry
#: only: on simulated healthy re-runs of the same plant (another unbalance phase, or another ramp rate) the 1X peak
#: of a probe jumped between the plant's nearby modes by 10–50 % (docs/transient.md)
CRITICAL_MOVED_FRACTION = 0.05
#: a coupling-end bearing's centreline changed when its half-rise speed moved by this fraction, or its position at
#: the top speed or at slow roll by this fraction of the clearance
RISE_CHANGED_FRACTION = 0.10


@dataclass(frozen=True)
class StartupContext:
    """What the start-up check reads: ``startup`` (the run's evidence), ``baseline`` (the asset's baseline
    start-up's, None when there is none), ``misaligned_call`` (the steady verdict calls misalignment:
    ``models.startup.misaligned_call``) and ``coupling_bearings`` (the bearings either side of the coupling)."""

    startup: StartupEvidence
    baseline: StartupEvidence | None = None
    misaligned_call: bool = False
    coupling_bearings: tuple[int, ...] = COUPLING_BEARINGS


def startup_check(context: StartupContext) -> list[Reason]:
    """The start-up's reasons: ``startup_changed`` (uncertain) for an "aligned" call on a run whose coupling-end
    centreline (its rise or slow-roll position) changed since the baseline; none otherwise (:func:`startup_findings`' reasons)."""
    return startup_findings(context)[1]


def startup_findings(context: StartupContext) -> tuple[list[dict[str, Any]], list[Reason]]:
    """Evidence entries and reasons from a start-up.

    Returns (evidence entries — each ``{"code", "value", "text", "effect"}`` with effect ``"supports"`` /
    ``"doubts"`` / ``"none"`` —, reasons: at most ``startup_changed`` (uncertain) for an "aligned" call on a run
    that changed since the baseline). A moved 1X critical alone is an entry, never a doubt
    (:data:`CRITICAL_MOVED_FRACTION`).
    """
    now = context.startup
    base = context.baseline
    call = bool(context.misaligned_call)
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
    cmp_ = compare_startups(now, base, tuple(context.coupling_bearings))
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
    for b, v in sorted(cmp_["slow_roll_change_per_clearance"].items()):
        if v > RISE_CHANGED_FRACTION:
            found.append(f"bearing {b} (coupling end) sits {100 * v:.0f} % of its clearance away from where it sat "
                         "at slow roll in the baseline (the same probes' gap)")
    value = {"critical_shift": {f"b{b}@{a:g}": f for (b, a), (_, _, f) in cmp_["critical_shift"].items()},
             "half_rise_shift": {str(b): v[2] for b, v in cmp_["half_rise_shift"].items()},
             "top_change_per_clearance": {str(b): v for b, v in cmp_["top_change_per_clearance"].items()},
             "slow_roll_change_per_clearance": {str(b): v for b, v in
                                                cmp_["slow_roll_change_per_clearance"].items()}}
    if not found:
        entries.append({"code": "startup_unchanged", "effect": "none", "value": value,
                        "text": "the coupling-end centreline rise and slow-roll position match the baseline "
                                f"start-up's (within {100 * RISE_CHANGED_FRACTION:.0f} %)"})
        return entries, []
    text = "; ".join(found)
    if call:
        entries.append({"code": "startup_changed", "effect": "supports", "value": value,
                        "text": f"the start-up changed since the baseline, as a misalignment would change it: {text}"})
        return entries, []
    entries.append({"code": "startup_changed", "effect": "doubts", "value": value, "text": text})
    return entries, [Reason("startup_changed", UNCERTAIN, {"changes": text})]
