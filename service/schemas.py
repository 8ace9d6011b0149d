"""Request and response models of the HTTP API (units in field names or descriptions, bounded lengths)."""
from __future__ import annotations

import datetime as dt
import re
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, StringConstraints, field_validator

from rotordiag.core.input_bounds import CLEARANCE_RANGE_UM, SAMPLE_RATE_RANGE_HZ, SPEED_RANGE_RPM
from rotordiag.core.notes import NOTES
from rotordiag.core.reasons import CATALOGUE, known_code
from rotordiag.models.headline import ACTIONS, URGENCIES
from rotordiag.simulator.dataset.spec import DESIGN_MECHANISMS

#: Bounds on what one request may carry (the body-size middleware bounds the bytes as well).
MAX_CHANNELS = 8                # 4 bearings x 2 probes
MAX_POINTS = 262_144            # samples per channel (16 s at 16 kHz)
MAX_KEYPHASOR_PULSES = 100_000
MAX_LABEL_LEN = 128
#: Values (numbers, strings, ...) one JSON recording may hold: every sample, every pulse, and a margin for the rest;
#: counted before the body is decoded (``features.safe_io.count_json_values``), so no body makes a worker allocate
#: more than a full recording needs.
MAX_RECORD_VALUES = MAX_CHANNELS * MAX_POINTS + MAX_KEYPHASOR_PULSES + 4096
#: Values one POST /diagnose/batch body may hold (two full recordings' worth; split larger batches).
MAX_BATCH_VALUES = 2 * MAX_RECORD_VALUES

FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]

_ASSET_ID_RE = re.compile(r"^[A-Za-z0-9._:-]+$")


def _check_asset_id(value: str) -> str:
    if value in (".", ".."):
        raise ValueError("asset_id may not be '.' or '..' (it becomes a path segment of /assets/{asset_id}/...); "
                         "name the machine train, e.g. unit-3-gen-exc")
    if not _ASSET_ID_RE.match(value):
        raise ValueError("asset_id may contain only letters, digits and . _ : - (it becomes part of the URL "
                         "/assets/{asset_id}/history, so no '/', spaces or other characters)")
    return value


#: An asset identifier: it is a path segment of ``GET /assets/{asset_id}/history``, so no ``/``.
AssetId = Annotated[str, StringConstraints(min_length=1, max_length=MAX_LABEL_LEN), AfterValidator(_check_asset_id)]


class _Strict(BaseModel):
    """Request bodies: unknown keys refused, and no coercion (``false`` is not a number, ``0`` not a boolean)."""

    model_config = ConfigDict(extra="forbid", strict=True)


class SlowRollIn(_Strict):
    """A slow-roll (runout) vector of one probe, to be subtracted from its fitted order."""

    order: Literal[1, 2] = Field(..., description="Order: 1 (1X) or 2 (2X).")
    amp_um_pp: FiniteFloat = Field(..., ge=0, le=10_000, description="Slow-roll amplitude, micrometres peak-to-peak.")
    phase_deg: FiniteFloat = Field(..., ge=-360, le=720, description="Slow-roll phase lag, degrees, from the same "
                                   "keyphasor reference as `keyphasor_times_s`.")


class ChannelIn(_Strict):
    """One proximity probe."""

    bearing: int = Field(..., ge=1, le=4, description="Bearing number 1-4 (MODEL.md: 1, 2 generator; 3, 4 exciter; "
                         "2 and 3 face each other across the coupling).", examples=[2])
    angle_deg: FiniteFloat = Field(
        ..., ge=-360.0, le=360.0,
        description="Probe mounting angle in degrees, measured from the horizontal x axis towards vertical-up y "
        "(e.g. 45 and 135 for an XY pair at 45 degrees either side of top dead centre).", examples=[45.0])
    units: str = Field(..., min_length=1, max_length=16,
                       description="Units of `data`: `um` (micrometres), `mm`, `m` or `mil` (thousandths of an inch, 25.4 µm).",
                       examples=["um"])
    data: list[FiniteFloat] = Field(
        ..., min_length=1, max_length=MAX_POINTS,
        description=f"Probe gap signal in `units`, uniformly sampled at `sample_rate_hz`; at most {MAX_POINTS} samples; "
        "all channels must have the same length. Finite numbers only.")
    slow_roll: list[SlowRollIn] | None = Field(
        None, max_length=2, description="Optional slow-roll (runout) 1X/2X vectors of this probe, subtracted as "
        "vectors from the fitted orders; needs `keyphasor_times_s` (the phases are keyphasor-referenced).")


class RecordingIn(_Strict):
    """Waveforms of one measurement: XY probe pairs at one or more bearings."""

    sample_rate_hz: FiniteFloat = Field(..., ge=SAMPLE_RATE_RANGE_HZ[0], le=SAMPLE_RATE_RANGE_HZ[1],
                                        description="Sample rate of every channel, Hz.",
                                        examples=[4096.0])
    speed_rpm: FiniteFloat | None = Field(
        None, ge=SPEED_RANGE_RPM[0], le=SPEED_RANGE_RPM[1],
        description="Running speed, r/min (the control system's reading or the nominal speed will do: the orders "
                    "are locked to the signals' synchronous lines within ±1 % of it, and the speed used is in the "
                    "answer). Omit to estimate it from the signals (or from `keyphasor_times_s`).",
        examples=[3000.0])
    keyphasor_times_s: (Annotated[list[FiniteFloat], Field(max_length=MAX_KEYPHASOR_PULSES)]
                        | Annotated[list[Annotated[list[FiniteFloat], Field(max_length=MAX_KEYPHASOR_PULSES)]],
                                    Field(min_length=1, max_length=4)]
                        | None) = Field(
        None,
        description="Once-per-revolution keyphasor pulse times, seconds from the first sample, increasing. With "
        "`acquisitions`, one list per acquisition (in the order listed, each on its take's clock): the phases of "
        "every take are then referenced to the same keyphasor mark and the phase differences across the takes are "
        f"measured. At most {MAX_KEYPHASOR_PULSES} pulses in all.")
    speed_range_rpm: list[FiniteFloat] | None = Field(
        None, min_length=2, max_length=2,
        description="[min, max] of the running speed, r/min, when it is not known exactly (the machine's nominal "
        "speed, e.g. [2900, 3100] for a 3000 r/min generator): the speed estimated from the signals is sought only "
        "there (a whirl or whip line is then not taken for 1X). 0 < min < max; `speed_rpm`, when given, must lie "
        "inside.", examples=[[2900.0, 3100.0]])
    clearance_um: FiniteFloat | None = Field(
        None, ge=CLEARANCE_RANGE_UM[0], le=CLEARANCE_RANGE_UM[1],
        description="Radial bearing clearance c, micrometres; when given, amplitudes are also reported divided by c "
        "and the offset δ = Δ·c is reported in micrometres.", examples=[350.0])
    dc_removed: bool = Field(
        False, description="The channels' DC part is no shaft position (AC-coupled acquisition): the shaft "
        "centreline is not read, and a stationary shaft-line offset is not assessed. Channels that all average to "
        "zero are read so anyway.")
    acquisitions: (Annotated[str, StringConstraints(max_length=32)]
                   | Annotated[list[Annotated[list[Annotated[int, Field(ge=1, le=4)]], Field(min_length=1, max_length=4)]],
                               Field(min_length=1, max_length=4)]
                   | None) = Field(
        None, description="Groups of bearings sampled together, when the channels come from separate acquisitions "
        "(takes), e.g. `\"1,2;3,4\"` or `[[1, 2], [3, 4]]`: the phase differences between bearings of different "
        "takes are then not measured, and with bearings 2 and 3 in different takes the verdict is never confident "
        "(`separate_acquisitions`) — unless each take carries its keyphasor (`keyphasor_times_s`, one list per "
        "acquisition). Leave it out when every channel was sampled together.", examples=["1,2;3,4"])
    asset_id: AssetId | None = Field(
        None, description="Identifier of the machine train; when given the diagnosis is stored for GET /assets/{id}/history.",
        examples=["unit-3-gen-exc"])
    plant: str | None = Field(
        None, min_length=1, max_length=MAX_LABEL_LEN,
        description="Free-text plant or unit label stored with the asset history.", examples=["Riverside unit 3"])
    channels: list[ChannelIn] = Field(
        ..., min_length=1, max_length=MAX_CHANNELS,
        description=f"Probe channels, at most {MAX_CHANNELS} (two probes per bearing).")


