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

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Final, Literal

from rotordiag.core.notes import Measured, template_fields

__all__ = ["CodeInfo", "CATALOGUE", "DEFAULT_VARIANT", "SANITY", "REASON", "UNCERTAIN", "INCONCLUSIVE", "FAIL", "WARN",
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
#: the variant name of a code's only message template
DEFAULT_VARIANT: Final = "default"


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
    template : str or mapping of str to str
        The message for one recording: a :meth:`str.format` template whose fields are the reason's typed values
        (a length as :class:`~rotordiag.core.notes.Length`, written in µm or mil); or, for a code whose cases read
        differently, one template per named variant (:data:`DEFAULT_VARIANT` for a single one).
    """

    code: str
    kind: Literal["sanity", "reason"]
    statuses: tuple[str, ...]
    meaning: str
    action: str
    template: str | Mapping[str, str]

    @property
    def templates(self) -> Mapping[str, str]:
        """The message templates by variant name."""
        t = self.template
        return MappingProxyType({DEFAULT_VARIANT: t} if isinstance(t, str) else dict(t))

    def fields(self, variant: str = DEFAULT_VARIANT) -> frozenset[str]:
        """The typed values a message of ``variant`` takes."""
        return template_fields(self._template(variant))

    def _template(self, variant: str) -> str:
        templates = self.templates
        if variant not in templates:
            raise ValueError(f"reason code {self.code!r} has no message variant {variant!r}; it has "
                             f"{', '.join(sorted(templates))}")
        return templates[variant]

    def message(self, variant: str = DEFAULT_VARIANT, values: Mapping[str, Any] | None = None) -> Measured:
        """The message of one recording: the template of ``variant`` with ``values`` (text in µm; mil with
        ``.render("mil")``).

        Raises
        ------
        ValueError
            For a variant the code lacks, or values that are not the template's fields (a programming error).
        TypeError
            For values that are not a mapping.
        """
        template = self._template(variant)
        if values is not None and not isinstance(values, Mapping):
            raise TypeError(f"reason {self.code!r}: values must be a mapping of the template's fields, got "
                            f"{type(values).__name__}")
        given = dict(values or {})
        wanted = template_fields(template)
        if set(given) != wanted:
            raise ValueError(f"reason {self.code!r} ({variant}): values {sorted(given)} are not the template's "
                             f"fields {sorted(wanted)}")
        return Measured(template, **given)

    def to_dict(self) -> dict:
        return {"code": self.code, "kind": self.kind, "statuses": list(self.statuses),
                "meaning": self.meaning, "action": self.action, "templates": dict(self.templates)}


_D = DEFAULT_VARIANT
_BEYOND_CLEARANCE = (" — a journal cannot move that far inside its bearing. Check the units (data declared in "
                     "{units!r}; µm read as mils is ×25.4), the probe sensitivity (e.g. 7.87 mV/µm) and clearance_um "
                     "(radial, in µm)")
_WHIRL_HINT = ("check the probe order (the first probe of each pair must be the one the shaft reaches first when it "
               "turns), the rotation direction and the viewing end (angles are measured toward the +y probe in the "
               "direction of rotation)")
_NO_SYNC = ("no 1X vibration stands out of the noise at any bearing — the recording carries no synchronous signal to "
            "diagnose (probes not reading the shaft, wrong speed, or a machine at rest); ")
_NO_SYNC_WHIRL = ("no 1X vibration stands out of the noise at any bearing, and sub-synchronous vibration{near} "
                  "dominates at bearing(s) {bearings} — ")
_WHIRL_FAULT = "oil whirl or whip, a fault to act on in itself (load, oil temperature, bearing clearance)"
_SPEED_MISMATCH = ("the signal's running-speed line reads {signal_rpm:.0f} r/min, {ratio:.3g} × the given "
                   "{given_rpm:.0f} r/min: either speed_rpm is wrong, or the sample rate is — if {given_rpm:.0f} r/min "
                   "is right, the channels were sampled at {fitting_rate_hz:.6g} Hz, not the {sample_rate_hz:g} Hz "
                   "given")
_KEYPHASOR_FAULTY = ("{fault}: the pulse train has missing or extra pulses, so the orders were not tracked by it but at "
                     "a steady speed, with phases relative to the first sample. Check the keyphasor probe's gap and "
                     "trigger level and the notch (worn, dirty, a second edge), or send the record without "
                     "keyphasor_times_s and with speed_rpm")
_OUTSIDE = ("{feature} is {value}{unit}, {how}{side} anything in the training data ({bound_name} {bound}{unit}; "
            "training range {train_min}{unit} … {train_max}{unit}): ")
_MISSING = "{n_missing} feature(s) the model always had are missing here (e.g. {examples}): "
_MISSING_PAIR = ("give an x/y probe pair at each bearing the model was trained with (the coupling bearings 2 and 3 at "
                 "least)")
_NO_2X = ("called misaligned, but the coupling bearings show no 2X (largest 2X/1X {seen} < {{min_2x_1x:g}}): the "
          "classic signature is missing and nothing physical backs the model's call — compare with this machine's "
          "baseline, check the centreline, or re-record")
_OFFSET_ALIGNED = ("called misaligned on the static offset between the coupling-end journals: with the two journals "
                   "at one position in their bearings the model would call it aligned")
_OFFSET_LOWER = ("the severity rests on the static offset between the coupling-end journals: with the two journals "
                 "at one position in their bearings the model would call it {lower_band}")
_OFFSET_APART = " (bearing 3's journal sits {apart_c:.2f} c from bearing 2's: x {apart_x_c:+.2f} c, y {apart_y_c:+.2f} c)"
_OFFSET_AFTER = (". A healthy train's coupling-end journals also sit apart (each by its own load: a heavy generator "
                 "journal beside a light exciter one), and a DC gap referenced to the wrong zero reads the same — "
                 "compare with this machine's cold or baseline positions before acting")
_NUMBERING = ("numbered the other way round (bearing b read as 5 − b) the recording is more like the machines the "
              "model knows (OOD score {{other_ood_score:.2f}} against {{ood_score:.2f}} as given; {called}): check the "
              "numbering — bearing 1 is the generator's far end (the turbine side), 2 its coupling end, 3 the "
              "exciter's coupling end and 4 its far end")
_ACQ = ("bearings {{bearing_a}} and {{bearing_b}} were recorded in separate acquisitions ({{acquisitions}}): the phase "
        "across the coupling is not measured, and the model tells aligned from slight partly by it{said}; record "
        "bearings {{bearing_a}} and {{bearing_b}} in one acquisition (or trend this machine's 2X/1X) before acting")
_ACQ_READ = (". Read with the shaft ends in phase across the coupling (0°, a healthy rigid coupling) the model calls it "
             "{in_phase}; in anti-phase (180°, the classic misalignment sign), {anti_phase}")
_COMMON_MODE = ("most of the {orders} is one signal common to every probe ({per_order}); a shaft's orbit differs from "
                "probe to probe and bearing to bearing, so that part is likely electrical pickup (mains at the running "
                "frequency or twice it on a grid-synchronous generator) or the probe mountings vibrating together. It "
                "was removed from every probe and the verdict is given on the rest")
_COMMON_MODE_ACT = (": check the probe cabling and grounding (a probe at a fixed target reads the pickup alone) and "
                    "re-record before acting on this verdict")


def _common_mode_template(order: int, source: str) -> str:
    """The ``common_mode_{order}x`` sanity finding's template (the two orders read alike)."""
    return (f"the {order}X is one signal common to every probe (" + "{amp} pk-pk at {phase_lag_deg:.0f}° on all "
            "{n_probes} probes of bearings {bearings}; {share_pct:.1f} % of the " + f"{order}X power): a shaft's "
            f"{order}X orbit differs between probe directions and from bearing to bearing, so this is no shaft motion "
            f"but electrical — {source}: a ground loop or a shared supply — or the probe mountings vibrating "
            "together. Check the probe cabling and grounding (a probe at a fixed target reads the pickup alone) and "
            "re-record")


_U, _I = (UNCERTAIN,), (INCONCLUSIVE,)
_UI = (UNCERTAIN, INCONCLUSIVE)

_ENTRIES = (
    # --- physics checks on the recording (features.check_recording) ---
    CodeInfo("zero_channel", SANITY, _I, "every sample of a channel is 0: the channel is not connected or not "
             "recorded", "check the probe's cable and the acquisition channel, then record again",
             ("bearing {bearing} probe at {angle_deg:g}°: every sample is 0 — the channel is not connected, not "
             "recorded or mapped to the wrong column; check the wiring and the channel order")),
    CodeInfo("flat_channel", SANITY, _I, "a channel's signal is constant: a probe out of range, a disconnected "
             "driver or a stuck input", "check the probe gap voltage, the driver and the acquisition input",
             ("bearing {bearing} probe at {angle_deg:g}°: the signal is constant ({level}) — probe disconnected or "
             "saturated, or the DC gap recorded without its AC part; check the probe, its driver and the acquisition "
             "channel")),
    CodeInfo("dropout", SANITY, _I, "a channel holds one value for a stretch of the record: samples lost, not motion",
             "check the connector and cable; send a record without the stretch (cut it out or record again)",
             ("bearing {bearing} probe at {angle_deg:g}°: the signal holds {level} for {duration_ms:.0f} ms in one "
             "stretch ({start_s:.3f}–{stop_s:.3f} s) — a dropout (a loose connector or cable, the acquisition losing "
             "samples), not motion; check the connection and send a record without it (cut it out, or record again)")),
    CodeInfo("clipped_channel", SANITY, _I, "many samples sit at a channel's maximum or minimum: the signal is "
             "clipped (probe outside its linear range, driver or ADC saturated)",
             "check the probe gap voltage and the input range",
             ("bearing {bearing} probe at {angle_deg:g}°: {share_pct:.1f} % of the samples sit at the channel's "
             "{extreme} ({level}) — the signal is clipped (probe outside its linear range, driver or ADC saturated); "
             "check the probe gap voltage and the input range")),
    CodeInfo("spike", SANITY, _U, "a few isolated samples make the orbit larger than the clearance: a glitch, not "
             "shaft motion", "check the probe's cable and connector, or cut those samples out",
             ("bearing {bearing}: {n_samples} isolated sample(s) (at t = {times_s} s) stand far off the rest of the "
             "record and make the motion {orbit} pk-pk; without them it is {orbit_without} pk-pk, inside the "
             "clearance. A glitch — electrical noise, a loose connector, a scratch or a dropout — not shaft motion: "
             "check the probe's cable and connector, or cut those samples out")),
    CodeInfo("orbit_exceeds_clearance", SANITY, _I, "the motion at a bearing is larger than the diametral clearance: "
             "a journal cannot move that far", "check the units (µm vs mils), the probe sensitivity and clearance_um "
             "(radial, in µm)",
             {_D: "bearing {bearing}: the motion is {orbit} pk-pk, {ratio:.1f}× the diametral clearance 2c = "
             "{clearance_2c}" + _BEYOND_CLEARANCE,
             "noise_allowance": "bearing {bearing}: the motion is {orbit} pk-pk, {ratio:.1f}× the diametral clearance "
             "2c = {clearance_2c} (allowing {noise} pk-pk for the probes' noise)" + _BEYOND_CLEARANCE}),
    CodeInfo("orbit_exceeds_probe_range", SANITY, _I, "the motion at a bearing is beyond a proximity probe's linear "
             "range", "check the units and the probe sensitivity",
             ("bearing {bearing}: the motion is {orbit} pk-pk, beyond the linear range of a proximity probe "
             "({probe_range}) — check the units (data declared in {units!r}) and the probe sensitivity")),
    CodeInfo("dc_implausible", SANITY, _I, "the mean probe reading is farther from zero than any proximity probe's "
             "gap", "check the units and the scale factor",
             ("bearing {bearing}: the mean probe reading is {mean} from zero — no proximity probe reads such a gap; "
             "check the units (declared {units!r}) and the scale factor")),
    CodeInfo("reverse_whirl_all", SANITY, _I, "1X whirls backward at every bearing: almost always a convention error",
             "check the probe order, the rotation direction and the viewing end (angles toward the +y probe in the "
             "direction of rotation)",
             ("1X whirls backward at every bearing ({bearings}); real machines whirl forward at 1X almost "
             "everywhere — " + _WHIRL_HINT)),
    CodeInfo("reverse_whirl", SANITY, _U, "1X whirls backward at one bearing: possible with very anisotropic "
             "supports, more often a convention error; that bearing is left out of the model's probe set",
             "check the probe order, the rotation direction and the viewing end",
             ("bearing {bearing}: 1X whirls backward — possible with very anisotropic supports, but more often a "
             "convention error: " + _WHIRL_HINT)),
    CodeInfo("no_sync_signal", SANITY, _UI, "no 1X vibration stands out of the noise (at one bearing: uncertain; at "
             "every bearing: inconclusive, perhaps oil whirl or a wrong speed)",
             "check the probes and speed_rpm or the keyphasor; re-record with less noise or once the machine runs "
             "stably",
             {_D: "bearing {bearing}: no 1X vibration above the noise floor",
             "every_bearing": _NO_SYNC + "check the probes and speed_rpm / the keyphasor",
             "every_bearing_speed": _NO_SYNC + _SPEED_MISMATCH,
             "whirl": _NO_SYNC_WHIRL + _WHIRL_FAULT + "; misalignment cannot be judged from this recording. "
             "Re-record with less noise or a keyphasor, or once the machine runs stably",
             "whirl_speed": _NO_SYNC_WHIRL + _SPEED_MISMATCH + "; or it is " + _WHIRL_FAULT + ". Misalignment "
             "cannot be judged from this recording"}),
    CodeInfo("common_mode_1x", SANITY, _U, "the 1X is one signal common to every probe: electrical pickup (mains at "
             "the running frequency) or the probe mountings vibrating together, not shaft motion",
             "check the probe cabling and grounding and re-record",
             _common_mode_template(1, "mains pickup at the running frequency (50/60 Hz on a 2-pole generator)")),
    CodeInfo("common_mode_2x", SANITY, _U, "the 2X is one signal common to every probe: electrical pickup (mains at "
             "twice the running frequency) or the probe mountings vibrating together, not shaft motion",
             "check the probe cabling and grounding and re-record",
             _common_mode_template(2, "mains pickup at twice the running frequency (100/120 Hz on a 2-pole "
                                   "generator, 50/60 Hz on a 4-pole one)")),
    CodeInfo("keyphasor_faulty", SANITY, _U, "the keyphasor pulse train has missing or extra pulses: the orders were "
             "tracked at a steady speed, phases relative to the first sample",
             "check the keyphasor probe's gap, trigger level and notch, or send speed_rpm instead",
             {_D: _KEYPHASOR_FAULTY, "take": "the take of bearings {bearings}: " + _KEYPHASOR_FAULTY}),
    # --- the model side (models.status and the checks beside it) ---
    CodeInfo("ood", REASON, _UI, "the recording is unlike the training data (OOD score above 1; above 3 far outside: "
             "inconclusive)", "a machine design, operating state or set-up the model does not know: read the "
             "evidence, compare with this machine's baseline",
             ("the recording is unlike the training data (OOD score {ood_score:.2f}; > 1 unusual, > "
             "{ood_inconclusive:g} far outside): another machine design, operating state or measurement set-up than "
             "the model knows")),
    CodeInfo("outside_training", REASON, _UI, "a feature lies outside the training data's range (far beyond it: "
             "inconclusive)", "check the units, the probe sensitivity and the stated clearance; otherwise a machine "
             "unlike the training family",
             {_D: _OUTSIDE + "a machine or measurement unlike the training family; the model has not seen this{more}",
             "attitude": _OUTSIDE + "the shaft does not sit where a plain oil-film journal bearing puts it — "
             "bearings of another type (tilting-pad, rolling-element), or the DC gaps, probe angles or rotation "
             "direction are wrong; the model knows plain journal bearings only{more}",
             "amplitude_above": _OUTSIDE + "check the units (µm vs mils ×25.4) and the probe sensitivity; the model "
             "has not seen this{more}",
             "per_clearance": _OUTSIDE + "check the stated bearing clearance, or a machine unlike the training "
             "family{more}"}),
    CodeInfo("scale", REASON, _UI, "the 1X vibration at a coupling bearing is far above or below the training data's "
             "typical level", "check the units (µm vs mils ×25.4) and the probe sensitivity",
             {"none": "no 1X vibration at bearing {bearing} ({amp} pk-pk) where the training data's typical is "
             "{typical}: check that the probes are connected and the data are not all zeros",
             "above": "1X vibration at bearing {bearing} is {amp} pk-pk, {factor:.0f}× above the training data's "
             "typical {typical}: the model has not seen machines vibrating like this — check the units (µm vs mils "
             "×25.4) and the probe sensitivity",
             "below": "1X vibration at bearing {bearing} is {amp} pk-pk, {factor:.0f}× below the training data's "
             "typical {typical}: the model has not seen machines vibrating like this — a different machine design or "
             "a very smooth-running one; read the evidence instead"}),
    CodeInfo("journals_near_centre", REASON, _U, "every journal sits near its bearing centre: sizes per clearance "
             "too small for a loaded rotor", "check the units, the probe sensitivity, the clearance (radial, µm) and "
             "that the DC readings are referenced to the bearing centre",
             ("every journal sits within {max_ecc_c:.3f} c of its bearing centre (eccentricities {ecc1_c:.3f}, "
             "{ecc2_c:.3f}, {ecc3_c:.3f}, {ecc4_c:.3f} at bearings 1–4): the rotor's weight holds at least one "
             "journal further off-centre than {limit_c:g} c in nearly every machine (in 22 of 719 held-out plants of "
             "the training family it did not), so the sizes per clearance are suspect — check the units and the "
             "probe sensitivity (numbers 10× too small read like this), the clearance (radial, in µm) and that the "
             "DC readings are referenced to the bearing centre")),
    CodeInfo("centreline_frame_turned", REASON, _U, "every journal's attitude angle is far off that of the "
             "training machines nearest this one (a plain journal bearing's), on one side: probes not at the angles "
             "given, or bearings unlike the training's",
             "check angle_deg, the rotation direction and the viewing end",
             ("at every bearing the shaft centreline sits {mean_offset_deg:+.0f}° off the attitude angle the "
             "training machines nearest this one held at its eccentricity ({bearings}; the angle from the load line, toward "
             "rotation; the reference: {reference}). Either the whole picture is turned, as when the probes do "
             "not sit at the angles given — check angle_deg (from horizontal +x toward vertical-up +y; 45/135 is "
             "the default for 8 channels), the rotation direction and the viewing end — or the bearings are "
             "unlike those of every machine the model was trained on (tilting-pad and linear bearings hold the "
             "journal near the load line; a model retrained for the plant's shaft line knows its bearings)")),
    CodeInfo("speed_ambiguous", REASON, _U, "the running speed was estimated from the spectrum and is in doubt (or "
             "chosen by the model among the speeds the spectrum allows)",
             "confirm the speed: give speed_rpm, speed_range_rpm or keyphasor_times_s",
             "{warning}"),
    CodeInfo("features_missing", REASON, _U, "features the model always had in training are missing here",
             "give an x/y probe pair at each bearing the model was trained with (coupling bearings 2 and 3 at "
             "least) and record at least 32 revolutions",
             {_D: _MISSING + _MISSING_PAIR, "motion": _MISSING + "record at least 32 revolutions for the motion "
             "type; " + _MISSING_PAIR}),
    CodeInfo("low_probability", REASON, _U, "no severity class is likely enough: the recording lies between classes",
             "recheck, or compare with this machine's baseline",
             ("no severity class is likely enough (highest probability {p_max:.0%} < {min_probability:.0%}): the "
             "recording lies between classes")),
    CodeInfo("far_band_probability", REASON, _U, "the model gives too much probability to bands two or more from its "
             "call", "recheck, or compare with this machine's baseline",
             ("the model gives {p_far:.0%} to {bands} — two or more bands from its call, more than the "
             "{max_far_probability:.0%} a confident verdict allows: recheck, or compare with this machine's baseline")),
    CodeInfo("far_band_interval", REASON, _U, "the Δ estimate's interval reaches a band two or more from the call",
             "recheck, or compare with this machine's baseline",
             ("the Δ estimate's {level:.0%} interval ({low:.3f}–{high:.3f}) reaches {bands} — two or more bands "
             "from the call: the Δ regressor does not rule out a gross error; recheck, or compare with this machine's "
             "baseline")),
    CodeInfo("below_alarm_threshold", REASON, _U, "misalignment is more likely than not but below the false-alarm "
             "threshold: called aligned", "recheck, or compare with this machine's baseline",
             ("misalignment is more likely than not ({p_misaligned:.0%}) but below the {threshold:.0%} the "
             "model needs to report it (set to keep false alarms on healthy machines at 5 %): called aligned — "
             "recheck, or compare with this machine's baseline")),
    CodeInfo("signature_above_call", REASON, _I, "outside the training family the coupling 2X/1X reads two or more "
             "bands above the model's call: no severity is given", "check the alignment or compare with this "
             "machine's baseline; a strong 2X has other causes too (two-pole rotor, crack, looseness, runout)",
             ("the model calls it {called}, but the coupling bearings' 2X/1X is {ratio_2x_1x:.2f}: the classic "
             "misalignment signature reads {read} (2X/1X ≥ {rule_cut:g}), two or more bands above the call, and the "
             "recording lies outside the machines the model was trained on, where its call is not to be trusted "
             "against the physics — no severity is given. Check the alignment (or compare with this machine's "
             "baseline); a strong 2X has other causes too: a two-pole rotor's asymmetry under gravity, a shaft "
             "crack, looseness, or runout (give the slow-roll vectors)")),
    CodeInfo("no_2x_signature", REASON, _U, "called misaligned, but the coupling bearings show no 2X",
             "compare with this machine's baseline, check the centreline, or re-record",
             {_D: _NO_2X.format(seen="{ratio_2x_1x:.3f}"), "not_measured": _NO_2X.format(seen="not measured")}),
    CodeInfo("static_offset_only", REASON, _U, "the misalignment call rests on the static offset between the "
             "coupling-end journals", "compare with this machine's cold or baseline journal positions",
             {_D: _OFFSET_LOWER + _OFFSET_AFTER, "aligned": _OFFSET_ALIGNED + _OFFSET_AFTER,
             "apart": _OFFSET_LOWER + _OFFSET_APART + _OFFSET_AFTER,
             "aligned_apart": _OFFSET_ALIGNED + _OFFSET_APART + _OFFSET_AFTER}),
    CodeInfo("offset_not_assessed", REASON, _U, "called aligned without the shaft-centreline position at the "
             "coupling bearings: a stationary offset is not ruled out",
             "give clearance_um and centre-referenced DC readings, or compare with this machine's baseline",
             ("called aligned without the shaft-centreline position at the coupling bearings (it needs the "
             "bearing clearance and DC probe readings referenced to the bearing centre; a raw gap is not a position): "
             "a stationary shaft-line offset shows mainly there and changes the vibration little, so it is not ruled "
             "out — give clearance_um and centre-referenced DC readings, or compare with this machine's baseline")),
    CodeInfo("class_delta_disagree", REASON, _U, "the severity classifier and the Δ regressor disagree; the Δ shown "
             "is clipped into the class's band", "recheck, or compare with this machine's baseline",
             ("the severity classifier and the Δ regressor disagree (the regressor's interval does not reach the "
             "class's band); the Δ shown is clipped into the class's band")),
    CodeInfo("bearing_set_untrained", REASON, _I, "none of the model's training probe sets lies within the "
             "recording's bearings", "add an x/y probe pair at a coupling bearing (3 tells the most) and send again",
             ("the probes the model can read are at {usable}{left_out}; the model was trained on the probe sets "
             "{trained_sets} and none of them lies within these, so it cannot judge this recording: add an x/y probe "
             "pair at a coupling bearing (3, the exciter's coupling end, tells the most) and send the recording "
             "again")),
    CodeInfo("bearing_set_uninformative", REASON, _I, "the probe set the model reads tells misalignment poorly on "
             "held-out plants", "add probes so that the recording has one of the model's good probe sets",
             ("the model reads {bearings}{via}, and from {probe_set} alone it tells misalignment poorly: on "
             "held-out plants macro-F1 {macro_f1:.2f} with {false_alarm:.1%} of the aligned machines called "
             "misaligned (a verdict needs ≥ {min_macro_f1:g} and ≤ {max_false_alarm:.0%}); add probes so that the "
             "recording has one of the sets {good_sets}")),
    CodeInfo("bearing_set_weak", REASON, _U, "the probe set the model reads gives more than the allowed false alarms "
             "on held-out plants", "probes at one of the model's good probe sets give a firmer verdict",
             ("the model reads {bearings}, and from {probe_set} it called {false_alarm:.1%} of the aligned "
             "machines of held-out plants misaligned (macro-F1 {macro_f1:.2f}; a confident verdict needs ≤ "
             "{max_false_alarm:.0%}): probes at one of the sets {good_sets} give a firmer one")),
    CodeInfo("bearing_numbering", REASON, _U, "numbered from the other end the recording is markedly more like the "
             "training machines", "check the numbering: 1 the generator's far end, 2 its coupling end, 3 the "
             "exciter's coupling end, 4 its far end",
             {_D: _NUMBERING.format(called="called {other_call} instead of {call}"),
             "same_call": _NUMBERING.format(called="called {call} either way")}),
    CodeInfo("separate_acquisitions", REASON, _U, "bearings 2 and 3 were recorded in separate acquisitions: the phase "
             "across the coupling is not measured", "record bearings 2 and 3 in one acquisition, or trend this "
             "machine's 2X/1X",
             {_D: _ACQ.format(said=""), "phase_read": _ACQ.format(said=_ACQ_READ + " — measure that phase to "
             "tell them apart"), "phase_read_same": _ACQ.format(said=_ACQ_READ + " — the call does not hinge on "
             "that phase")}),
    CodeInfo("reverse_2x", REASON, _U, "a misalignment call on a coupling 2X that whirls backward",
             "check the probe wiring and pickup; compare with this machine's baseline",
             ("called misaligned on a 2X that whirls backward at bearing {bearing} (reverse {reverse_per_forward:.1f} × "
             "forward): in the machines the model was trained on a coupling's or a two-pole rotor's 2X whirls "
             "forward. A 2X with its own phase on each probe cable (electrical pickup through a ground loop) or a "
             "probe wiring problem reads so; a strongly preloaded (flattened) orbit can too. Check the probe cabling "
             "and grounding (a record with the unit off the grid shows pickup that stays), or compare with this "
             "machine's baseline")),
    CodeInfo("startup_changed", REASON, _U, "called aligned, but the start-up's coupling-end centreline (its rise "
             "or its slow-roll position) changed since the asset's baseline start-up",
             "compare the two start-ups' Bode and centreline plots before accepting the verdict",
             ("called aligned, but the start-up changed since the asset's baseline start-up: {changes}. A moved "
             "bearing, a changed coupling or a rub changes a run-up so; compare the two start-ups' Bode and "
             "centreline plots before accepting the verdict")),
    CodeInfo("clearance_diametral", REASON, _U, "half the stated clearance makes the recording markedly more like the "
             "training machines", "check that clearance_um is the radial clearance (half the diametral one)",
             ("with half the stated clearance ({clearance}) the recording is markedly more like the machines the "
             "model was trained on (OOD score {ood_half:.2f} against {ood_score:.2f}); there it would be "
             "{class_half!r}. clearance_um is the radial clearance c, half the diametral one (bore minus journal): "
             "check which one was given")),
    CodeInfo("family_untrained", REASON, _U, "the machine's declared plant model is not a machine family the model "
             "was trained on (its card's training families): its call is not to be trusted on this design",
             "retrain for this plant (`rotordiag retrain --shaftline`, POST /models/retrain) or compare with this "
             "machine's baseline; check the asset's plant model",
             ("this machine is declared as {machine}, a family the model was not trained on (it was trained on "
              "{trained}): on a design it never saw its severity is not to be trusted, however sure it looks — retrain "
              "for this plant (rotordiag retrain --shaftline, POST /models/retrain) or compare with this machine's "
              "baseline")),
    CodeInfo("signature_contradicts_call", REASON, _UI, "called aligned while the coupling bearings' 2X/1X reads two or "
             "more bands higher on the rule of thumb: the verdict contradicts its own evidence (three bands, a 2X/1X "
             "of 2 or more beside aligned: no severity is shown)",
             "check the alignment or compare with this machine's baseline; a strong 2X has other causes too (two-pole "
             "rotor, crack, looseness, runout)",
             ("called {call}, but the coupling bearings' 2X/1X is {ratio:.2f}: the classic misalignment signature reads "
              "{rule_band} (2X/1X ≥ {rule_cut:g}), two or more bands above the call, so the verdict contradicts its own "
              "evidence. Check the alignment or compare with this machine's baseline; a strong 2X has other causes too "
              "(a two-pole rotor's asymmetry under gravity, a shaft crack, looseness, runout: give the slow-roll "
              "vectors)")),
    CodeInfo("attitude_outside_training", REASON, _U, "the clearance is not stated, but the direction of a journal's "
             "DC position in its bearing (its attitude angle, which needs no clearance) lies outside the training "
             "machines'", "state clearance_um and check that the DC readings are referenced to the bearing centre; "
             "bearings unlike plain cylindrical ones (tilting pads) read so",
             ("the clearance is not stated, so the shaft-centreline features are missing; but the direction of the "
              "journal's DC position in its bearing, which needs no clearance, lies outside the machines the model was "
              "trained on ({where}; the attitude angle from the load line, toward rotation). A bearing unlike the "
              "training's plain cylindrical ones (tilting pads hold the journal near the load line), or DC readings not "
              "referenced to the bearing centre, read so: the model's call is not to be trusted on this machine — "
              "state clearance_um and check the DC reference, or compare with this machine's baseline")),
    CodeInfo("common_mode", REASON, _U, "a 1X / 2X common to every probe (electrical pickup) was removed before the "
             "verdict", "check the probe cabling and grounding and re-record before acting",
             {_D: _COMMON_MODE + " ({call!r}, as with it)" + _COMMON_MODE_ACT, "changed": _COMMON_MODE + " ({call!r}; as recorded, with it, the "
              "class would be {call_as_sent!r})" + _COMMON_MODE_ACT}),
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
    """The catalogue as a Markdown table (code, found by, status, meaning, what to do, message template), as
    docs/pipeline.md holds it; a code with variants lists each template after its variant's name."""
    rows = ["| code | found by | status | meaning | what to do | message (template) |", "|---|---|---|---|---|---|"]
    for e in _ENTRIES:
        where = "sanity check" if e.kind == SANITY else "model side"
        templates = e.templates
        message = ("<br>".join(f"*{v}*: `{t}`" for v, t in templates.items()) if len(templates) > 1
                   else f"`{templates[DEFAULT_VARIANT]}`")
        rows.append(f"| `{e.code}` | {where} | {' / '.join(e.statuses)} | {e.meaning} | {e.action} | {message} |")
    return "\n".join(rows) + "\n"
