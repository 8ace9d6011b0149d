"""The catalogue of every code a verdict can carry: its sanity findings and the reasons behind its status.

Each code is defined here once, as data — what it means, what the engineer should do, and the statuses it can
give — and everything else is read from this table: the :class:`rotordiag.models.status.Reason` and
:class:`rotordiag.features.SanityFinding` constructors refuse a code that is not in it, the API schema's ``code``
enum is made from it (``service/schemas.py``), and the reason table of ``docs/pipeline.md`` is generated from it
(:func:`markdown_table`; ``tests/test_reasons_catalogue.py`` keeps the page and the table equal).

A sanity finding (``features.check_recording``) is ``fail`` or ``warn``; it becomes a reason of the same code,
``inconclusive`` or ``uncertain``. The other reasons are found by the model side (``models.status`` and the checks
beside it). A message is the finding in words for this one recording, with its numbers; the catalogue's
``meaning`` and ``action`` say the same for every recording.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Final, Literal

__all__ = ["CodeInfo", "CATALOGUE", "SANITY", "REASON", "UNCERTAIN", "INCONCLUSIVE", "FAIL", "WARN",
           "code_info", "known_code", "require_code", "markdown_table"]

#: what a sanity finding's level can be (``features.check_recording``)
FAIL = "fail"
WARN = "warn"
#: what a reason alone makes of a verdict
UNCERTAIN = "uncertain"
INCONCLUSIVE = "inconclusive"
#: where a code is found: a physics check on the recording (also a reason), or the model side only
SANITY: Final = "sanity"
REASON: Final = "reason"


@dataclass(frozen=True)
class CodeInfo:
    """One code of the catalogue.

    Attributes
    ----------
    code : str
        The stable identifier an answer carries.
    kind : {"sanity", "reason"}
        ``sanity``: a physics check of the recording (``features.check_recording``) that is also a reason;
        ``reason``: found on the model side only.
    statuses : tuple of {"uncertain", "inconclusive"}
        What the reason alone can make of the verdict.
    meaning : str
        What was found, for every recording.
    action : str
        What the engineer should check or do.
    """

    code: str
    kind: Literal["sanity", "reason"]
    statuses: tuple[str, ...]
    meaning: str
    action: str

    def to_dict(self) -> dict:
        return {"code": self.code, "kind": self.kind, "statuses": list(self.statuses),
                "meaning": self.meaning, "action": self.action}


_U, _I = (UNCERTAIN,), (INCONCLUSIVE,)
_UI = (UNCERTAIN, INCONCLUSIVE)

_ENTRIES = (
    # --- physics checks on the recording (features.check_recording) ---
    CodeInfo("zero_channel", SANITY, _I, "every sample of a channel is 0: the channel is not connected or not "
             "recorded", "check the probe's cable and the acquisition channel, then record again"),
    CodeInfo("flat_channel", SANITY, _I, "a channel's signal is constant: a probe out of range, a disconnected "
             "driver or a stuck input", "check the probe gap voltage, the driver and the acquisition input"),
    CodeInfo("dropout", SANITY, _I, "a channel holds one value for a stretch of the record: samples lost, not motion",
             "check the connector and cable; send a record without the stretch (cut it out or record again)"),
    CodeInfo("clipped_channel", SANITY, _I, "many samples sit at a channel's maximum or minimum: the signal is "
             "clipped (probe outside its linear range, driver or ADC saturated)",
             "check the probe gap voltage and the input range"),
    CodeInfo("spike", SANITY, _U, "a few isolated samples make the orbit larger than the clearance: a glitch, not "
             "shaft motion", "check the probe's cable and connector, or cut those samples out"),
    CodeInfo("orbit_exceeds_clearance", SANITY, _I, "the motion at a bearing is larger than the diametral clearance: "
             "a journal cannot move that far", "check the units (µm vs mils), the probe sensitivity and clearance_um "
             "(radial, in µm)"),
    CodeInfo("orbit_exceeds_probe_range", SANITY, _I, "the motion at a bearing is beyond a proximity probe's linear "
             "range", "check the units and the probe sensitivity"),
    CodeInfo("dc_implausible", SANITY, _I, "the mean probe reading is farther from zero than any proximity probe's "
             "gap", "check the units and the scale factor"),
    CodeInfo("reverse_whirl_all", SANITY, _I, "1X whirls backward at every bearing: almost always a convention error",
             "check the probe order, the rotation direction and the viewing end (angles toward the +y probe in the "
             "direction of rotation)"),
    CodeInfo("reverse_whirl", SANITY, _U, "1X whirls backward at one bearing: possible with very anisotropic "
             "supports, more often a convention error; that bearing is left out of the model's probe set",
             "check the probe order, the rotation direction and the viewing end"),
    CodeInfo("no_sync_signal", SANITY, _UI, "no 1X vibration stands out of the noise (at one bearing: uncertain; at "
             "every bearing: inconclusive, perhaps oil whirl or a wrong speed)",
             "check the probes and speed_rpm or the keyphasor; re-record with less noise or once the machine runs "
             "stably"),
    CodeInfo("common_mode_1x", SANITY, _U, "the 1X is one signal common to every probe: electrical pickup (mains at "
             "the running frequency) or the probe mountings vibrating together, not shaft motion",
             "check the probe cabling and grounding and re-record"),
    CodeInfo("common_mode_2x", SANITY, _U, "the 2X is one signal common to every probe: electrical pickup (mains at "
             "twice the running frequency) or the probe mountings vibrating together, not shaft motion",
             "check the probe cabling and grounding and re-record"),
    CodeInfo("keyphasor_faulty", SANITY, _U, "the keyphasor pulse train has missing or extra pulses: the orders were "
             "tracked at a steady speed, phases relative to the first sample",
             "check the keyphasor probe's gap, trigger level and notch, or send speed_rpm instead"),
    # --- the model side (models.status and the checks beside it) ---
    CodeInfo("ood", REASON, _UI, "the recording is unlike the training data (OOD score above 1; above 3 far outside: "
             "inconclusive)", "a machine design, operating state or set-up the model does not know: read the "
             "evidence, compare with this machine's baseline"),
    CodeInfo("outside_training", REASON, _UI, "a feature lies outside the training data's range (far beyond it: "
             "inconclusive)", "check the units, the probe sensitivity and the stated clearance; otherwise a machine "
             "unlike the training family"),
    CodeInfo("scale", REASON, _UI, "the 1X vibration at a coupling bearing is far above or below the training data's "
             "typical level", "check the units (µm vs mils ×25.4) and the probe sensitivity"),
    CodeInfo("journals_near_centre", REASON, _U, "every journal sits near its bearing centre: sizes per clearance "
             "too small for a loaded rotor", "check the units, the probe sensitivity, the clearance (radial, µm) and "
             "that the DC readings are referenced to the bearing centre"),
    CodeInfo("centreline_frame_turned", REASON, _U, "every journal's attitude angle is far off a plain journal "
             "bearing's, on one side: probes not at the angles given, or bearings unlike plain cylindrical ones",
             "check angle_deg, the rotation direction and the viewing end"),
    CodeInfo("speed_ambiguous", REASON, _U, "the running speed was estimated from the spectrum and is in doubt (or "
             "chosen by the model among the speeds the spectrum allows)",
             "confirm the speed: give speed_rpm, speed_range_rpm or keyphasor_times_s"),
    CodeInfo("features_missing", REASON, _U, "features the model always had in training are missing here",
             "give an x/y probe pair at each bearing the model was trained with (coupling bearings 2 and 3 at "
             "least) and record at least 32 revolutions"),
    CodeInfo("low_probability", REASON, _U, "no severity class is likely enough: the recording lies between classes",
             "recheck, or compare with this machine's baseline"),
    CodeInfo("far_band_probability", REASON, _U, "the model gives too much probability to bands two or more from its "
             "call", "recheck, or compare with this machine's baseline"),
    CodeInfo("far_band_interval", REASON, _U, "the Δ estimate's interval reaches a band two or more from the call",
             "recheck, or compare with this machine's baseline"),
    CodeInfo("below_alarm_threshold", REASON, _U, "misalignment is more likely than not but below the false-alarm "
             "threshold: called aligned", "recheck, or compare with this machine's baseline"),
    CodeInfo("signature_above_call", REASON, _I, "outside the training family the coupling 2X/1X reads two or more "
             "bands above the model's call: no severity is given", "check the alignment or compare with this "
             "machine's baseline; a strong 2X has other causes too (two-pole rotor, crack, looseness, runout)"),
    CodeInfo("no_2x_signature", REASON, _U, "called misaligned, but the coupling bearings show no 2X",
             "compare with this machine's baseline, check the centreline, or re-record"),
    CodeInfo("static_offset_only", REASON, _U, "the misalignment call rests on the static offset between the "
             "coupling-end journals", "compare with this machine's cold or baseline journal positions"),
    CodeInfo("offset_not_assessed", REASON, _U, "called aligned without the shaft-centreline position at the "
             "coupling bearings: a stationary offset is not ruled out",
             "give clearance_um and centre-referenced DC readings, or compare with this machine's baseline"),
    CodeInfo("class_delta_disagree", REASON, _U, "the severity classifier and the Δ regressor disagree; the Δ shown "
             "is clipped into the class's band", "recheck, or compare with this machine's baseline"),
    CodeInfo("bearing_set_untrained", REASON, _I, "none of the model's training probe sets lies within the "
             "recording's bearings", "add an x/y probe pair at a coupling bearing (3 tells the most) and send again"),
    CodeInfo("bearing_set_uninformative", REASON, _I, "the probe set the model reads tells misalignment poorly on "
             "held-out plants", "add probes so that the recording has one of the model's good probe sets"),
    CodeInfo("bearing_set_weak", REASON, _U, "the probe set the model reads gives more than the allowed false alarms "
             "on held-out plants", "probes at one of the model's good probe sets give a firmer verdict"),
    CodeInfo("bearing_numbering", REASON, _U, "numbered from the other end the recording is markedly more like the "
             "training machines", "check the numbering: 1 the generator's far end, 2 its coupling end, 3 the "
             "exciter's coupling end, 4 its far end"),
    CodeInfo("separate_acquisitions", REASON, _U, "bearings 2 and 3 were recorded in separate acquisitions: the phase "
             "across the coupling is not measured", "record bearings 2 and 3 in one acquisition, or trend this "
             "machine's 2X/1X"),
    CodeInfo("reverse_2x", REASON, _U, "a misalignment call on a coupling 2X that whirls backward",
             "check the probe wiring and pickup; compare with this machine's baseline"),
    CodeInfo("startup_changed", REASON, _U, "called aligned, but the start-up's coupling-end centreline rise "
             "changed since the asset's baseline start-up",
             "compare the two start-ups' Bode and centreline plots before accepting the verdict"),
    CodeInfo("clearance_diametral", REASON, _U, "half the stated clearance makes the recording markedly more like the "
             "training machines", "check that clearance_um is the radial clearance (half the diametral one)"),
    CodeInfo("family_untrained", REASON, _U, "the machine's declared plant model is not a machine family the model "
             "was trained on (its card's training families): its call is not to be trusted on this design",
             "retrain for this plant (`rotordiag retrain --shaftline`, POST /models/retrain) or compare with this "
             "machine's baseline; check the asset's plant model"),
    CodeInfo("signature_contradicts_call", REASON, _U, "called aligned while the coupling bearings' 2X/1X reads two or "
             "more bands higher on the rule of thumb: the verdict contradicts its own evidence",
             "check the alignment or compare with this machine's baseline; a strong 2X has other causes too (two-pole "
             "rotor, crack, looseness, runout)"),
    CodeInfo("attitude_outside_training", REASON, _U, "the clearance is not stated, but the direction of a journal's "
             "DC position in its bearing (its attitude angle, which needs no clearance) lies outside the training "
             "machines'", "state clearance_um and check that the DC readings are referenced to the bearing centre; "
             "bearings unlike plain cylindrical ones (tilting pads) read so"),
    CodeInfo("common_mode", REASON, _UI, "without the part of the 1X / 2X common to every probe the class differs "
             "(inconclusive when that part dominates)", "check the probe cabling and grounding before acting"),
)

#: every code, in the order of the table above (physics checks first)
CATALOGUE: MappingProxyType[str, CodeInfo] = MappingProxyType({e.code: e for e in _ENTRIES})
if len(CATALOGUE) != len(_ENTRIES):                                      # pragma: no cover - a typo in the table
    raise RuntimeError("rotordiag.core.reasons: a code is defined twice")


def known_code(code: str) -> bool:
    """Whether ``code`` is in the catalogue."""
    return code in CATALOGUE


def code_info(code: str) -> CodeInfo:
    """The catalogue's entry of ``code``.

    Raises
    ------
    KeyError
        For a code the catalogue lacks.
    """
    return CATALOGUE[code]


def require_code(code: str, status: str) -> None:
    """Refuse a code the catalogue lacks, or a status it does not allow that code (a programming error).

    ``status`` is a reason's (``uncertain`` / ``inconclusive``) or a sanity finding's level (``warn`` → uncertain,
    ``fail`` → inconclusive).

    Raises
    ------
    ValueError
        Naming the code and what the catalogue allows.
    """
    info = CATALOGUE.get(code)
    if info is None:
        raise ValueError(f"reason code {code!r} is not in the catalogue (rotordiag.core.reasons): add it there")
    as_status = {WARN: UNCERTAIN, FAIL: INCONCLUSIVE}.get(status, status)
    if as_status not in info.statuses:
        raise ValueError(f"reason code {code!r} with status {status!r}: the catalogue allows "
                         f"{', '.join(info.statuses)}")


def markdown_table() -> str:
    """The catalogue as a Markdown table (code, found by, status, meaning, what to do), as docs/pipeline.md holds it."""
    rows = ["| code | found by | status | meaning | what to do |", "|---|---|---|---|---|"]
    for e in _ENTRIES:
        where = "sanity check" if e.kind == SANITY else "model side"
        rows.append(f"| `{e.code}` | {where} | {' / '.join(e.statuses)} | {e.meaning} | {e.action} |")
    return "\n".join(rows) + "\n"