#: what ``plant_model`` (the ``POST /diagnose`` query parameter, the JSON body's and a batch record's field) says
PLANT_MODEL_DESCRIPTION = (
    "The machine's plant model, `default` (MODEL.md's plant) or a preset (`gen50_2pole`, `gen200_2pole`, "
    "`gen600_2pole`, `gen600_4pole`; `train:NAME`: its finite-element train). A machine family the model was not "
    "trained on is never given a confident verdict (`family_untrained`); the answer's `answered_by` says which "
    "plant model the recording was judged as.")
#: the bounds of ``plant_model`` wherever it is given
PLANT_MODEL_MAX_LEN = 64


class DiagnoseRequest(RecordingIn):
    """Body of POST /diagnose (JSON form)."""

    model_config = ConfigDict(extra="forbid", strict=True, json_schema_extra={"examples": [{
        "sample_rate_hz": 4096.0, "speed_rpm": 3000.0, "clearance_um": 350.0, "asset_id": "unit-3",
        "channels": [
            {"bearing": 2, "angle_deg": 45.0, "units": "um", "data": [10.1, 12.3, 9.8, 7.7]},
            {"bearing": 2, "angle_deg": 135.0, "units": "um", "data": [3.1, 5.0, 6.2, 4.4]},
        ]}]})

    plant_model: str | None = Field(None, min_length=1, max_length=PLANT_MODEL_MAX_LEN,
                                    description=PLANT_MODEL_DESCRIPTION + " As the query parameter `plant_model`; "
                                    "given in both, they must agree.", examples=["gen600_2pole"])


class BatchRecord(DiagnoseRequest):
    """One record of POST /diagnose/batch: a recording as for POST /diagnose, with what the query parameters of a
    single upload say about it (each record can be a different recording of a different time)."""

    model_config = ConfigDict(extra="forbid", strict=True)

    recorded_at: str | None = Field(None, min_length=10, max_length=40,
                                    description="When the recording was made (ISO 8601; UTC when no offset): orders "
                                    "the asset's trend, so a backfilled recording lands in its place.",
                                    examples=["2025-01-14T10:00:00Z"])
    tags: str | None = Field(None, max_length=4000, description="Operating state at the recording: "
                             "`load_mw=350;field_current_a=1210;stator_temp_c=71`.")
    note: str | None = Field(None, min_length=1, max_length=2000,
                             description="An event note stored with the recording, e.g. `aligned on 2026-03-02`.")


class BatchRequest(_Strict):
    """Body of POST /diagnose/batch."""

    records: list[BatchRecord] = Field(..., min_length=1, max_length=10_000,
                                           description="Recordings to diagnose (the server caps the count; "
                                           "see ROTORDIAG_MAX_BATCH_RECORDS).")


class BatchEnvelope(_Strict):
    """What a POST /diagnose/batch body is checked against before its records: the list and its length. Each record
    is then validated on its own as a ``DiagnoseRequest``, so one bad record is that record's 422, not the batch's."""

    records: list[dict[str, Any]] = Field(..., min_length=1, max_length=10_000)


class ErrorOut(BaseModel):
    """Error body: what was wrong and what to fix."""

    detail: Any = Field(..., description="A message, or FastAPI's list of {loc, msg, type} for schema errors.")


# --- jobs -----------------------------------------------------------------------------------

JobStatus = Literal["queued", "running", "succeeded", "failed", "interrupted", "cancelled"]


class JobOut(BaseModel):
    """A job's state."""

    id: str = Field(..., description="Job identifier (UUID).")
    kind: Literal["dataset", "retrain"] = Field(..., description="`dataset` (POST /datasets) or `retrain` "
                                                "(POST /models/retrain).")
    status: JobStatus = Field(..., description="`interrupted`: the server stopped while it ran; `cancelled`: "
                              "stopped by POST /jobs/{id}/cancel; POST /jobs/{id}/resume continues either.")
    progress: float = Field(..., ge=0, le=1, description="Fraction done, 0-1 (a retrain's stages weighted by "
                            "their expected time: models.plant_retrain.StagedProgress).")
    stage: str = Field(..., description="Current stage, e.g. `simulating`, `features`, `training`, `held-out "
                       "simulation`, `report`.")
    eta_s: float | None = Field(None, ge=0, description="While running: seconds left, estimated as the time since "
                                "the attempt started × (1 − progress) / progress; null before 1 % or when not running.")
    message: str = Field(..., description="Human-readable progress note.")
    params: dict[str, Any] = Field(..., description="The request that created the job.")
    result: dict[str, Any] | None = Field(None, description="Dataset summary or new model version and evaluation.")
    error: str | None = Field(None, description="Why the job failed.")
    attempts: int = Field(..., description="How many times the job has been started (resumes and takeovers count).")
    created_at: dt.datetime = Field(..., description="When the job was created (UTC).")
    started_at: dt.datetime | None = Field(..., description="When its last attempt started (UTC).")
    finished_at: dt.datetime | None = Field(..., description="When it last finished, failed or was interrupted (UTC).")
    updated_at: dt.datetime = Field(..., description="Last progress update (UTC).")
    lease_owner: str | None = Field(None, description="The replica that runs (or last ran) the job.")
    lease_expires_at: dt.datetime | None = Field(
        None, description="While it runs: when the holder's lease ends unless renewed (UTC); past it, another "
        "replica takes the job over.")


# --- assets ---------------------------------------------------------------------------------

class ChangeQuantityOut(BaseModel):
    """One change quantity against the baseline (largest over the bearings)."""

    value: float | None = Field(None, description="Largest value over the bearings (µm, µm pk-pk or 1: see `unit`).")
    unit: str = Field(..., description="Unit of `value` and `threshold`.")
    bearing: int | None = Field(None, description="Bearing of the largest value.")
    threshold: float | None = Field(None, description="Alarm threshold (null: not alarmed on).")
    value_per_c: float | None = Field(None, description="`value` as a fraction of the radial clearance, when known.")
    threshold_per_c: float | None = Field(None, description="Alarm threshold on `value_per_c` (both must be exceeded).")
    exceeded: bool = Field(..., description="Over the threshold(s).")


class ThresholdsBasisOut(BaseModel):
    """Whether an asset's 1X, 2X and centreline change thresholds are its own or the fleet-wide ones."""

    basis: Literal["own", "fleet"] = Field(..., description="`own`: set from the spread of the asset's baseline "
                                           "recordings (k × their largest leave-one-out difference, at least a "
                                           "probe system's resolution); `fleet`: the shipped thresholds, fitted on "
                                           "simulated machines of many sizes.")
    reason: Literal["own_repeatability", "too_few_recordings", "recordings_not_comparable", "nothing_measured"] = Field(
        ..., description="Why (`models.change.BASIS_REASONS`): `too_few_recordings` below `needed`; "
        "`recordings_not_comparable` when they are more than 10 % apart in speed; `nothing_measured` when they carry "
        "no 1X/2X phase (no keyphasor) and no centreline.")
    n_recordings: int = Field(..., description="Recordings the baseline is made of.")
    needed: int = Field(..., description="Recordings at one operating condition the asset's own thresholds need.")
    margin: float | None = Field(None, description="With `own`: the factor k on the largest difference between the "
                                 "baseline's recordings.")


class BaselineRecordingOut(BaseModel):
    """One recording an asset's baseline is made of."""

    diagnosis_id: int = Field(..., description="The stored diagnosis (GET /assets/{id}/history).")
    speed_rpm: float | None = Field(None, description="Its speed, r/min.")
    recorded_at: str | None = Field(None, description="When it was recorded (UTC; when stored, if not given).")
    added_at: str | None = Field(None, description="When it was added to the baseline (UTC).")


class BaselineSectionOut(BaseModel):
    """Whether a baseline was used for this answer, and what changed since it."""

    used: bool = Field(..., description="True when the recording was compared with the asset's baseline.")
    compared: bool = Field(..., description="Same as `used` (false also when the speed is too far from the baseline's).")
    message: str = Field(..., description="One sentence: no baseline / not compared and why / changed or not.")
    set_at: str | None = Field(None, description="When the baseline was set (UTC, ISO 8601).")
    speed_rpm: float | None = Field(None, description="Speed of the baseline, r/min.")
    model_version: str | None = Field(None, description="Model version that diagnosed the baseline recording(s).")
    source: str | None = Field(None, description="`recording`, `diagnosis` or `auto`.")
    changed: bool | None = Field(None, description="True when a change quantity is over its alarm threshold "
                                 "(null when not compared).")
    exceeded: list[str] = Field(default_factory=list, description="The quantities over their thresholds.")
    quantities: dict[str, ChangeQuantityOut] = Field(default_factory=dict, description="`1x_change`, `2x_change`, "
                                                     "`dc_shift`, `orbit_ellipticity_change`, `orbit_2x_1x_change`.")
    values: dict[str, float | None] = Field(default_factory=dict, description="Every change feature "
                                            "(features.change_features: per bearing and probe direction).")
    speed_change_frac: float | None = Field(None, description="speed / baseline speed − 1.")
    thresholds_basis: ThresholdsBasisOut | None = Field(
        None, description="Whether the 1X, 2X and centreline thresholds are the asset's own (≥ 3 baseline "
        "recordings) or the fleet-wide ones, and why (null: no baseline).")
    notes: list[str] = Field(default_factory=list, description="Why some change quantities are missing, and where "
                             "the thresholds come from (warning codes `change_thresholds_own` / "
                             "`change_thresholds_fleet`).")


