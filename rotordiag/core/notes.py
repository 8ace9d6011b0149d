"""The catalogue of every warning an answer can carry, and the typed warning (:class:`Note`) made from it.

A warning is something that makes a verdict less certain without being a reason of its own status (the reasons
and sanity findings are in :mod:`rotordiag.core.reasons`). Each is defined here once, as data: its code, its
severity, what it means and what to do, and a message template whose fields are typed values (speeds in r/min,
ratios, counts, lengths as :class:`Length` in µm). A :class:`Note` is one warning of one recording: its code and
values, and its text rendered from the template (µm by default, mils with :meth:`Note.render`).

``doubt`` warnings put an estimated running speed in doubt: ``models.status`` turns each into the
``speed_ambiguous`` reason, found by the code (:func:`speed_in_doubt`), never by the words.
"""
from __future__ import annotations

from dataclasses import dataclass
from string import Formatter
from types import MappingProxyType
from typing import Any, Final, Literal

from rotordiag.core.units import UM_PER_MIL

__all__ = ["Length", "Measured", "NoteInfo", "Note", "NOTES", "DOUBT", "CAUTION", "INFO", "SPEED_DOUBT_CODES",
           "speed_in_doubt", "notes_markdown_table", "typed_to_json", "typed_from_json", "template_fields"]

#: severities: ``doubt`` — the running speed is in doubt (``speed_ambiguous`` reason, never ``confident``);
#: ``caution`` — the verdict rests on less or different data than usual; ``info`` — a limit of what was measured
DOUBT: Final = "doubt"
CAUTION: Final = "caution"
INFO: Final = "info"


@dataclass(frozen=True)
class Length:
    """A length carried as a number with its unit (µm), rendered in µm or mil only when a message is written.

    Attributes
    ----------
    value_um : float
    fmt : str
        The format spec of the number (``".3g"``), the same in either unit.
    """

    value_um: float
    fmt: str = ".3g"

    def render(self, units: str = "um") -> str:
        if units == "mil":
            return f"{self.value_um / UM_PER_MIL:{self.fmt}} mil"
        return f"{self.value_um:{self.fmt}} µm"


class Measured(str):
    """A measurement's text (an evidence value) with its typed values: a ``str`` in µm, re-rendered in mil from
    the values (:meth:`render`), never by parsing the sentence.

    Parameters
    ----------
    template : str
        :meth:`str.format` template; a :class:`Length` field is written with its unit.
    **values
        The template's fields.
    """

    template: str
    values: dict[str, Any]

    def __new__(cls, template: str, **values: Any) -> Measured:
        self = super().__new__(cls, template.format(**_rendered(values, "um")))
        self.template = template
        self.values = dict(values)
        return self

    def __reduce__(self):
        return (_measured, (self.template, self.values))

    def render(self, units: str = "um") -> str:
        """The text with its lengths in ``units`` (``"um"`` or ``"mil"``)."""
        return self.template.format(**_rendered(self.values, units))

    @classmethod
    def of(cls, *parts: str | Length) -> Measured:
        """A text from its pieces in order: plain text and :class:`Length` values (``Measured.of("bearing 3 is ",
        Length(42.0), " pk-pk")``) — for messages assembled piece by piece."""
        template, values = [], {}
        for k, part in enumerate(parts):
            if isinstance(part, Length):
                template.append(f"{{v{k}}}")
                values[f"v{k}"] = part
            else:
                template.append(str(part).replace("{", "{{").replace("}", "}}"))
        return cls("".join(template), **values)

    @property
    def leads_with_length(self) -> bool:
        """Whether the text begins with a length (then an evidence item's ``number`` is that length)."""
        for literal, name, _, _ in Formatter().parse(self.template):
            return literal == "" and isinstance(self.values.get(name or ""), Length)
        return False


def _measured(template: str, values: dict[str, Any]) -> Measured:
    return Measured(template, **values)


def template_fields(template: str) -> frozenset[str]:
    """The :meth:`str.format` field names of a message template (what its typed values must be)."""
    return frozenset(f for _, f, _, _ in Formatter().parse(template) if f)


