"""The headline of a verdict: one sentence of what to do about the machine, and how urgent.

A plant engineer reads the first line and acts on it, so the headline is made from typed data only — the
verdict's status, band, reason codes (:mod:`rotordiag.core.reasons`), motion type, the offset in µm and the
baseline comparison — by the ordered rules of :data:`RULES`; the first rule that matches decides the action. The
sentence is rendered in the user's length units at the edge (CLI, API, page, report), as every other length.

The order puts the measurement before the machine: a recording whose units or physics fail gives "check the
measurement first" and no severity at all (``show_severity`` false), however the model scored it; a sub-synchronous
whirl comes before misalignment (it is a stability problem a misalignment verdict cannot describe); then a change
since the asset's baseline; then the band, with the status deciding whether the band is acted on or confirmed first.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Final, Literal

from rotordiag.core.reasons import INCONCLUSIVE, SANITY, code_info, known_code
from rotordiag.core.timefmt import readable_time
from rotordiag.core.units import um_to

__all__ = ["ACTIONS", "URGENCIES", "UNITS_CODES", "Headline", "headline", "headline_dict"]

Action = Literal["none", "check_measurement", "record_again", "investigate_whirl", "investigate_change", "watch",
                 "confirm", "plan_alignment", "align_soon"]
Urgency = Literal["none", "before_acting", "routine", "next_outage", "soon"]

#: every action a headline can name, and what it asks of the engineer
ACTIONS: Final[Mapping[str, str]] = {
    "none": "no action",
    "check_measurement": "check the measurement (units, sensitivity, probes) before reading any verdict",
    "record_again": "record again as the reasons say: this recording does not allow a verdict",
    "investigate_whirl": "investigate the sub-synchronous vibration (oil whirl or whip) first",
    "investigate_change": "investigate what changed since the asset's baseline",
    "watch": "keep trending; no intervention",
    "confirm": "confirm the reading (a second recording, the baseline, the centreline) before acting",
    "plan_alignment": "plan an alignment check at the next outage",
    "align_soon": "check the alignment soon; trend the vibration closely until then",
}
#: how soon, from nothing to do to soon
URGENCIES: Final[tuple[str, ...]] = ("none", "before_acting", "routine", "next_outage", "soon")

#: reason codes that say the units or the scale of the recording are wrong (the length itself is suspect)
UNITS_CODES: Final[frozenset[str]] = frozenset({
    "orbit_exceeds_clearance", "orbit_exceeds_probe_range", "dc_implausible", "scale", "journals_near_centre"})


def _subsynchronous(motion_type: str | None) -> bool:
    """A motion that is not the forced period-1 response (``simulator.motion`` labels: ``period-2``…,
    ``quasi-periodic``, ``chaotic``); ``unresolved`` and unknown say nothing."""
    return motion_type is not None and motion_type not in ("period-1", "unresolved")


@dataclass(frozen=True)
class Headline:
    """What to do (``action``, one of :data:`ACTIONS`), how soon (``urgency``), the sentence, and whether a
    severity may be shown beside it (false when the measurement itself is in doubt)."""

    action: Action
    urgency: Urgency
    text: str
    show_severity: bool = True

    def to_dict(self) -> dict[str, Any]:
        return {"action": self.action, "urgency": self.urgency, "text": self.text,
                "show_severity": self.show_severity}


@dataclass(frozen=True)
class _Facts:
    """What the rules read from a verdict (µm), computed once."""

    status: str
    band: str | None
    codes: tuple[str, ...]
    sanity_failed: tuple[str, ...]
    units_codes: tuple[str, ...]
    motion_type: str | None
    offset_um: float | None
    baseline_changed: bool
    baseline_exceeded: tuple[str, ...]
    baseline_set_at: str | None
    units: str
    startup_changed: bool = False


def _length(value_um: float, units: str) -> str:
    """A length as a plant engineer says it: mm above 100 µm, µm below; mils in mil units."""
    if units == "mil":
        return f"{um_to(value_um, 'mil'):.1f} mil"
    if abs(value_um) >= 100.0:
        return f"{value_um / 1000.0:.2f} mm"
    return f"{value_um:.0f} µm"


def _offset_clause(f: _Facts) -> str:
    return f": the coupling offset is about {_length(f.offset_um, f.units)}" if f.offset_um is not None else ""


def _change_clause(f: _Facts) -> str:
    from .change import CHANGE_NAMES

    if f.startup_changed and not f.baseline_changed:
        return "the start-up's coupling-end centreline changed since the baseline start-up"

    what = " and ".join(CHANGE_NAMES.get(x, x.replace("_", " ")) for x in f.baseline_exceeded) or "the signature"
    when = f" of {readable_time(f.baseline_set_at)}" if f.baseline_set_at else ""
    return f"the {what} changed since the baseline{when}"


def _first_action(codes: tuple[str, ...]) -> str:
    return code_info(codes[0]).action if codes and known_code(codes[0]) else "see the reasons"


Rule = tuple[str, Callable[[_Facts], bool], Callable[[_Facts], Headline]]

#: the rules in the order they are tried; the first whose test is true makes the headline
RULES: Final[tuple[Rule, ...]] = (
    ("units wrong", lambda f: bool(f.units_codes) or bool(f.sanity_failed),
     lambda f: Headline("check_measurement", "before_acting",
                        ("check the measurement first: the units look wrong — " if f.units_codes else
                         "check the measurement first: ") + _first_action(f.units_codes or f.sanity_failed),
                        show_severity=False)),
    ("sub-synchronous whirl", lambda f: _subsynchronous(f.motion_type),
     lambda f: Headline("investigate_whirl", "soon",
                        f"investigate the sub-synchronous vibration first: the motion is {f.motion_type} (oil whirl "
                        "or whip?), a bearing stability problem that misalignment figures do not describe")),
    ("inconclusive", lambda f: f.status == INCONCLUSIVE,
     lambda f: Headline("record_again", "before_acting", "no verdict from this recording: " + _first_action(f.codes),
                        show_severity=False)),
    ("changed since the baseline", lambda f: f.baseline_changed or f.startup_changed,
     lambda f: Headline("investigate_change", "soon" if f.band in ("moderate", "severe") else "next_outage",
                        f"investigate: {_change_clause(f)}"
                        + ("; the model reads aligned" if f.band == "aligned" else
                           f"; the model reads {f.band} misalignment{_offset_clause(f)}" if f.band else ""))),
    ("aligned against its own 2X", lambda f: f.band == "aligned" and "signature_contradicts_call" in f.codes,
     lambda f: Headline("confirm", "before_acting", "confirm before acting: called aligned, but the coupling bearings' "
                        "2X/1X reads misalignment — " + code_info("signature_contradicts_call").action)),
    ("aligned", lambda f: f.band == "aligned" and f.status == "confident",
     lambda f: Headline("none", "none", "no action: aligned")),
    ("probably aligned", lambda f: f.band == "aligned",
     lambda f: Headline("watch", "routine", "no action on this recording alone: probably aligned, not certain — "
                        + _first_action(f.codes))),
    ("slight", lambda f: f.band == "slight",
     lambda f: Headline("watch", "routine", f"keep trending: slight misalignment{_offset_clause(f)}"
                        + ("" if f.status == "confident" else " (not certain: " + _first_action(f.codes) + ")"))),
    ("moderate or severe, not certain", lambda f: f.band in ("moderate", "severe") and f.status != "confident",
     lambda f: Headline("confirm", "before_acting", f"confirm before acting: the model reads {f.band} misalignment"
                        f"{_offset_clause(f)}, but not with confidence — " + _first_action(f.codes))),
    ("moderate", lambda f: f.band == "moderate",
     lambda f: Headline("plan_alignment", "next_outage",
                        f"plan an alignment check at the next outage{_offset_clause(f)}")),
    ("severe", lambda f: f.band == "severe",
     lambda f: Headline("align_soon", "soon", f"check the alignment soon: severe misalignment{_offset_clause(f)}; "
                        "trend the vibration closely until then")),
)


def _facts(verdict: Mapping[str, Any], baseline: Mapping[str, Any] | None, units: str) -> _Facts:
    reasons = [r for r in verdict.get("reasons") or [] if isinstance(r, Mapping)]
    codes = tuple(str(r.get("code")) for r in reasons if r.get("code"))
    sanity_failed = tuple(c for c, r in zip(codes, reasons, strict=False)
                          if known_code(c) and code_info(c).kind == SANITY and r.get("status") == INCONCLUSIVE)
    base = baseline if baseline is not None else verdict.get("baseline")
    changed = bool(isinstance(base, Mapping) and base.get("compared") and base.get("changed"))
    severity = verdict.get("severity")
    band = None if severity in (None, INCONCLUSIVE) else str(severity)
    offset = verdict.get("offset_um")
    return _Facts(status=str(verdict.get("status") or "confident"), band=band, codes=codes,
                  sanity_failed=sanity_failed, units_codes=tuple(c for c in codes if c in UNITS_CODES),
                  motion_type=verdict.get("motion_type"),
                  offset_um=float(offset) if isinstance(offset, int | float) else None,
                  baseline_changed=changed,
                  baseline_exceeded=tuple(base.get("exceeded") or ()) if changed and isinstance(base, Mapping) else (),
                  baseline_set_at=str(base.get("set_at")) if changed and isinstance(base, Mapping)
                  and base.get("set_at") else None,
                  units="mil" if units.strip().lower().startswith("mil") else "um",
                  startup_changed="startup_changed" in codes)


def headline(verdict: Mapping[str, Any], *, baseline: Mapping[str, Any] | None = None,
             units: str = "um") -> Headline:
    """The headline of ``verdict`` (a verdict dict in µm, as ``Verdict.to_dict()`` or the API answer before its
    unit conversion gives it).

    Parameters
    ----------
    verdict : mapping
        ``status``, ``severity``, ``reasons`` (with ``code`` and ``status``), ``motion_type``, ``offset_um``,
        and ``baseline`` when the answer carries the comparison.
    baseline : mapping, optional
        The baseline comparison (``models.change.compare``), when it is not in ``verdict``.
    units : {"um", "mil"}
        The units the sentence gives lengths in.
    """
    f = _facts(verdict, baseline, units)
    for _, test, make in RULES:
        if test(f):
            return make(f)
    return Headline("confirm", "before_acting", "read the reasons and the evidence: " + _first_action(f.codes))


def headline_dict(verdict: Mapping[str, Any], *, baseline: Mapping[str, Any] | None = None,
                  units: str = "um") -> dict[str, Any]:
    """:func:`headline` as the JSON object an answer carries."""
    return headline(verdict, baseline=baseline, units=units).to_dict()