class AlarmEvent(BaseModel):
    """A trend alarm raised or cleared."""

    time: dt.datetime = Field(..., description="Time of the diagnosis that raised or cleared it (UTC).")
    event: Literal["raised", "cleared"] = Field(..., description="What happened.")
    diagnosis_id: int = Field(..., description="The diagnosis.")
    quantities: list[str] = Field(default_factory=list, description="Quantities over their thresholds (raised).")


class BaselineOut(BaseModel):
    """An asset's baseline."""

    model_config = ConfigDict(protected_namespaces=())

    asset_id: str = Field(..., description="The asset.")
    set_at: str | None = Field(None, description="When it was set (UTC).")
    recorded_at: str | None = Field(None, description="When its (last) recording was diagnosed (UTC).")
    source: str = Field(..., description="`recording`, `diagnosis` or `auto`.")
    diagnosis_ids: list[int] = Field(..., description="Stored diagnoses it was made of.")
    speed_rpm: float | None = Field(None, description="Its speed, r/min; recordings are compared within ±5 %.")
    model_version: str = Field(..., description="Model version that diagnosed its recording(s).")
    signature: dict[str, Any] | None = Field(None, description="The 1X/2X vectors, centreline and orbit shape per "
                                             "bearing (features.signature).")
    repeatability: dict[str, Any] | None = Field(
        None, description="For a baseline of ≥ 3 recordings at one operating condition: the asset's own 1X, 2X and "
        "centreline thresholds from how much those recordings differ from each other (`thresholds`, `spread`, "
        "`n_recordings`, `margin`); they replace the shipped ones for this asset. Null otherwise. Recomputed "
        "whenever a recording is added to or removed from the baseline.")
    n_recordings: int = Field(1, description="Recordings the baseline is made of (averaged as vectors).")
    recordings: list[BaselineRecordingOut] | None = Field(
        None, description="Those recordings (add: POST /assets/{id}/baseline/recordings, remove: DELETE "
        "/assets/{id}/baseline/recordings/{diagnosis_id}); empty for a baseline set before they were kept one by one.")
    thresholds_basis: ThresholdsBasisOut | None = Field(
        None, description="Whether its change thresholds are the asset's own or the fleet-wide ones, and why.")


class AssetBaselineOut(BaseModel):
    """GET /assets/{id}/baseline: the baseline, or the automatic proposal when none is set."""

    asset_id: str = Field(..., description="The asset.")
    baseline: BaselineOut | None = Field(None, description="The baseline (null: none set).")
    proposal: dict[str, Any] | None = Field(None, description="When none is set: the automatic proposal "
                                            "(`diagnosis_ids`, `speed_rpm`) or why there is none (`reason`).")
    thresholds: dict[str, float | None] = Field(..., description="The alarm thresholds in force.")
    edited_thresholds: dict[str, float | None] = Field(..., description="This asset's edits of them.")
    thresholds_origin: dict[str, str] = Field(
        default_factory=dict, description="Where each threshold in force comes from: `shipped` "
        "(models/default/change_thresholds.json), `repeatability` (this asset's own, from its baseline of ≥ 3 "
        "recordings) or `edited`.")


class ThresholdsIn(_Strict):
    """PUT /assets/{id}/thresholds: alarm thresholds to override (null: do not alarm on it)."""

    thresholds: dict[str, float | None] = Field(..., description="Change-feature name → threshold, e.g. "
                                                "`{\"dc_shift_um\": 25}`; `{}` restores the shipped thresholds.")


class ProbeConfigIn(_Strict):
    """PUT /assets/{id}/probes: the asset's probe configuration, used by every upload (binary or multipart)
    that names the asset; each field as the /diagnose query parameter of the same name."""

    channel_map: str | None = Field(None, min_length=1, max_length=2000, description="Probe columns by name, "
                                    "`GEN DE X=b2@45;GEN DE Y=b2@135;…` (or `bearings`/`angles_deg`).")
    bearings: str | None = Field(None, max_length=64, pattern=r"^[0-9, ]*$",
                                 description="Bearing of each channel in file order, e.g. `2,2,3,3`.")
    angles_deg: str | None = Field(None, max_length=256, description="Probe angle of each channel in file order.")
    units: str | None = Field(None, min_length=1, max_length=16, description="`um`, `mm`, `m`, `mil`, `V` or `mV`.")
    sensitivity: str | None = Field(None, min_length=1, max_length=32, description="For V/mV: as the datasheet "
                                    "states it, `200 mV/mil`, `7.87 V/mm`, `7.87 mV/um`.")
    gap_voltage_v: float | None = Field(None, ge=-100, le=100, description="For V/mV: the DC gap voltage, V.")
    keyphasor_channel: str | None = Field(None, min_length=1, max_length=64, description="The keyphasor column.")
    rotation: Literal["ccw", "cw"] | None = Field(None, description="Shaft rotation seen from `viewed_from`.")
    viewed_from: Literal["driver", "non-driver"] | None = Field(None, description="The end the angles and the "
                                                                 "rotation are seen from.")
    clearance_um: float | None = Field(None, ge=CLEARANCE_RANGE_UM[0], le=CLEARANCE_RANGE_UM[1],
                                       description="Radial bearing clearance c, µm (not the diametral one).")
    speed_range_rpm: str | None = Field(None, min_length=3, max_length=40, description="The machine's speed band "
                                        "around its rated speed, `lo,hi` r/min (e.g. `2950,3050`): where the "
                                        "running speed is looked for when an upload gives none.")
    model_version: str | None = Field(None, min_length=1, max_length=128, description="The registered model "
                                      "version this asset's uploads are diagnosed with (default: the active one).")
    plant_model: str | None = Field(None, min_length=1, max_length=64, description="The asset's plant model: a "
                                    "preset of `rotordiag plant` (`gen50_2pole`, `gen200_2pole`, `gen600_2pole`, "
                                    "`gen600_4pole`) or `default` (MODEL.md's plant); its Campbell diagram is drawn "
                                    "under the asset's start-up plots.")
    plant_shaftline: dict[str, Any] | None = Field(None, description="Instead of `plant_model`: the asset's shaft "
                                                   "line, the tables of `rotordiag plant from-shaftline` (as the "
                                                   "retrain job's `shaftline`).")


class ProbeConfigOut(BaseModel):
    """GET/PUT /assets/{id}/probes."""

    asset_id: str = Field(..., description="The asset.")
    probes: dict[str, Any] = Field(..., description="The stored fields (those not set are left out).")
    updated_at: dt.datetime | None = Field(None, description="When it was set (UTC).")


class AssetProbesSection(BaseModel):
    """In a /diagnose answer: the asset's stored probe configuration and what of it this upload used."""

    asset_id: str = Field(..., description="The asset whose configuration it is.")
    used: dict[str, Any] = Field(..., description="The stored fields this upload was read with.")
    overridden_by_upload: list[str] = Field(..., description="Groups (`layout`, `units`, `sensitivity`, "
                                            "`gap_voltage`, `keyphasor`) the upload gave itself instead.")