@dataclass(frozen=True)
class NoteInfo:
    """One warning of the catalogue.

    Attributes
    ----------
    code : str
        The stable identifier.
    severity : {"doubt", "caution", "info"}
    meaning : str
        What was found, for every recording.
    action : str
        What the engineer should check or do.
    template : str
        The message, :meth:`str.format` fields named after the typed values (a :class:`Length` field is written
        with its unit).
    """

    code: str
    severity: Literal["doubt", "caution", "info"]
    meaning: str
    action: str
    template: str

    @property
    def fields(self) -> frozenset[str]:
        return template_fields(self.template)

    def to_dict(self) -> dict:
        return {"code": self.code, "severity": self.severity, "meaning": self.meaning, "action": self.action,
                "template": self.template}


_GIVE = "give speed_rpm, speed_range_rpm or keyphasor_times_s"
_ENTRIES = (
    # --- the running speed in doubt (features' speed estimate, models.checks.speed_choice) ---
    NoteInfo("speed_estimate_ambiguous", DOUBT, "the running speed was estimated from the spectrum and another "
             "reading of it (a whirl, a sub-harmonic, a 2X) fits nearly as well", _GIVE,
             "speed estimate ambiguous: {detail}"),
    NoteInfo("speed_not_converged", DOUBT, "the refinement of the estimated running speed wandered off its "
             "spectral peak; the peak's frequency is used", _GIVE,
             "speed refinement did not converge; using the spectral peak {speed_rpm:.2f} r/min"),
    NoteInfo("speed_estimated_elsewhere", DOUBT, "the running speed was estimated outside the package's reading of "
             "the spectrum (speed_estimate_rpm)", "confirm it with speed_rpm or keyphasor_times_s",
             "speed estimate ambiguous: {speed_rpm:.1f} r/min was estimated outside this package's reading of "
             "the spectrum (speed_estimate_rpm); confirm it with speed_rpm or keyphasor_times_s"),
    NoteInfo("speed_chosen_by_model", DOUBT, "the estimated speed made the recording unlike the training machines; "
             "another speed the spectrum allows makes it like them and the verdict is given there", _GIVE,
             "speed estimate ambiguous: the verdict is given at {speed_rpm:.1f} r/min, not at the estimate "
             "{estimate_rpm:.1f} r/min. At the estimate the recording was unlike the machines the model was trained "
             "on (OOD score {estimate_ood:.2f}); of the {n_tried} other running speeds its spectrum allows, "
             "{speed_rpm:.1f} r/min makes it like them (OOD score {chosen_ood:.2f}). The speed rests on that "
             "judgement, not on the signal alone: confirm it (speed_rpm, speed_range_rpm or keyphasor_times_s)"),
    NoteInfo("speed_doubt_at_estimate", DOUBT, "why the speed estimate was in doubt, kept beside a speed chosen by "
             "the model", _GIVE, "at the estimate {estimate_rpm:.1f} r/min: {note}"),
    NoteInfo("speed_above_subsynchronous", INFO, "the largest line family is sub-synchronous and not harmonic "
             "with a higher one (oil whirl / whip?): the running speed is taken from the higher family",
             "confirm the speed if in doubt (speed_rpm or keyphasor_times_s)",
             "a line family at {line_cpm:.1f} cpm ({ratio_x:.3f}X) is sub-synchronous and not harmonic with the "
             "running speed (oil whirl / whip?); the speed is taken from the family at {speed_rpm:.1f} r/min"),
    NoteInfo("speed_from_whirl_partner", INFO, "the largest line family is a sub-synchronous whirl / whip; the "
             "running speed is read from its combination lines with the whirl", "confirm the speed if in doubt "
             "(speed_rpm or keyphasor_times_s)", "the line family at {whirl_cpm:.1f} cpm ({ratio_x:.3f}X) is a "
             "sub-synchronous whirl / whip: {n_lines} lines at combinations mΩ + kω of it with the running speed Ω "
             "({speed_rpm:.1f} r/min)"),
    NoteInfo("non_synchronous_dominant", CAUTION, "the largest spectral line is not a harmonic of the running "
             "speed: non-synchronous vibration dominates", "check the speed estimate or give speed_rpm / "
             "keyphasor_times_s",
             "the largest spectral line ({line_cpm:.1f} cpm = {order:.2f}X) is not synchronous: non-synchronous "
             "vibration dominates; check the speed estimate or give speed_rpm / keyphasor_times_s"),
    # --- the given speed or keyphasor ---
    NoteInfo("keyphasor_not_used", CAUTION, "the keyphasor pulses cannot be tracked (missing or extra pulses): "
             "the orders are tracked at a steady speed, phases relative to the first sample",
             "check the keyphasor probe's gap, trigger level and notch, or send speed_rpm instead",
             "keyphasor_times_s not used: {fault}. The orders are tracked at a steady {speed_rpm:.1f} r/min "
             "({source}), phases relative to the first sample"),
    NoteInfo("speed_varies", INFO, "the running speed changes between revolutions; orders are tracked revolution by "
             "revolution", "none (a steady operating state gives the firmest verdict)",
             "running speed varies by up to {variation_pct:.1f} % between revolutions; orders are tracked "
             "revolution by revolution from the keyphasor"),
    NoteInfo("speed_disagrees_keyphasor", CAUTION, "the stated speed_rpm differs from the keyphasor's by more than "
             "1 %; the keyphasor is used", "check speed_rpm", "speed_rpm {given_rpm:g} disagrees with the keyphasor "
             "({speed_rpm:.2f} r/min); the keyphasor is used"),
    NoteInfo("speed_off_signal", CAUTION, "the stated speed_rpm is off the signal's synchronous lines; the orders "
             "are tracked at the signal's speed", "check speed_rpm and sample_rate_hz",
             "speed_rpm {given_rpm:g} is {off_pct:+.2f} % off the signal's synchronous lines ({speed_rpm:.2f} "
             "r/min): the orders are tracked at the signal's speed"),
    NoteInfo("speed_off_line", CAUTION, "the stated speed_rpm differs from one of the signal's harmonic lines: order "
             "amplitudes are underestimated and phases drift", "check the speed (and sample_rate_hz) or give "
             "keyphasor_times_s",
             "speed_rpm {given_rpm:g} differs from the signal's {order}X line ({line_rpm:.2f} r/min, {off_pct:+.2f} "
             "%); order amplitudes are underestimated and phases drift — check the speed (and sample_rate_hz: a "
             "sample rate that is off moves every line alike) or give keyphasor_times_s"),
    # --- what the record allows ---
    NoteInfo("no_dc_position", INFO, "the channels carry no DC position: a stationary shaft-line offset is not "
             "assessed", "give DC readings referenced to the bearing centre",
             "the channels carry no DC position ({why}): no shaft-centreline position, so a stationary shaft-line "
             "offset is not assessed; give DC readings referenced to the bearing centre for it"),
    NoteInfo("few_revolutions_subharmonic", INFO, "too few revolutions for fine sub-harmonic bands",
             "record more revolutions", "only {n_revs} revolutions: sub-harmonic band features have a resolution of "
             "{resolution_x:.3f}X and are coarse (>= {min_revs} revolutions recommended)"),
    NoteInfo("few_revolutions_motion", INFO, "too few revolutions to classify the motion (periodic, quasi-periodic, "
             "chaotic)", "record more revolutions",
             "only {n_revs} revolutions: motion type not determined (needs >= {min_revs})"),
    NoteInfo("motion_not_classified", INFO, "the orbit is too small to classify the motion against the noise",
             "check the units of the samples", "motion type not determined: the orbit ({orbit}) is too small to "
             "classify against the noise; check the units of the samples"),
    # --- separate acquisitions (features._takes, features._acquisitions) ---
    NoteInfo("take_note", INFO, "a warning of one take of a recording made in separate acquisitions (the "
             "take's own warning, with its code, is the value ``note``; a doubtful speed stays doubtful)",
             "as the take's warning says", "the take of {take}: {note}"),
    NoteInfo("takes_speeds_differ", CAUTION, "the takes of one recording ran at different speeds",
             "re-record at one operating state", "the takes ran at different speeds ({speeds}): amplitudes and "
             "phases compare across takes only at the same speed and load; re-record at one operating state"),
    NoteInfo("takes_motion_differ", INFO, "the takes show different motion types; the least regular is reported",
             "none", "the takes show different motion types ({motions}): the least regular, {shown}, is reported"),
    NoteInfo("separate_acquisitions_referenced", INFO, "bearings were recorded in separate acquisitions, each with "
             "its keyphasor: phases across them are measured", "record at the same speed and load in each take",
             "bearings recorded in separate acquisitions ({groups}), each with its keyphasor: every order's phase is "
             "referenced to the keyphasor mark, so the phase differences across the takes are measured — provided "
             "the machine ran at the same speed and load in each"),
    NoteInfo("separate_acquisitions_unreferenced", CAUTION, "bearings were recorded in separate acquisitions "
             "without a keyphasor reference: phase differences across them are not measured",
             "record the bearings in one acquisition or with a keyphasor", "bearings recorded in separate "
             "acquisitions ({groups}): the phase differences between {pairs} are not measured ({why})"),
    # --- the model side (models.predict, models.checks.bearing_sets) ---
    NoteInfo("model_features_not_produced", CAUTION, "features the model reads were not produced by the feature "
             "extractor (treated as missing)", "use the feature extractor the model was trained with",
             "{n_missing} model feature(s) not produced by the feature extractor (treated as missing): "
             "{examples}"),
    NoteInfo("features_never_missing", CAUTION, "features always present in training are missing here",
             "record an x/y pair at each trained bearing and at least 32 revolutions",
             "{n_missing} feature(s) missing here were always present in training (e.g. {examples}); the verdict "
             "relies on the others and is less certain"),
    NoteInfo("signal_unlike_training", CAUTION, "the recording is unlike the training data (OOD score above 1)",
             "treat the verdict with caution", "signal unlike the training data (OOD score {ood_score:.2f} > 1): "
             "treat the verdict with caution"),
    NoteInfo("features_outside_training", CAUTION, "features lie outside the training data's range",
             "treat the verdict with caution", "{n_outside} feature(s) outside the training data's range "
             "({examples}): treat the verdict with caution"),
    NoteInfo("reverse_whirl_as_trained", INFO, "the 1X whirls backward at one bearing, as it does there in the "
             "training machines most like this one: read as the machine's motion, not a probe mistake",
             "if the probes were changed or re-cabled, check their order and polarity",
             "bearing {bearing}: the 1X whirls backward, as in {n_backward} of the {n_neighbours} training "
             "recordings nearest this one (a journal on anisotropic supports between their split critical speeds): "
             "read as the machine's motion, not a probe-order or polarity mistake"),
    NoteInfo("bearings_not_read", INFO, "bearings outside the model's probe set were left out of the model's "
             "reading (the evidence still shows them)", "none", "{detail}"),
    # --- the change since an asset's baseline (models.change.compare) ---
    NoteInfo("change_thresholds_own", INFO, "the 1X, 2X and centreline change thresholds are this asset's own, set "
             "from how much its baseline recordings differ from each other",
             "take the baseline's recordings across the operating band you compare in (load, temperature)",
             "1X, 2X and centreline thresholds from this asset's own repeatability ({n_recordings} baseline "
             "recordings, {margin:g} × their largest difference from each other)"),
    NoteInfo("change_thresholds_fleet", CAUTION, "the change thresholds are the fleet-wide ones, set on simulated "
             "machines of many sizes: a small machine's change of a few µm (a coupling offset moving its journals) "
             "stays under them", "add recordings of the unchanged machine at this operating condition to the "
             "baseline (POST /assets/{id}/baseline/recordings) until it has 3",
             "fleet-wide change thresholds: {why}; a change of a few µm on a small machine stays under them"),
)

