"""A start-up or coast-down as evidence beside the steady verdict (issue 46, item 4): what a run shows, and how it
is merged into a verdict.

From a tracked run (``features.transient``): each probe's 1X critical (``OrderTrack.peaks``) and each bearing's
shaft-centreline rise — the speed by which the journal has made half its rise from the slowest step
(``half_rise_rpm``, a lift-off speed), where it stands at the top speed (``top_um``, from the slowest step's
position) and where it sits at slow roll (``slow_roll_um``, the slowest steps' mean gap: a shaft train's offset moves
it at every speed, so the rise from it does not change): :func:`startup_evidence`, stored by the service as plain data (:class:`StartupEvidence`).
:func:`compare_startups` sets a run against the asset's baseline start-up. The check that turns the comparison into
evidence entries and at most one reason (``startup_changed``) is ``models.checks.startup``; :func:`with_startup`
adds its entries and reasons to a verdict, never changing a band. How much it adds, measured on simulated held-out
plants: docs/transient.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotordiag.core.conventions import COUPLING_BEARINGS

from .status import UNCERTAIN, Reason

__all__ = ["StartupEvidence", "startup_evidence", "compare_startups", "with_startup", "misaligned_call"]


@dataclass
class StartupEvidence:
    """What a start-up shows: ``criticals`` {(bearing, angle_deg): speed_rpm} of the 1X peaks, ``half_rise_rpm``
    {bearing: speed}, ``top_um`` {bearing: (x, y) at the top speed from the slowest step}, ``clearance_um``
    {bearing: radial clearance} (empty when not known), the run's speed range, ``slow_roll_um`` {bearing: (x, y)
    the journal's mean position over the slowest steps, in the centreline's own zero} (empty in evidence stored
    before it was kept)."""

    criticals: dict[tuple[int, float], float]
    half_rise_rpm: dict[int, float] = field(default_factory=dict)
    top_um: dict[int, tuple[float, float]] = field(default_factory=dict)
    clearance_um: dict[int, float] = field(default_factory=dict)
    speed_range_rpm: tuple[float, float] = (math.nan, math.nan)
    slow_roll_um: dict[int, tuple[float, float]] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON data (probes as ``"b2@45"``, bearings as strings): what the service stores of a start-up."""
        return {"criticals": {f"b{b}@{a:g}": s for (b, a), s in sorted(self.criticals.items())},
                "half_rise_rpm": {str(b): v for b, v in sorted(self.half_rise_rpm.items())},
                "top_um": {str(b): [float(v[0]), float(v[1])] for b, v in sorted(self.top_um.items())},
                "clearance_um": {str(b): v for b, v in sorted(self.clearance_um.items())},
                "speed_range_rpm": [float(v) for v in self.speed_range_rpm],
                "slow_roll_um": {str(b): [float(v[0]), float(v[1])] for b, v in sorted(self.slow_roll_um.items())}}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> StartupEvidence:
        """The inverse of :meth:`to_dict`. Raises ValueError on data it did not write."""
        try:
            crit = {}
            for key, s in (d.get("criticals") or {}).items():
                b, a = str(key).removeprefix("b").split("@")
                crit[(int(b), float(a))] = float(s)
            lo, hi = d.get("speed_range_rpm") or (math.nan, math.nan)
            return cls(crit, {int(b): float(v) for b, v in (d.get("half_rise_rpm") or {}).items()},
                       {int(b): (float(v[0]), float(v[1])) for b, v in (d.get("top_um") or {}).items()},
                       {int(b): float(v) for b, v in (d.get("clearance_um") or {}).items()},
                       (float(lo), float(hi)),
                       {int(b): (float(v[0]), float(v[1])) for b, v in (d.get("slow_roll_um") or {}).items()})
        except (TypeError, ValueError, IndexError, AttributeError) as exc:
            raise ValueError(f"not a stored start-up evidence: {exc}") from None


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
        ev.slow_roll_um[int(b)] = (x0, y0)
        rise = np.hypot(x - x0, y - y0)
        total = math.hypot(x1 - x0, y1 - y0)
        if total > 0:
            i = int(np.argmax(rise >= 0.5 * total))
            ev.half_rise_rpm[int(b)] = float(sp[i])
        if int(b) in centreline.clearance_um:
            ev.clearance_um[int(b)] = float(centreline.clearance_um[int(b)])
    return ev