class AssetPoint(BaseModel):
    """One stored diagnosis of an asset."""

    id: int | None = Field(None, description="Diagnosis id (for POST /assets/{id}/baseline?diagnosis_id=).")
    alarm: bool | None = Field(None, description="Trend alarm state after this diagnosis: true changed since the "
                               "baseline, false compared and unchanged, null not compared.")
    change: dict[str, Any] | None = Field(None, description="The comparison with the baseline (as `baseline` in the "
                                          "/diagnose answer, without evidence), when compared.")

    time: dt.datetime = Field(..., description="When the diagnosis was made (UTC).")
    severity: str = Field(..., description="Severity class.")
    misalignment: float | None = Field(None, description="Estimated Δ = δ/c (non-dimensional).")
    misalignment_low: float | None = Field(None, description="Lower end of the Δ interval.")
    misalignment_high: float | None = Field(None, description="Upper end of the Δ interval.")
    speed_rpm: float | None = Field(None, description="Running speed used, r/min.")
    ood: bool | None = Field(None, description="True when the signals looked unlike the training data.")
    model_version: str = Field(..., description="Model version that made the diagnosis.")
    plant: str | None = Field(None, description="Plant label sent with the diagnosis.")
    recorded_at: dt.datetime | None = Field(None, description="When the recording was made, as given with it (UTC; "
                                            "null: not given).")
    trend_time: dt.datetime | None = Field(None, description="Where the point sits on the trend: `recorded_at`, "
                                           "else `time`; the points are ordered by it.")
    tags: dict[str, Any] | None = Field(None, description="Operating state at the recording (`load_mw`, "
                                        "`field_current_a`, temperatures, ...), as given with it.")
    note: str | None = Field(None, description="Event note given with the recording (e.g. `aligned on ...`).")
    key_features: dict[str, Any] = Field(..., description="Key features of the diagnosis (name -> value, units in name).")
    amplitudes_um_pp: dict[str, float | None] = Field(
        default_factory=dict,
        description="1X and 2X orbit major axes of each bearing diagnosed, micrometres peak-to-peak "
        "(`b{n}_1x_major_um_pp`, `b{n}_2x_major_um_pp`), for trend plots.")


class AssetHistory(BaseModel):
    """Trend of an asset's diagnoses, oldest first."""

    asset_id: str = Field(..., description="The asset.")
    site: str | None = Field(None, description="Where it sits (PUT /assets/{id}/hierarchy).")
    unit: str | None = Field(None, description="Its unit at the site.")
    train: str | None = Field(None, description="Its machine train.")
    count: int = Field(..., description="Number of points returned.")
    points: list[AssetPoint] = Field(..., description="Diagnoses, oldest first.")
    alarms: list[AlarmEvent] = Field(default_factory=list, description="Trend alarms raised and cleared among "
                                     "these points, oldest first.")


# --- health ---------------------------------------------------------------------------------

class HealthOut(BaseModel):
    """Liveness and readiness."""

    status: Literal["ok", "starting", "degraded"] = Field(
        ..., description="`starting` until a diagnosis worker has loaded and checked the active model; `degraded` "
        "when no model can be loaded or its checksum is unknown, the database cannot be read and written, or the "
        "data disk is nearly full (`detail` says which); `ok` otherwise. Anything but `ok` answers 503.")
    version: str = Field(..., description="Code version.")
    database: bool = Field(..., description="The database read a table and took a write.")
    disk_free_mb: float | None = Field(None, description="Free space on the disk holding the data directory, MiB.")
    model_version: str | None = Field(None, description="Active model version, if any.")
    model_sha256: str | None = Field(None, description="SHA-256 of the model file the diagnosis workers (or the "
                                     "server, without workers) hold for `model_version`; checked at least every 5 s.")
    detail: str = Field("", description="What is wrong when degraded.")
    replica: str = Field("", description="This API process's name among the replicas sharing the database "
                         "(ROTORDIAG_REPLICA_ID); each replica answers for itself.")
    jobs_held: int = Field(0, description="Jobs this replica is running (claimed from the database).")


# --- diagnosis output -------------------------------------------------------------------------

class FeatureContributionOut(BaseModel):
    """A feature that drove the verdict."""

    name: str = Field(..., description="Feature name (units in the name, e.g. `_um`, `_deg`; ratios unitless).")
    value: float | None = Field(None, description="Its value in this recording (null: not measurable here).")
    reference: float | None = Field(None, description="Its training median.")
    contribution: float | None = Field(None, description="Drop in the probability of the predicted class when this "
                                       "feature alone is set to its training median (positive: pushed toward the verdict).")


class BearingOut(BaseModel):
    """Key features of one bearing."""

    bearing: int = Field(..., description="Bearing number 1-4.")
    probe_angles_deg: list[float] = Field(..., description="The two probes' mounting angles, degrees from "
                                          "horizontal +x toward vertical +y.")
    clearance_um: float | None = Field(None, description="Radial clearance used, µm (null: unknown).")
    clearance_mil: float | None = Field(None, description="`clearance_um` in mils, when `output_units=mil`.")
    features: dict[str, float | None] = Field(
        ..., description="This bearing's features by name (`b{n}_...`; units in the names: `_um_pp` micrometres "
        "peak-to-peak, `_deg` degrees, `_per_c` divided by the clearance, `_ratio`/`_frac` unitless; "
        "null when not measurable). Definitions: docs/features.md.")


class OodFindingOut(BaseModel):
    """One feature outside the range of the model's training data (``models.estimators.FeatureEnvelope``)."""

    feature: str = Field(..., description="Feature name (units in the name; `b{n}_attitude_deg`: shaft centreline "
                         "attitude angle, `b{n}_attitude_offset_deg`: that angle minus a plain short journal "
                         "bearing's at the same eccentricity).")
    value: float | None = Field(None, description="This recording's value.")
    train_min: float | None = Field(None, description="Smallest value in the training data.")
    train_max: float | None = Field(None, description="Largest value in the training data.")
    side: Literal["below", "above"] = Field(..., description="Which side of the training range the value is on.")
    factor: float | None = Field(None, description="How many times beyond the range (amplitudes and ratios; "
                                 "null for angles).")
    excess_spreads: float | None = Field(None, description="Distance beyond the range in the feature's training "
                                         "spread (5-95 % range, log10 for amplitudes and ratios).")


class ReasonOut(BaseModel):
    """Why a verdict is not `confident`."""

    code: str = Field(..., description="Stable identifier: one of the catalogue's codes (`rotordiag.core.reasons`; "
                      "docs/pipeline.md's reason table says what each means and what to do). A physics sanity check's "
                      "code is also a reason: `fail` makes it `inconclusive`, `warn` `uncertain`.",
                      json_schema_extra={"enum": list(CATALOGUE)})
    status: Literal["uncertain", "inconclusive"] = Field(..., description="What this reason alone makes of the verdict.")
    message: str = Field(..., description="What was found and what to check: the code's message template in the "
                         "catalogue (docs/pipeline.md's reason table) filled with this recording's values, its lengths "
                         "in `output_units`.")
    action: str | None = Field(None, description="What to do, the same for every answer with this code: the "
                               "catalogue's (`rotordiag.core.reasons`; docs/pipeline.md's reason table).")

    @field_validator("code")
    @classmethod
    def _in_catalogue(cls, v: str) -> str:
        if not known_code(v):
            raise ValueError(f"reason code {v!r} is not in the catalogue (rotordiag.core.reasons)")
        return v


class EvidenceOut(BaseModel):
    """One measured signature, independent of the ML model."""

    scope: str = Field(..., description="`bearing N` or `coupling 2–3`.")
    name: str = Field(..., description="What is measured, e.g. `1X x`, `2X/1X`, `1X phase difference y`, "
                      "`orbit shape`, `shaft centreline`.")
    value: str = Field(..., description="The measurement with units (amplitudes µm peak-to-peak, phase lag in degrees).")
    meaning: str = Field(..., description="What it usually means.")
    number: float | None = Field(None, description="The main number (µm pk-pk, ratio, degrees or eccentricity ratio).")


class HeadlineOut(BaseModel):
    """What to do about the machine, in one sentence (``models.headline``)."""

    action: Literal[tuple(ACTIONS)] = Field(  # type: ignore[valid-type]
        ..., description="What to do: " + "; ".join(f"`{k}` — {v}" for k, v in ACTIONS.items()) + ".")
    urgency: Literal[URGENCIES] = Field(  # type: ignore[valid-type]
        ..., description="How soon: `none`, `before_acting` (check before reading the verdict), `routine`, "
        "`next_outage`, `soon`.")
    text: str = Field(..., description="The sentence, lengths in the answer's `output_units`.")
    show_severity: bool = Field(True, description="False when the measurement itself is in doubt (units or "
                                "physics checks failed, or no verdict): then no severity is to be shown.")