#: every warning code, in the order above
NOTES: MappingProxyType[str, NoteInfo] = MappingProxyType({e.code: e for e in _ENTRIES})
if len(NOTES) != len(_ENTRIES):                                          # pragma: no cover - a typo in the table
    raise RuntimeError("rotordiag.core.notes: a code is defined twice")

#: the codes that put the running speed in doubt (the ``speed_ambiguous`` reason)
SPEED_DOUBT_CODES: frozenset[str] = frozenset(e.code for e in _ENTRIES if e.severity == DOUBT)


def _rendered(values: dict[str, Any], units: str) -> dict[str, Any]:
    """The values with their lengths written in ``units``: a :class:`Length`, or a :class:`Measured` (a piece of
    text with lengths of its own, as a reason's list of per-bearing values)."""
    return {k: (v.render(units) if isinstance(v, Length | Measured) else v) for k, v in values.items()}


class Note(str):
    """One warning of one recording: a ``str`` (its text in µm, as every answer has carried it) with its
    catalogue ``code`` and typed ``values``.

    Parameters
    ----------
    code : str
        A code of :data:`NOTES`.
    **values
        The template's fields; a length as :class:`Length`.

    Raises
    ------
    ValueError
        For a code the catalogue lacks, or values that are not the template's fields (a programming error).
    """

    code: str
    values: dict[str, Any]

    def __new__(cls, code: str, **values: Any) -> Note:
        info = NOTES.get(code)
        if info is None:
            raise ValueError(f"warning code {code!r} is not in the catalogue (rotordiag.core.notes): add it there")
        if set(values) != info.fields:
            raise ValueError(f"warning {code!r}: values {sorted(values)} are not the template's fields "
                             f"{sorted(info.fields)}")
        self = super().__new__(cls, info.template.format(**_rendered(values, "um")))
        self.code = code
        self.values = dict(values)
        return self

    def __reduce__(self):                   # pickled / copied as its code and values (the worker process)
        return (_note, (self.code, self.values))

    @property
    def severity(self) -> str:
        return NOTES[self.code].severity

    def render(self, units: str = "um") -> str:
        """The message with its lengths in ``units`` (``"um"`` or ``"mil"``)."""
        return NOTES[self.code].template.format(**_rendered(self.values, units))