def compare_startups(now: StartupEvidence, baseline: StartupEvidence,
                     coupling_bearings: tuple[int, ...] = COUPLING_BEARINGS) -> dict[str, Any]:
    """How the run differs from the baseline: ``critical_shift`` {probe: (baseline, now, fraction)} for the probes
    with a 1X critical in both; ``half_rise_shift`` {coupling bearing: (baseline, now, fraction)};
    ``top_change_per_clearance`` {coupling bearing: |Δ position at the top speed| / clearance};
    ``slow_roll_change_per_clearance`` {coupling bearing: |Δ slow-roll position| / clearance} (both runs' gaps read
    against the same zero: the same probes, DC-coupled; a centreline referenced to each run's own slow roll gives 0).
    ``coupling_bearings``: the bearings either side of the coupling (the paper model's 2 and 3; a train's the
    last of the driving rotor and the first of the driven one)."""
    crit = {p: (baseline.criticals[p], s, (s - baseline.criticals[p]) / baseline.criticals[p])
            for p, s in now.criticals.items() if p in baseline.criticals}
    rise = {b: (baseline.half_rise_rpm[b], now.half_rise_rpm[b],
                (now.half_rise_rpm[b] - baseline.half_rise_rpm[b]) / baseline.half_rise_rpm[b])
            for b in coupling_bearings if b in now.half_rise_rpm and b in baseline.half_rise_rpm}
    top = {}
    for b in coupling_bearings:
        c = now.clearance_um.get(b) or baseline.clearance_um.get(b)
        if b in now.top_um and b in baseline.top_um and c:
            d = np.subtract(now.top_um[b], baseline.top_um[b])
            top[b] = float(np.hypot(*d) / c)
    slow = {}
    for b in coupling_bearings:
        c = now.clearance_um.get(b) or baseline.clearance_um.get(b)
        if b in now.slow_roll_um and b in baseline.slow_roll_um and c:
            slow[b] = float(np.hypot(*np.subtract(now.slow_roll_um[b], baseline.slow_roll_um[b])) / c)
    return {"critical_shift": crit, "half_rise_shift": rise, "top_change_per_clearance": top,
            "slow_roll_change_per_clearance": slow}


def misaligned_call(verdict: dict[str, Any] | None) -> bool:
    """Whether a verdict dict calls misalignment (a band other than aligned; inconclusive calls nothing)."""
    return verdict is not None and verdict.get("severity") not in ("aligned", "inconclusive", None)


#: what each entry of ``models.checks.startup.startup_findings`` is called on an evidence row (``scope`` "start-up")
_ENTRY_NAMES = {"startup_criticals": "1X criticals", "startup_no_baseline": "baseline start-up",
                "startup_criticals_moved": "1X criticals against the baseline",
                "startup_unchanged": "coupling-end centreline rise", "startup_changed": "coupling-end centreline rise"}
_EFFECT_MEANING = {"supports": "the start-up changed as a misalignment would change it: supports the call",
                   "doubts": "the start-up changed since the baseline start-up, which the verdict does not explain",
                   "none": "for the record; not a doubt by itself"}


def with_startup(verdict: dict[str, Any], entries: list[dict[str, Any]], reasons: list[Reason],
                 source: str = "") -> dict[str, Any]:
    """``verdict`` (a ``Verdict.to_dict()``-style dict, not changed) with a start-up's evidence: each entry as an
    evidence row (``scope`` "start-up", ``name``, ``value``, ``meaning``) and the reasons added; a ``confident``
    status becomes ``uncertain`` when a reason is added. The band, Δ and probabilities are never changed, so the
    start-up can only make the verdict less certain. ``source`` names the start-up (e.g. its date) in the rows."""
    out = dict(verdict)
    tag = f" ({source})" if source else ""
    rows = [{"scope": "start-up", "name": _ENTRY_NAMES.get(e["code"], e["code"]) + tag, "value": e["text"],
             "meaning": _EFFECT_MEANING[e["effect"]], "number": None, "code": e["code"], "effect": e["effect"]}
            for e in entries]
    out["evidence"] = [ev for ev in (verdict.get("evidence") or []) if ev.get("scope") != "start-up"] + rows
    if reasons:
        have = {r.get("code") for r in verdict.get("reasons") or [] if isinstance(r, dict)}
        out["reasons"] = list(verdict.get("reasons") or []) + [r.to_dict() for r in reasons if r.code not in have]
        if out.get("status") == "confident":
            out["status"] = UNCERTAIN
    return out