class AnsweredByOut(BaseModel):
    """Which model answered and which plant model the recording was judged as (``models.families.answered_by``)."""

    model_config = ConfigDict(protected_namespaces=())

    model_version: str | None = Field(..., description="The registered model version that answered.")
    training_families: list[str] = Field(..., description="The machine families its card says it was trained on "
                                         "(`lumped:default`, `lumped:preset:gen600_2pole`, `train:preset:…`); empty "
                                         "when the card records none.")
    training_families_text: list[str] = Field(..., description="The same in words.")
    retrained_for: str | None = Field(..., description="For a model retrained for one plant (`rotordiag retrain`, "
                                      "`POST /models/retrain`): that plant; null for the shipped or an ordinary model.")
    plant_model: str | None = Field(..., description="The machine family the recording was judged as (the declared "
                                    "plant model); null when none was declared.")
    plant_model_text: str | None = Field(..., description="The same in words.")
    declared_by: Literal["asset", "request", "command line", "given"] | None = Field(
        ..., description="Who declared it: `asset` (its stored plant model, PUT /assets/{id}/probes), `request` "
        "(`?plant_model=`, a JSON body's or a batch record's `plant_model`), `command line` (`--plant-model`); null "
        "when none was declared.")
    plant_model_trained: bool | None = Field(..., description="Whether the model was trained on that family (false: "
                                             "`family_untrained`, never confident); null when none was declared or "
                                             "the card records no families.")
    text: str = Field(..., description="All of it in one sentence.")


class DiagnoseResponse(BaseModel):
    """The verdict of the active (or requested) model, from ``models.pipeline.diagnose_recording``."""

    model_config = ConfigDict(protected_namespaces=())

    headline: HeadlineOut | None = Field(None, description="Opens every answer: what to do about the machine and "
                                         "how urgent, made from the status, the band, the reasons and the baseline "
                                         "comparison (docs/pipeline.md, the headline rules).")

    status: Literal["confident", "uncertain", "inconclusive"] = Field(
        "confident", description="`inconclusive`: a physics sanity check failed or the recording is far outside what "
        "the model knows — no severity is given, read `reasons` and `evidence`; `uncertain`: a severity is given but "
        "`reasons` say why to doubt it; `confident`: none of these.")
    reasons: list[ReasonOut] = Field(default_factory=list, description="Why the verdict is not confident, worst first.")
    evidence: list[EvidenceOut] = Field(default_factory=list, description="Measured signatures (1X/2X vectors, 2X/1X, "
                                        "phase across the coupling, orbit shape, shaft centreline), each with what it "
                                        "usually means; independent of the ML model.")
    severity: str = Field(..., description="Severity class by the model's Δ bands (default: aligned Δ < 0.05, "
                          "slight 0.05-0.15, moderate 0.15-0.35, severe ≥ 0.35), or `inconclusive` when `status` is "
                          "inconclusive.", examples=["slight"])
    model_severity: str | None = Field(None, description="The classifier's class even when `status` is inconclusive "
                                       "(for audit; do not act on it then).")
    misalignment_model: float | None = Field(None, description="The Δ regressor's own estimate; `misalignment` is it "
                                             "clipped into the band of `severity`, so class and Δ always agree.")
    speed_source: str | None = Field(None, description="`keyphasor`, `given`, `estimated`, or `keyphasor intervals` "
                                     "(a faulty keyphasor's sound pulse intervals: the orders tracked at that steady "
                                     "speed, phases from the first sample).")
    probabilities: dict[str, float] = Field(..., description="Calibrated probability of each severity class (sum 1).")
    misalignment: float | None = Field(..., description="Estimated misalignment Δ = δ/c (offset over radial "
                                       "clearance, non-dimensional), inside the band of `severity`; null when "
                                       "inconclusive.")
    misalignment_interval: list[float | None] = Field(..., min_length=2, max_length=2,
                                                      description="[low, high] interval of Δ at `interval_level` "
                                                      "(null: unbounded on that side).")
    interval_level: float | None = Field(..., description="Nominal coverage of the Δ interval (e.g. 0.9).")
    output_units: Literal["um", "mil"] = Field("um", description="Units of the lengths in this answer "
                                               "(`?output_units=`); the field names say them too.")
    offset_um: float | None = Field(None, description="Offset δ = Δ·c in micrometres (only when `clearance_um` was given).")
    offset_mil: float | None = Field(None, description="`offset_um` in mils, when `output_units=mil`.")
    offset_interval_mil: list[float | None] | None = Field(None, description="`offset_interval_um` in mils, "
                                                           "when `output_units=mil`.")
    offset_interval_um: list[float | None] | None = Field(None, description="[low, high] of δ in micrometres "
                                                          "(null inside: unbounded on that side).")
    direction: dict[str, Any] | None = Field(None, description="Which way the exciter sits relative to the "
                                             "generator at the coupling (models.direction): `estimated` true with "
                                             "`horizontal` and `vertical` (each `value` and 90 % `interval`, in "
                                             "`unit`: um, mil or per_c; + = right / high, seen from the end from "
                                             "which the shaft turns counter-clockwise), `angle_deg` (from +x toward "
                                             "+y) and `text`; a side is named only where its interval excludes 0. "
                                             "`estimated` false with `code` and `why_not`: a model trained without "
                                             "direction labels, a recording without DC positions (AC-coupled) or "
                                             "without the clearance, an aligned or inconclusive verdict.")
    angular_offset: dict[str, Any] | None = Field(None, description="The angular offset α at the coupling: "
                                                  "`estimated` true with `angular_mrad`, `interval_mrad` and "
                                                  "`interval_level`, or false with `code` and `why_not` (as "
                                                  "`direction`; also a model whose training carried no α).")
    motion_type: str | None = Field(None, description="Motion type of the shaft (e.g. `period-1`, `quasi-periodic`), "
                                    "when the record is long enough to tell.")
    top_features: list[FeatureContributionOut] = Field(..., description="Features that drove the verdict, "
                                                       "largest effect first.")
    ood: bool = Field(..., description="True when the recording is unlike the model's training data "
                      "(out-of-distribution: `ood_score` > 1 or any `ood_findings`): treat the verdict with caution.")
    ood_score: float | None = Field(None, description="Distance to the training data over its usual distance "
                                    "(> 1 flags OOD).")
    ood_findings: list[OodFindingOut] = Field(default_factory=list, description="Features outside the range of "
                                              "the training data (largest excess first); each also in `reasons` "
                                              "(code `outside_training`). Any of them sets `ood`.")
    speed_rpm: float | None = Field(None, description="Running speed used, r/min (given — locked to the signals' "
                                    "synchronous lines within ±1 % —, from the keyphasor, or estimated from the signals).")
    model_version: str = Field(..., description="Registered model version that produced the verdict.")
    answered_by: AnsweredByOut | None = Field(None, description="Which model answered (version, training families, "
                                              "the plant it was retrained for) and which plant model the recording "
                                              "was judged as, and who declared it; null in answers stored before it "
                                              "was given.")
    bands: dict[str, Any] = Field(..., description="The model's severity bands: `edges` (Δ) and `names`.")
    warnings: list[str] = Field(..., description="Anything that makes the verdict less certain: each the message of "
                                "one code of the warnings catalogue (`rotordiag.core.notes`; docs/pipeline.md's warnings "
                                "table): " + ", ".join(f"`{c}`" for c in NOTES) + ".")
    warning_codes: list[Literal[tuple(NOTES)]] = Field(  # type: ignore[valid-type]
        default_factory=list, description="The catalogue code of each of `warnings`, in the same order "
        "(`rotordiag.core.notes`; docs/pipeline.md's warnings table says what each means and what to do): match on "
        "these, not on the words. Empty in answers stored before the codes were given.")
    asset_probes: AssetProbesSection | None = Field(None, description="With an `asset_id` that has a probe "
                                                    "configuration (PUT /assets/{id}/probes): what of it was used.")
    input_notes: list[str] = Field(default_factory=list, description="What the reader assumed or left out of an "
                                   "uploaded file: the sample rate from its time column or header, the probe "
                                   "voltages' conversion to µm, metadata lines skipped, columns not read as probes.")
    bearings: list[BearingOut] = Field(..., description="Per-bearing key features from the features package.")
    diagnosis_id: int | None = Field(None, description="With an `asset_id` and the API key: the id of the stored "
                                     "diagnosis.")
    stored: bool | None = Field(None, description="With an `asset_id`: whether this diagnosis was stored in the "
                                "asset's history (only requests with the `X-API-Key` header store).")
    storage_note: str | None = Field(None, description="With an `asset_id` and no API key: why the diagnosis was "
                                     "not stored.")
    startup: dict[str, Any] | None = Field(None, description="With an `asset_id` whose later start-up is compared with its "
                                           "baseline start-up (POST /assets/{id}/startup): `startup_id`, "
                                           "`baseline_startup_id` (null: none), `changed` (the coupling-end "
                                           "centreline rise moved), `reasons` added; the comparison itself is in "
                                           "`evidence` (scope `start-up`).")
    baseline: BaselineSectionOut | None = Field(None, description="With an `asset_id`: whether the asset's baseline "
                                                "was used, its date, and what changed since it (the change items are "
                                                "also in `evidence`, scope `change since baseline`).")
    key_features: dict[str, float | None] = Field(..., description="Values of `top_features` by name (stored in the "
                                                  "asset history).")