def _note(code: str, values: dict[str, Any]) -> Note:
    return Note(code, **values)


def speed_in_doubt(warning: object) -> bool:
    """Whether a warning puts the estimated running speed in doubt: a :class:`Note` of a ``doubt`` code, or one
    that carries such a note (a take's warning)."""
    return isinstance(warning, Note) and (warning.code in SPEED_DOUBT_CODES
                                          or speed_in_doubt(warning.values.get("note")))


def notes_markdown_table() -> str:
    """The warnings catalogue as a Markdown table (code, severity, meaning, what to do)."""
    rows = ["| code | severity | meaning | what to do |", "|---|---|---|---|"]
    for e in _ENTRIES:
        rows.append(f"| `{e.code}` | {e.severity} | {e.meaning} | {e.action} |")
    return "\n".join(rows) + "\n"


def typed_to_json(obj: Any) -> Any:
    """A :class:`Note`, :class:`Measured` or :class:`Length` (also inside dicts and lists) as plain JSON data that
    :func:`typed_from_json` turns back into the same typed object — so a stored text can be rendered again in mils.
    Other values pass as they are (numbers, strings, None); anything else as its ``str``."""
    if isinstance(obj, Length):
        return {"__length_um__": float(obj.value_um), "fmt": obj.fmt}
    if isinstance(obj, Note):
        return {"__note__": obj.code, "values": typed_to_json(obj.values)}
    if isinstance(obj, Measured):
        return {"__measured__": obj.template, "values": typed_to_json(obj.values)}
    if isinstance(obj, dict):
        return {str(k): typed_to_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [typed_to_json(v) for v in obj]
    if obj is None or isinstance(obj, bool | int | float | str):
        return obj
    if hasattr(obj, "__float__"):   # NumPy scalars
        return float(obj)
    return str(obj)


def typed_from_json(data: Any) -> Any:
    """The inverse of :func:`typed_to_json`. Raises ValueError on a typed entry it cannot rebuild (an unknown
    warning code, values that are not the template's fields)."""
    if isinstance(data, list):
        return [typed_from_json(v) for v in data]
    if not isinstance(data, dict):
        return data
    if "__length_um__" in data:
        return Length(float(data["__length_um__"]), str(data.get("fmt", ".3g")))
    if "__note__" in data:
        return Note(str(data["__note__"]), **typed_from_json(data.get("values") or {}))
    if "__measured__" in data:
        try:
            return Measured(str(data["__measured__"]), **typed_from_json(data.get("values") or {}))
        except (KeyError, IndexError, ValueError) as exc:
            raise ValueError(f"a stored measurement does not fit its template: {exc}") from None
    return {k: typed_from_json(v) for k, v in data.items()}