class BatchItem(BaseModel):
    """Outcome for one record of a batch."""

    index: int = Field(..., description="Position of the record in `records` (0-based).")
    status_code: int = Field(..., description="200 when diagnosed; otherwise the status a single /diagnose "
                             "call would have answered (422: bad recording).")
    result: DiagnoseResponse | None = Field(None, description="The verdict when `status_code` is 200.")
    error: str | None = Field(None, description="What to fix when the record could not be diagnosed.")


class BatchResponse(BaseModel):
    """Body answered by POST /diagnose/batch."""

    count: int = Field(..., description="Number of records.")
    n_ok: int = Field(..., description="Records diagnosed successfully.")
    items: list[BatchItem] = Field(..., description="One entry per record, in order.")


class ModelCard(BaseModel):
    """A registered model version: its card (see docs/models) plus the `active` flag."""

    model_config = ConfigDict(extra="allow", protected_namespaces=())

    version: str = Field(..., description="Version name (directory in the registry).")
    active: bool = Field(..., description="True for the version /diagnose uses by default.")
    probe_sets: list[dict[str, Any]] | None = Field(
        None, description="The bearing sets the model was trained on (`bearings`), with its held-out `macro_f1` and "
        "`false_alarm` on each when measured for this model, and what a recording with those probes gets (`verdict`: "
        "`reads`, `never confident`, `no severity` or `not measured`); a recording is read through the largest of "
        "them it has (docs/models.md). Null when the card does not list them.")


class ModelDetail(ModelCard):
    """One version: its card, and for a plant-retrained version its quality report (docs/models.md)."""

    activated_by: Literal["forced", "report"] | None = Field(
        None, description="How a plant-retrained version was activated: `report` (its quality report says it is "
        "better than the model it was compared with), `forced` (activated although it is not); null: never activated, "
        "or not a plant-retrained version.")
    plant_report: dict[str, Any] | None = Field(
        None, description="The full quality report of a plant-retrained version (`plant_report.json`): held-out "
        "recordings of its plant under every measurement condition, this model beside the one it was compared "
        "with (band macro-F1, false alarms, confident share, confident two bands off, 90 % interval coverage, "
        "paired bootstrap intervals) and the `decision`; null for other versions.")


class ModelList(BaseModel):
    """The registry."""

    active: str | None = Field(None, description="Active version.")
    versions: list[ModelCard] = Field(..., description="Registered versions, oldest first.")


# --- job requests -----------------------------------------------------------------------------



class DatasetJobRequest(_Strict):
    """Body of POST /datasets: a dataset sweep spec (docs/datasets.md), as TOML text or as the same tables in JSON."""

    spec_toml: str | None = Field(None, max_length=200_000,
                                  description="The spec file's text (see examples/dataset_small.toml).")
    spec: dict[str, Any] | None = Field(
        None, description="The spec as a JSON object with the TOML tables as keys "
        "(`design`, `operating`, `plant`, `measurement`, `simulation`).",
        examples=[{"design": {"method": "sobol", "n_samples": 64, "seed": 1},
                   "operating": {"misalignment": {"min": 0.0, "max": 0.6}, "speed_rpm": {"min": 1500, "max": 2100},
                                 "mechanism": "rigid"},
                   "measurement": {"sample_rate_hz": 2048, "duration_revs": 64, "snr_db": 30}}])
    name: str | None = Field(None, max_length=64, pattern=r"^[A-Za-z0-9._-]+$",
                             description="File name stem of the dataset under <data_dir>/datasets (default: the job id).")


class FieldRecord(_Strict):
    """A field-labelled recording: waveforms measured on the user's machine with a known misalignment."""

    misalignment: FiniteFloat = Field(..., ge=0, le=0.9, description="Δ = δ/c measured by an alignment survey.")
    mechanism: str = Field("rigid", description="Coupling mechanism the record is grouped with in the evaluation: "
                           "any mechanism of the simulator (`pin`, `rigid`, `offset`, `flexible`; docs/model.md).",
                           json_schema_extra={"enum": list(DESIGN_MECHANISMS)})
    recording: RecordingIn = Field(..., description="The waveforms (as in POST /diagnose).")

    @field_validator("mechanism")
    @classmethod
    def _mechanism(cls, v: str) -> str:
        if v not in DESIGN_MECHANISMS:
            raise ValueError(f"unknown mechanism {v!r}; use one of {list(DESIGN_MECHANISMS)}")
        return v


#: the largest shaft-line TOML text POST /trains/summary and POST /models/retrain read (a real one is a few kB)
MAX_SHAFTLINE_TOML_CHARS = 100_000


class RetrainRequest(_Strict):
    """Body of POST /models/retrain: retrain the model for a plant."""

    plant: dict[str, Any] = Field(
        default_factory=dict,
        description="Values set over the plant. With `shaftline` or `preset` (a finite-element shaft train): "
        "the train's values by name with units (`simulator.train.plant.TRAIN_PERTURBABLE`: e.g. `clearance_m`, "
        "`viscosity_pa_s`, `coupling_stiffness_n_m`, `balance_grade_mm_s`), over the shaft line's own. Without: "
        "the MODEL.md lumped plant's `simulator.Plant` fields (e.g. `generator_mass_kg`, `asymmetry`).",
        examples=[{"generator_mass_kg": 30000.0, "asymmetry": 0.04}])
    shaftline: dict[str, Any] | None = Field(
        None,
        description="The plant as a plant engineer describes it: the shaft-line tables of "
        "`rotordiag plant from-shaftline` (`generator`, `exciter` with `segments` [[length_m, diameter_m], ...] "
        "and `body_masses`, `bearings`, `oil`, `coupling`, ...; examples/shaftline_200mw.toml), simulated as its "
        "finite-element shaft train within manufacturing tolerances (docs/models.md, \"Retraining for one "
        "plant\"); a `coupling.type` it names is the only coupling trained on.",
        examples=[{"generator": {"segments": [[0.6, 0.45], [0.9, 0.6], [5.0, 1.0], [0.9, 0.6], [0.6, 0.45]],
                                 "body_masses": [[2.125, 3000.0], [3.375, 3000.0], [4.625, 3000.0],
                                                 [5.875, 3000.0]]},
                   "exciter": {"segments": [[0.4, 0.25], [2.6, 0.36], [0.4, 0.25]], "body_masses": [[1.7, 1500.0]]},
                   "bearings": {"diameter_m": [0.45, 0.45, 0.25, 0.25], "length_m": [0.35, 0.35, 0.15, 0.15],
                                "clearance_m": 0.00035},
                   "coupling": {"type": "flexible", "stiffness_n_m": 1.0e8}}])
    shaftline_toml: str | None = Field(
        None, max_length=MAX_SHAFTLINE_TOML_CHARS,
        description="The same shaft line as the text of its TOML file (`rotordiag retrain --shaftline`'s file; it "
        "may hold `rated_speed_rpm` at the top); instead of `shaftline` or `preset`.")
    preset: str | None = Field(None, min_length=1, max_length=64,
                               description="A rated-machine preset by name (`gen50_2pole`, `gen200_2pole`, "
                               "`gen600_2pole`, `gen600_4pole`) instead of `shaftline`: its shaft line and its rated "
                               "speeds.", examples=["gen600_4pole"])
    rated_speed_rpm: float | None = Field(None, ge=100, le=6000, allow_inf_nan=False,
                                          description="The plant's rated speed, r/min: the default sweep trains at "
                                          "0.8–1.05 × it (a preset gives its own); without it 1200–2200 r/min.")
    sweep: dict[str, Any] = Field(
        default_factory=dict,
        description="Dataset spec tables (`design`, `operating`, `measurement`, `simulation`, `plant.perturb`, "
        "`plant.scale`) "
        "overriding the retraining defaults (see docs/service.md).",
        examples=[{"design": {"n_samples": 200}, "operating": {"speed_rpm": {"min": 2900, "max": 3100}}}])
    training: dict[str, Any] = Field(default_factory=dict,
                                     description="Tables and keys of train.toml (seed, bands, features, classifier, "
                                     "regressor, ood, envelope, augment, evaluation, baselines) that override the "
                                     "shipped model's recipe, models/default/train.toml; what is not named is kept.")
    field_data: list[FieldRecord] = Field(default_factory=list, max_length=1000,
                                          description="Optional field-labelled recordings added to the training set.")
    activate: bool = Field(True, description="Make the new version active if its quality report on the plant says it "
                           "is better than the active model (docs/models.md, \"Activated only if better\").")
    force: bool = Field(False, description="Activate the new version even if its report says it is not better "
                        "(recorded in its card: `activated_by` = `forced`).")
    report_cases: int = Field(6, ge=1, le=50, description="Held-out recordings per class (each coupling of a "
                              "shaft train, or the four lumped mechanisms, and aligned) of the plant's quality "
                              "report; each is measured under every condition.")


class JobCreated(BaseModel):
    """Answer to a job-creating POST."""

    id: str = Field(..., description="Job id.")
    status: JobStatus = Field(..., description="Initial state (`queued`).")
    url: str = Field(..., description="Where to poll the job.")


class JobList(BaseModel):
    """Recent jobs, newest first."""

    count: int = Field(..., description="Number of jobs returned.")
    jobs: list[JobOut] = Field(..., description="Jobs, newest first.")


# --- setpoint alarms and webhooks (issue 45, item 3; service.alarms) ---------------------------

class SetpointsIn(_Strict):
    """PUT /assets/{id}/setpoints."""

    setpoints: dict[str, dict[str, float]] = Field(..., description="Quantity → `{\"alert\": x, \"danger\": y}` "
                                                   "(either or both): `overall_um_pp`, `x1_um_pp`, `x2_um_pp` "
                                                   "(µm pk-pk, the largest probe) and `misalignment` (Δ = δ/c); "
                                                   "`{}` removes them.")


class SetpointsOut(BaseModel):
    """GET/PUT /assets/{id}/setpoints."""

    asset_id: str = Field(..., description="The asset.")
    setpoints: dict[str, dict[str, float]] = Field(..., description="The setpoints in force (none shipped).")
    units: dict[str, str] = Field(..., description="Unit of each quantity.")
    levels: dict[str, str] = Field(..., description="The level each alarm quantity is at now (from its latest "
                                   "event; `change` is the baseline-change alarm).")


_Label = Annotated[str, StringConstraints(min_length=1, max_length=MAX_LABEL_LEN, strip_whitespace=True)]


class HierarchyIn(_Strict):
    """PUT /assets/{id}/hierarchy: where the asset sits (a field left out or null is cleared)."""

    site: _Label | None = Field(None, description="The plant or site, e.g. `Riverside`.")
    unit: _Label | None = Field(None, description="The unit at the site, e.g. `unit 3`.")
    train: _Label | None = Field(None, description="The machine train of the unit, e.g. `generator-exciter`.")


class AssetSummary(BaseModel):
    """One asset in GET /assets."""

    asset_id: str = Field(..., description="The asset.")
    site: str | None = Field(None, description="Its plant or site.")
    unit: str | None = Field(None, description="Its unit at the site.")
    train: str | None = Field(None, description="Its machine train.")
    diagnoses: int = Field(0, description="Stored diagnoses.")
    latest: dt.datetime | None = Field(None, description="Trend time of its latest stored diagnosis.")


class AlarmEventOut(BaseModel):
    """One raised or cleared alarm of an asset."""

    id: int = Field(..., description="The event's id (for `POST …/events/{id}/ack`).")
    asset_id: str = Field(..., description="The asset.")
    time: str | None = Field(None, description="When the diagnosis that raised or cleared it was stored (UTC).")
    quantity: str = Field(..., description="`overall_um_pp`, `x1_um_pp`, `x2_um_pp`, `misalignment` or `change`.")
    unit: str | None = Field(None, description="Unit of `value` and `setpoint` (`um_pp`, or none for Δ).")
    level: str = Field(..., description="`alert`, `danger`, or `normal` (cleared).")
    event: str = Field(..., description="`raised` or `cleared`.")
    value: float | None = Field(None, description="The quantity's value in the diagnosis that raised or cleared it.")
    setpoint: float | None = Field(None, description="The setpoint crossed (raised events).")
    diagnosis_id: int | None = Field(None, description="The stored diagnosis that raised or cleared it.")
    message: str = Field(..., description="What happened, in words.")
    acked_at: str | None = Field(None, description="When it was acknowledged (null: not yet).")
    ack_note: str | None = Field(None, description="The note given with the acknowledgement.")


class AlarmEventsOut(BaseModel):
    """GET /assets/{id}/events."""

    asset_id: str = Field(..., description="The asset.")
    events: list[AlarmEventOut] = Field(..., description="Newest first.")


class AckIn(_Strict):
    """POST /assets/{id}/events/{event_id}/ack."""

    note: str | None = Field(None, max_length=2000, description="Who acknowledged and what is being done.")


class WebhookIn(_Strict):
    """POST /webhooks."""

    url: str = Field(..., min_length=8, max_length=2000, pattern=r"^https?://[^\s]+$",
                     description="http(s) URL the events are POSTed to.")
    secret: str | None = Field(None, min_length=16, max_length=256, description="Signing key (a random one is made "
                               "and returned once when not given).")
    asset_id: str | None = Field(None, min_length=1, max_length=MAX_LABEL_LEN, pattern=r"^[A-Za-z0-9._:-]+$",
                                 description="Only this asset's events (all assets when not given).")


class WebhookOut(BaseModel):
    """A webhook (POST/GET /webhooks)."""

    id: int = Field(..., description="The webhook's id.")
    url: str = Field(..., description="Where the events are POSTed.")
    asset_id: str | None = Field(None, description="Only this asset's events (null: all assets).")
    created_at: dt.datetime | None = Field(None, description="When it was added (UTC).")
    secret: str | None = Field(None, description="Only in the answer to POST /webhooks.")
    signature_header: str = Field(..., description="Header carrying `sha256=` + hex HMAC-SHA256 of the body "
                                  "with the secret as key.")


class DeliveryOut(BaseModel):
    """One delivery of an event to a webhook (GET /webhooks/{id}/deliveries)."""

    id: int = Field(..., description="The delivery's id (header `X-Rotordiag-Delivery`).")
    webhook_id: int = Field(..., description="The webhook.")
    event_id: int | None = Field(None, description="null for a test delivery.")
    status: str = Field(..., description="pending, sending, delivered, failed or dropped.")
    attempts: int = Field(..., description="Attempts made so far.")
    last_error: str | None = Field(None, description="What the last failed attempt got.")
    created_at: str | None = Field(None, description="When the delivery was queued (UTC).")
    next_attempt_at: str | None = Field(None, description="When it is tried next (UTC).")
    delivered_at: str | None = Field(None, description="When a 2xx answer came (UTC).")


# --- shaft trains ---------------------------------------------------------------------------



class TrainSummaryRequest(_Strict):
    """Body of POST /trains/summary: one shaft train (a preset, a shaft-line table or a shaft-line TOML text)
    and the speed of its static state and stability margin."""

    preset: str | None = Field(None, max_length=64, description="A preset machine: one of GET /trains/presets.",
                               examples=["gen200_2pole"])
    shaftline: dict[str, Any] | None = Field(
        None, description="A shaft line as tables (the TOML of `rotordiag plant from-shaftline`, e.g. "
        "examples/shaftline_200mw.toml, as JSON): `generator`, `exciter`, `bearings`, `coupling`, ...")
    shaftline_toml: str | None = Field(
        None, max_length=MAX_SHAFTLINE_TOML_CHARS,
        description="The same shaft line as the text of its TOML file (what the web page uploads).")
    speed_rpm: float | None = Field(
        None, ge=SPEED_RANGE_RPM[0], le=SPEED_RANGE_RPM[1], allow_inf_nan=False,
        description="Running speed of the summary, r/min; default the preset's rated speed (required for a "
        "shaft line, which carries none).")


class TrainPreset(BaseModel):
    """A preset machine of the shaft-train model."""

    name: str = Field(..., description="Preset name for `preset` in POST /trains/summary and `--train`.")
    rated_speed_rpm: list[float] = Field(..., description="Its rated speeds, r/min (50 Hz and 60 Hz grids).")


class TrainRotorOut(BaseModel):
    """One rotor of the train."""

    name: str = Field(..., description="`generator` or `exciter`.")
    n_stations: int = Field(..., description="Finite-element stations of the rotor.")
    length_m: float = Field(..., description="Rotor length, flange and overhangs included, m.")
    mass_kg: float = Field(..., description="Shaft and body masses, kg.")
    n_bearings: int = Field(..., description="Bearings under this rotor (2, or 1 for an overhung exciter).")


class TrainBearingOut(BaseModel):
    """One bearing at the train's static state (gravity and bearing positions, the oil films at speed)."""

    name: str = Field(..., description="B1, B2 (generator), B3, B4 (exciter), from the generator's free end.")
    rotor: str = Field(..., description="The rotor it carries.")
    type: str = Field(..., description="Bearing model (e.g. TiltingPadBearing, EllipticalBearing, ShortBearing).")
    z_m: float = Field(..., description="Axial position from bearing 1, m.")
    load_vertical_kn: float = Field(..., description="Vertical force of the journal on the bearing, kN "
                                    "(+ up: a bearing carrying its share of the weight reads negative).")
    load_horizontal_kn: float = Field(..., description="Horizontal force of the journal on the bearing, kN (+x).")
    eccentricity: float = Field(..., description="Journal eccentricity |e|/c in its clearance (1: touching).")
    attitude_angle_deg: float = Field(..., description="Angle from the load to the journal's displacement, "
                                      "degrees, positive in the direction of rotation.")


class TrainSummaryOut(BaseModel):
    """A train's stations, bearings at their static state and stability margin at `speed_rpm`."""

    source: str = Field(..., description="The preset name, or `shaftline` for an uploaded shaft line.")
    speed_rpm: float = Field(..., description="Speed of the static state and the margin, r/min.")
    rated_speed_rpm: float | None = Field(None, description="The preset's rated speed, r/min (null for a file).")
    n_stations: int = Field(..., description="Finite-element stations of the whole train.")
    coupling: str = Field(..., description="Coupling type between the rotors (`rigid` or `flexible`).")
    rotors: list[TrainRotorOut] = Field(..., description="The rotors, generator first.")
    bearings: list[TrainBearingOut] = Field(..., description="Every bearing, in train order.")
    log_decrement: float = Field(..., description="Stability margin: logarithmic decrement of the least-damped "
                                 "mode (API 684); ≤ 0 is an unstable train (oil whirl/whip).")
    mode_frequency_hz: float = Field(..., description="Damped frequency of that mode, Hz.")
    mode_forward: bool = Field(..., description="Whether that mode whirls forward (with the rotation).")
    stable: bool = Field(..., description="log_decrement > 0.")
    warning: str | None = Field(None, description="Why the speed is beyond the stability threshold, when it is.")


#: a simulated train recording's length: samples per channel (record_revs × samples_per_rev), checked before allocating
MAX_TRAIN_SIM_SAMPLES = 32_768


class TrainProbeIn(_Strict):
    """One probe of a simulated train: the bearing it is at and its angle."""

    bearing: int = Field(..., ge=1, le=8, description="Bearing number along the train, 1 = generator far end.")
    angle_deg: float = Field(..., ge=-360.0, le=360.0, allow_inf_nan=False,
                             description="Probe angle, degrees from +x (horizontal) toward +y (vertical up).")


class TrainSimulateRequest(_Strict):
    """Body of POST /trains/simulate: one shaft train (a preset, a shaft-line table or a shaft-line TOML text), its
    misalignment and unbalance, the speed, and the recording's length and format."""

    preset: str | None = Field(None, max_length=64, description="A preset machine: one of GET /trains/presets.",
                               examples=["gen200_2pole"])
    shaftline: dict[str, Any] | None = Field(
        None, description="A shaft line as tables (as for POST /trains/summary).")
    shaftline_toml: str | None = Field(
        None, max_length=MAX_SHAFTLINE_TOML_CHARS, description="The same shaft line as the text of its TOML file.")
    speed_rpm: float | None = Field(
        None, ge=SPEED_RANGE_RPM[0], le=SPEED_RANGE_RPM[1], allow_inf_nan=False,
        description="Running speed, r/min; default the preset's rated speed (required for a shaft line).")
    coupling: Literal["rigid", "flexible"] | None = Field(
        None, description="Coupling type, replacing the shaft line's (a flexible one takes the shaft line's "
        "coupling stiffnesses); default the shaft line's own.")
    offset_um: float = Field(0.0, ge=-10_000.0, le=10_000.0, allow_inf_nan=False,
                             description="Parallel offset δ between the shaft lines at the coupling, µm, along "
                             "`offset_angle_deg`, set by moving the exciter's bearings.")
    offset_angle_deg: float = Field(-90.0, ge=-360.0, le=360.0, allow_inf_nan=False,
                                    description="Direction of the offset and of the angle, degrees from +x "
                                    "(horizontal) toward +y (vertical up): -90 (default) = the exciter low, the "
                                    "common vertical offset; 0 = sideways.")
    angular_mrad: float = Field(0.0, ge=-10.0, le=10.0, allow_inf_nan=False,
                                description="Angular offset α between the shaft lines, mrad (the exciter's line "
                                "rising away from the coupling along `offset_angle_deg`).")
    unbalance_kg_m: float | None = Field(None, ge=0.0, le=10.0, allow_inf_nan=False,
                                         description="Unbalance at the middle of the generator, kg·m, at the "
                                         "keyphasor mark, in place of the line's own (a preset's: ISO 21940-11 "
                                         "G2.5); omitted: the line's own.")
    transient_revs: int = Field(200, ge=10, le=320, description="Revolutions simulated and discarded before the "
                                "record (the transient of the start).")
    record_revs: int = Field(32, ge=1, le=256, description="Revolutions recorded.")
    samples_per_rev: int = Field(128, ge=16, le=512, description="Samples per revolution of the record.")
    probes: list[TrainProbeIn] | None = Field(
        None, min_length=1, max_length=16, description="The probes to record; default a 45°/135° pair at every "
        "bearing (the layout the features read: two probes per bearing, at least 30° from parallel).")
    snr_db: float | None = Field(40.0, gt=0.0, le=200.0, allow_inf_nan=False,
                                 description="Probe noise: signal-to-noise ratio per probe, dB (null: none).")
    seed: int = Field(0, ge=0, le=2**32 - 1, description="Seed of the probe noise.")
    format: Literal["json", "csv", "h5"] = Field(
        "json", description="`json`: the recording as JSON (channels, keyphasor, warnings); `csv` or `h5`: a file "
        "download in the layout `rotordiag simulate --train --probes-out` writes (b<bearing>@<angle> µm columns and "
        "a `kp` keyphasor pulse column; warnings in the `X-Rotordiag-Warnings` header), readable by "
        "`rotordiag diagnose` and POST /diagnose.")

    @field_validator("samples_per_rev")
    @classmethod
    def _bounded_record(cls, v: int, info: Any) -> int:
        revs = info.data.get("record_revs")
        if revs is not None and revs * v > MAX_TRAIN_SIM_SAMPLES:
            raise ValueError(f"record_revs × samples_per_rev = {revs} × {v} = {revs * v} samples per channel, more "
                             f"than {MAX_TRAIN_SIM_SAMPLES}: record fewer revolutions or fewer samples per revolution")
        return v


class TrainChannelOut(BaseModel):
    """One probe of a simulated train."""

    bearing: int = Field(..., description="Bearing number along the train, 1 = generator far end.")
    angle_deg: float = Field(..., description="Probe angle, degrees from +x toward +y.")
    units: str = Field("um", description="Always `um`.")
    data: list[float] = Field(..., description="Displacement of the journal toward the probe, µm, DC included.")


class TrainSimulateOut(BaseModel):
    """A shaft train's steady recording as its probes read it."""

    source: str = Field(..., description="The preset name, or `shaftline` for an uploaded shaft line.")
    speed_rpm: float = Field(..., description="Running speed, r/min.")
    sample_rate_hz: float = Field(..., description="Sample rate of every channel, Hz.")
    channels: list[TrainChannelOut] = Field(..., description="Two probes (45° and 135°) at every bearing.")
    keyphasor_times_s: list[float] = Field(..., description="Keyphasor mark times, s (one per revolution).")
    clearance_um: dict[str, float] = Field(..., description="Radial clearance of each bearing (by number), µm.")
    log_decrement: float = Field(..., description="Log decrement of the least-damped mode at the static state.")
    warnings: list[str] = Field(..., description="What the user must know, e.g. a speed beyond the stability "
                                "threshold (the response is then oil whirl/whip).")
    inputs: dict[str, Any] = Field(..., description="Everything that made the recording (offsets, unbalance, "
                                   "revolutions, noise and its seed).")
