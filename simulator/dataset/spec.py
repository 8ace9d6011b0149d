"""The dataset specification: a small TOML file, validated with pydantic.

See ``examples/dataset_small.toml`` for a commented example and
``docs/datasets.md`` for the user guide. The tables are:

``[design]``       sampling design: ``method`` (grid | sobol | lhs), ``n_samples``, ``seed``
``[operating]``    Δ, A, Ω, phases, exciter unbalance, ``coupling_phase_rad``, ``mechanism``
                   (pin | rigid | offset | flexible): each a value, a list or a range
``[plant]``        base plant (``file``, ``shaftline`` or ``preset``, and/or ``set``), or a machine family
                   (``presets`` and/or ``shaftlines``, weighted), relative ``perturb``-ations and ``scale`` factors
``[measurement]``  probes, sample rate, duration, SNR, runout, speed fluctuation
``[simulation]``   transient_revs, samples_per_rev, rtol, atol, classify_motion, steady_start, transient_stop, integrator
``[transient]``    optional: every sample a run-up or coast-down along one speed profile (``start_rpm``,
                   ``end_rpm``, ``duration_s``, or ``times_s`` and ``speeds_rpm``) after ``settle_revs``
                   (simulator.transient); then ``operating.speed_rpm`` and the measurement's duration are the
                   profile's, not given

A *value* is a number; a *list* ``[a, b, c]`` is a set of levels; a *range*
``{min = .., max = ..}`` is a continuous interval (``n = k`` levels for a grid).
"""
from __future__ import annotations

import hashlib
import json
import math
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, field_validator, model_validator

from rotordiag.simulator.params import (
    DEFAULT_EXCITER_BEARING_SPAN_M,
    MISALIGNMENT_RANGE,
    SPEED_RANGE_RPM,
    UNBALANCE_RANGE,
)

__all__ = ["SpecError", "DatasetSpec", "Range", "Transient", "load_spec", "parse_spec", "PERTURBABLE"]

TWO_PI = 2.0 * math.pi

#: Plant fields that may be perturbed relatively (tuples are perturbed per bearing).
PERTURBABLE: tuple[str, ...] = (
    "journal1_mass_kg", "generator_mass_kg", "journal3_mass_kg", "journal4_mass_kg",
    "exciter_mass_kg", "journal6_mass_kg", "generator_stiffness_n_m", "asymmetry",
    "generator_damping_n_s_m", "exciter_stiffness_n_m", "exciter_damping_n_s_m",
    "clearance_m", "viscosity_pa_s", "bearing_radius_m", "bearing_length_m", "coupling_stiffness_n_m",
)


#: Couplings a shaft train's samples may have (``operating.mechanism`` with ``plant.model = "train"``).
TRAIN_MECHANISMS: tuple[str, ...] = ("rigid", "flexible")

#: Factor bounds of ``plant.scale`` ranges, and the most members of a machine family.
SCALE_RANGE: tuple[float, float] = (0.1, 10.0)
MAX_FAMILY = 64
#: Spec-level bound on ``operating.angular_misalignment_mrad`` (mrad); simulate checks the plant's own
#: |α|·L ≤ 0.9 c (0.093 mrad on the default plant).
ANGULAR_LIMIT_MRAD = 10.0


class SpecError(ValueError):
    """An invalid dataset spec; the message names the offending key and what to fix."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Range(_Strict):
    """A continuous interval ``{min = a, max = b}``; ``n`` levels when the design is a grid."""

    min: float
    max: float
    n: int | None = Field(default=None, ge=1, le=10_000)

    @model_validator(mode="after")
    def _ordered(self) -> Range:
        if not (math.isfinite(self.min) and math.isfinite(self.max)):
            raise ValueError("min and max must be finite numbers")
        if self.max < self.min:
            raise ValueError(f"empty range: max ({self.max}) < min ({self.min})")
        return self

    @property
    def lo(self) -> float:
        return self.min

    @property
    def hi(self) -> float:
        return self.max


def _parse_variable(v: Any) -> Any:
    """Turn TOML input into a float, a non-empty list of floats or a Range, with clear errors."""
    if isinstance(v, bool):
        raise ValueError(f"expected a number, a list of numbers or a range {{min = .., max = ..}}, got {v!r}")
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, list):
        if not v:
            raise ValueError("empty list: give at least one value")
        if len(v) > 10_000:
            raise ValueError(f"at most 10000 levels, got {len(v)}")
        if any(isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) for x in v):
            raise ValueError(f"a list must hold finite numbers, got {v!r}")
        return [float(x) for x in v]
    if isinstance(v, dict):
        try:
            return Range.model_validate(v)
        except ValidationError as exc:
            raise ValueError("; ".join(_one_error(e) for e in exc.errors())) from None
    if isinstance(v, Range):
        return v
    raise ValueError(f"expected a number, a list of numbers or a range {{min = .., max = ..}}, got {v!r}")


#: Mechanisms a dataset spec can ask for (every misaligned mechanism of the simulator).
DESIGN_MECHANISMS: tuple[str, ...] = ("pin", "rigid", "offset", "flexible")


def _parse_mechanism(v: Any) -> Any:
    allowed = DESIGN_MECHANISMS
    if isinstance(v, str):
        if v not in allowed:
            raise ValueError(f"unknown mechanism {v!r}; use one of {list(allowed)} (Δ = 0 always runs aligned)")
        return v
    if isinstance(v, list):
        if not v:
            raise ValueError("mechanism list is empty")
        bad = [m for m in v if m not in allowed]
        if bad or len(set(v)) != len(v):
            raise ValueError(f"mechanism list must hold distinct values from {list(allowed)}, got {v!r}")
        return list(v)
    if isinstance(v, dict):
        if not v:
            raise ValueError("mechanism weights are empty; give e.g. {pin = 0.5, rigid = 0.5}")
        bad = sorted(set(v) - set(allowed))
        if bad:
            raise ValueError(f"unknown mechanism(s) {bad}; use some of {list(allowed)}")
        w = list(v.values())
        if any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in w) or \
                any(not (math.isfinite(x) and x >= 0) for x in w) or sum(w) <= 0:
            raise ValueError(f"mechanism weights must be numbers ≥ 0, not all zero, got {v!r}")
        return {k: float(x) for k, x in v.items()}
    raise ValueError(f"mechanism must be one of {list(allowed)}, a list of them or weights "
                     f"{{pin = .., rigid = ..}}, got {v!r}")


Variable = Annotated[Union[float, list[float], Range], BeforeValidator(_parse_variable)]
Mechanism = Annotated[Union[str, list[str], dict[str, float]], BeforeValidator(_parse_mechanism)]


def _bounds(v: Variable) -> tuple[float, float]:
    if isinstance(v, Range):
        return v.min, v.max
    if isinstance(v, list):
        return min(v), max(v)
    return float(v), float(v)


def _check_bounds(name: str, v: Variable, lo: float, hi: float, unit: str = "") -> Variable:
    a, b = _bounds(v)
    if not (math.isfinite(a) and math.isfinite(b)) or a < lo or b > hi:
        raise ValueError(f"{name} must lie in [{lo:g}, {hi:g}]{unit}, got {a:g}..{b:g}")
    return v


class Design(_Strict):
    """How operating points and plant perturbations are sampled."""

    method: Literal["grid", "sobol", "lhs"] = "sobol"
    n_samples: int | None = Field(default=None, ge=1, le=10_000_000)
    seed: int = Field(ge=0, lt=2**63, description="master seed: every draw of the dataset derives from it")

    @model_validator(mode="after")
    def _n(self) -> Design:
        if self.method != "grid" and self.n_samples is None:
            raise ValueError(f"n_samples is required for method = {self.method!r}")
        return self


class Operating(_Strict):
    """Operating point of each sample (MODEL.md ranges)."""

    speed_rpm: Variable | None = None  # required for steady samples; a transient sample's speed is its profile's
    misalignment: Variable
    unbalance: Variable = 0.05
    unbalance_phase_rad: Variable = 0.0
    exciter_unbalance: Variable = 0.0
    exciter_unbalance_phase_rad: Variable = 0.0
    offset_angle_rad: Variable = 0.0
    coupling_phase_rad: Variable = 0.0
    angular_misalignment_mrad: Variable = 0.0
    mechanism: Mechanism = "rigid"

    @field_validator("speed_rpm")
    @classmethod
    def _speed(cls, v: Variable | None) -> Variable | None:
        return None if v is None else _check_bounds("speed_rpm", v, *SPEED_RANGE_RPM, " r/min")

    @field_validator("misalignment")
    @classmethod
    def _delta(cls, v: Variable) -> Variable:
        return _check_bounds("misalignment", v, *MISALIGNMENT_RANGE)

    @field_validator("unbalance", "exciter_unbalance")
    @classmethod
    def _unb(cls, v: Variable) -> Variable:
        return _check_bounds("unbalance", v, *UNBALANCE_RANGE)

    @field_validator("angular_misalignment_mrad")
    @classmethod
    def _angular(cls, v: Variable) -> Variable:
        # the plant-dependent bound (|α|·L ≤ 0.9 c) is checked by simulate; this keeps it finite and sane
        return _check_bounds("angular_misalignment_mrad", v, -ANGULAR_LIMIT_MRAD, ANGULAR_LIMIT_MRAD, " mrad")

    @field_validator("unbalance_phase_rad", "exciter_unbalance_phase_rad", "offset_angle_rad", "coupling_phase_rad")
    @classmethod
    def _phase(cls, v: Variable) -> Variable:
        return _check_bounds("phase", v, -TWO_PI, TWO_PI, " rad")


class PlantSpec(_Strict):
    """The base plant (or a family of base plants) and how it varies between samples."""

    model: Literal["lumped", "train"] = Field(
        default="lumped", description="how the shaft line is simulated: \"lumped\" (the paper's 11-DOF model, the "
        "line reduced to it) or \"train\" (the finite-element shaft train, each rotor on its own bearings, "
        "misaligned by moving the exciter's bearings; simulator.train)")
    file: str | None = Field(default=None, description="plant TOML/JSON file, relative to the spec file")
    shaftline: str | dict[str, Any] | None = Field(
        default=None, description="shaft-line TOML file (relative to the spec file), or the shaft-line tables "
        "themselves, reduced to the plant (simulator.shaftline)")
    preset: str | None = Field(default=None, description="a named shaft-line preset (simulator.shaftline.PRESETS)")
    presets: list[str] | dict[str, float] | None = Field(
        default=None, description="a machine family: each sample's base plant is one of these presets, "
        "equally likely (list) or by weight (table)")
    shaftlines: list[str] | dict[str, float] | None = Field(
        default=None, description="a machine family of shaft-line files (relative to the spec), as `presets`")
    set: dict[str, Any] = Field(default_factory=dict, description="values overriding the base plant")
    perturb: dict[str, float] = Field(
        default_factory=dict,
        description="relative half-widths r: value × (1 + u), u uniform in [−r, r] (per bearing for tuples)",
    )
    scale: dict[str, Range] = Field(
        default_factory=dict,
        description="factor ranges {min, max} in [0.1, 10]: value × f, log f uniform (one factor per field, "
        "all bearings together for tuples)",
    )

    @field_validator("perturb")
    @classmethod
    def _perturb(cls, v: dict[str, float]) -> dict[str, float]:
        for name, r in v.items():
            if not (math.isfinite(r) and 0.0 <= r <= 0.9):
                raise ValueError(f"perturbation of {name} must be a relative half-width in [0, 0.9], got {r}")
        return v

    @field_validator("scale")
    @classmethod
    def _scale(cls, v: dict[str, Range]) -> dict[str, Range]:
        for name, r in v.items():
            if r.n is not None:
                raise ValueError(f"scale.{name}: n (levels) is not used; scaling needs a random design")
            if not (SCALE_RANGE[0] <= r.min <= r.max <= SCALE_RANGE[1]):
                raise ValueError(f"scale.{name} must be factors within [{SCALE_RANGE[0]:g}, {SCALE_RANGE[1]:g}], "
                                 f"got {r.min:g}..{r.max:g}")
        return v

    @field_validator("presets", "shaftlines")
    @classmethod
    def _family(cls, v: list[str] | dict[str, float] | None) -> list[str] | dict[str, float] | None:
        if v is None:
            return v
        if not v:
            raise ValueError("empty family: give at least one member")
        if len(v) > MAX_FAMILY:
            raise ValueError(f"at most {MAX_FAMILY} members, got {len(v)}")
        if isinstance(v, list):
            if len(set(v)) != len(v):
                raise ValueError(f"members must be distinct, got {v!r}")
            return v
        w = list(v.values())
        if any(not (math.isfinite(x) and x >= 0) for x in w) or sum(w) <= 0:
            raise ValueError(f"weights must be numbers ≥ 0, not all zero, got {v!r}")
        return v

    @model_validator(mode="after")
    def _one_base(self) -> PlantSpec:
        single = [k for k in ("file", "shaftline", "preset") if getattr(self, k) is not None]
        family = [k for k in ("presets", "shaftlines") if getattr(self, k) is not None]
        if len(single) > 1 or (single and family):
            raise ValueError(f"give one of file, shaftline, preset, or a family (presets and/or shaftlines), "
                             f"got {', '.join(single + family)}")
        if self.model == "train" and (self.file is not None or not (single or family)):
            raise ValueError("model = \"train\" simulates a finite-element shaft train: give its shaft line "
                             "(preset, shaftline, presets or shaftlines), not a lumped plant file or none")
        allowed = self.perturbable
        for what, names in (("perturbed", self.perturb), ("scaled", self.scale)):
            for name in names:
                if name not in allowed:
                    raise ValueError(f"{name!r} cannot be {what} in a {self.model} plant; {what}: "
                                     f"{', '.join(allowed)}")
        return self

    @property
    def perturbable(self) -> tuple[str, ...]:
        """The names ``perturb`` and ``scale`` accept for this plant model."""
        if self.model == "train":
            from rotordiag.simulator.train.plant import TRAIN_PERTURBABLE

            return TRAIN_PERTURBABLE
        return PERTURBABLE

    @property
    def is_family(self) -> bool:
        return self.presets is not None or self.shaftlines is not None


class Measurement(_Strict):
    """The measurement model applied to the simulated journal displacements."""

    bearings: list[Literal[1, 2, 3, 4]] = Field(default=[1, 2, 3, 4], min_length=1, max_length=4)
    probe_angles_deg: list[float] = Field(
        default=[45.0, 135.0], min_length=1, max_length=8,
        description="probe directions, degrees counter-clockwise from +x (horizontal); 90 = top",
    )
    sample_rate_hz: float = Field(gt=0, le=1e6)
    duration_s: float | None = Field(default=None, gt=0, le=3600.0, allow_inf_nan=False)
    duration_revs: float | None = Field(default=None, gt=0, le=1e6, allow_inf_nan=False)
    snr_db: Variable = math.inf
    runout_1x_um: Variable = 0.0
    runout_2x_um: Variable = 0.0
    speed_fluctuation: float = Field(default=0.0, ge=0.0, le=0.05, description="relative amplitude of Ω(t)")
    speed_fluctuation_hz: float = Field(default=0.5, gt=0.0, le=100.0)

    @field_validator("bearings")
    @classmethod
    def _unique_bearings(cls, v: list[int]) -> list[int]:
        if len(set(v)) != len(v):
            raise ValueError(f"bearings must be distinct, got {v}")
        return v

    @field_validator("probe_angles_deg")
    @classmethod
    def _angles(cls, v: list[float]) -> list[float]:
        if any(not math.isfinite(a) or not -360.0 <= a <= 360.0 for a in v):
            raise ValueError(f"probe angles must be finite degrees in [-360, 360], got {v}")
        if len({round(a % 360.0, 9) for a in v}) != len(v):
            raise ValueError(f"probe angles must be distinct directions, got {v}")
        return v

    @field_validator("snr_db")
    @classmethod
    def _snr(cls, v: Variable) -> Variable:
        a, b = _bounds(v)
        if math.isnan(a) or math.isnan(b) or a < -20.0:
            raise ValueError(f"snr_db must be ≥ -20 dB (inf = no noise), got {a:g}..{b:g}")
        return v

    @field_validator("runout_1x_um", "runout_2x_um")
    @classmethod
    def _runout(cls, v: Variable) -> Variable:
        return _check_bounds("runout", v, 0.0, 1000.0, " µm")

    @model_validator(mode="after")
    def _duration(self) -> Measurement:
        if self.duration_s is not None and self.duration_revs is not None:  # none at all: checked by DatasetSpec
            raise ValueError("give exactly one of duration_s or duration_revs")
        if isinstance(self.snr_db, list):
            raise ValueError("snr_db must be a value or a range {min, max}, not a list")
        return self

    @property
    def n_channels(self) -> int:
        return len(self.bearings) * len(self.probe_angles_deg)


class Simulation(_Strict):
    """Integration settings passed to :func:`simulator.simulate`."""

    transient_revs: int = Field(default=400, ge=0, le=100_000)
    samples_per_rev: int = Field(default=128, ge=16, le=4096)
    rtol: float = Field(default=1e-6, gt=0, le=1e-2)
    atol: float = Field(default=1e-8, gt=0, le=1e-2)
    record_revs_min: int = Field(default=32, ge=1, le=100_000,
                                 description="record at least this many revolutions (Poincaré points for the motion label)")
    classify_motion: bool = Field(default=True, description="label the motion type with simulator.analysis")
    steady_start: Literal["shooting", "integrate"] = Field(
        default="shooting",
        description="start each record on the period-1 orbit found by shooting where that converges to a stable "
                    "orbit (else integrate the transient; diagnostics/steady_start says which), or always "
                    "integrate transient_revs revolutions")
    transient_stop: Literal["stationary", "fixed"] = Field(
        default="fixed",
        description="steady_start = shooting, samples that fall back to integration: always integrate all of "
                    "transient_revs (the default), or end the transient once the Poincaré-point statistics are "
                    "stationary (at most transient_revs; rotordiag.simulator.steady.attractor; opt-in: no overall "
                    "speed-up measured on the shipped specs, docs/datasets.md)")
    integrator: Literal["auto", "explicit"] = Field(
        default="auto",
        description="explicit Dormand-Prince 5(4) that hands a run over to LSODA once it becomes stiff (a journal "
                    "whirling near its bushing wall; the default), or Dormand-Prince throughout (the integration "
                    "before issue 16; 10-100x slower on such runs, which may then end 'diverged' on the step budget)")


#: Most points of a ``[transient]`` table profile.
MAX_PROFILE_POINTS = 1000
#: ``[simulation]`` keys of steady samples only: a transient sample starts settled at its profile's first speed
#: (``transient.settle_revs``) and is recorded at the acquisition rate, not per revolution.
STEADY_ONLY_SIMULATION = ("transient_revs", "samples_per_rev", "record_revs_min", "steady_start",
                          "transient_stop", "integrator", "classify_motion")


class Transient(_Strict):
    """Run-ups or coast-downs: every sample runs through the same speed profile
    (:class:`rotordiag.simulator.transient.SpeedProfile`), a linear ramp or a table."""

    start_rpm: float | None = Field(default=None, allow_inf_nan=False)
    end_rpm: float | None = Field(default=None, allow_inf_nan=False)
    duration_s: float | None = Field(default=None, allow_inf_nan=False)
    times_s: list[float] | None = Field(default=None, max_length=MAX_PROFILE_POINTS)
    speeds_rpm: list[float] | None = Field(default=None, max_length=MAX_PROFILE_POINTS)
    settle_revs: int = Field(default=200, ge=0, le=5000,
                             description="revolutions at the profile's first speed before its t = 0 (a settled start)")

    @model_validator(mode="after")
    def _one_profile(self) -> Transient:
        linear = [k for k in ("start_rpm", "end_rpm", "duration_s") if getattr(self, k) is not None]
        table = [k for k in ("times_s", "speeds_rpm") if getattr(self, k) is not None]
        if linear and table:
            raise ValueError(f"give a linear ramp (start_rpm, end_rpm, duration_s) or a table (times_s, speeds_rpm), "
                             f"not both (got {', '.join(linear + table)})")
        if not linear and not table:
            raise ValueError("give the speed profile: start_rpm, end_rpm and duration_s (a linear ramp), or "
                             "times_s and speeds_rpm (a table)")
        missing = sorted({"start_rpm", "end_rpm", "duration_s"} - set(linear)) if linear else \
            sorted({"times_s", "speeds_rpm"} - set(table))
        if missing:
            raise ValueError(f"the speed profile lacks {', '.join(missing)}")
        self.profile  # noqa: B018  (SpeedProfile's own checks: a ramp that reverses, a speed outside the range, …)
        return self

    @property
    def profile(self) -> Any:
        """The :class:`~rotordiag.simulator.transient.SpeedProfile` (raises ValueError with what to fix)."""
        from rotordiag.simulator.transient import SpeedProfile

        if self.times_s is not None:
            return SpeedProfile.table(self.times_s, self.speeds_rpm)
        return SpeedProfile.linear(self.start_rpm, self.end_rpm, self.duration_s)  # type: ignore[arg-type]


class DatasetSpec(_Strict):
    """A validated dataset specification (see the module docstring)."""

    design: Design
    operating: Operating
    plant: PlantSpec = Field(default_factory=PlantSpec)
    measurement: Measurement
    simulation: Simulation = Field(default_factory=Simulation)
    transient: Transient | None = None

    @property
    def is_transient(self) -> bool:
        """True when every sample is a run-up or coast-down (a ``[transient]`` table)."""
        return self.transient is not None

    @model_validator(mode="after")
    def _consistent(self) -> DatasetSpec:
        op = self.operating
        if self.transient is None and op.speed_rpm is None:
            raise ValueError("operating.speed_rpm: required key is missing (or give a [transient] speed profile)")
        if self.transient is not None:
            self._transient_consistent()
        elif self.measurement.duration_s is None and self.measurement.duration_revs is None:
            raise ValueError("measurement: give exactly one of duration_s or duration_revs")
        if self.design.method == "grid":
            for name in Operating.model_fields:
                v = getattr(op, name)
                if isinstance(v, Range) and v.n is None and v.min != v.max:
                    raise ValueError(f"operating.{name}: a grid needs the number of levels, e.g. "
                                     f"{{min = {v.min:g}, max = {v.max:g}, n = 5}}")
            if isinstance(op.mechanism, dict):
                raise ValueError("operating.mechanism: weights need a random design (sobol or lhs); "
                                 "for a grid give a list such as [\"pin\", \"rigid\"]")
            if self.plant.perturb and any(r > 0 for r in self.plant.perturb.values()):
                raise ValueError("plant.perturb needs a random design (sobol or lhs), not a grid")
            if any(r.max > r.min for r in self.plant.scale.values()):
                raise ValueError("plant.scale needs a random design (sobol or lhs), not a grid")
            if any(isinstance(f, dict) for f in (self.plant.presets, self.plant.shaftlines)):
                raise ValueError("plant.presets/shaftlines: weights need a random design (sobol or lhs); "
                                 "for a grid give a list")
        else:
            for name in Operating.model_fields:
                v = getattr(op, name)
                if isinstance(v, Range) and v.n is not None:
                    raise ValueError(f"operating.{name}: n (levels) is only used by method = \"grid\"")
        if self.plant.model == "train":
            mechs = [op.mechanism] if isinstance(op.mechanism, str) else list(op.mechanism)
            bad = sorted(set(mechs) - set(TRAIN_MECHANISMS))
            if bad:
                raise ValueError(f"operating.mechanism {bad} is not a shaft train's coupling: a train is "
                                 f"misaligned by moving bearings, with a {' or '.join(TRAIN_MECHANISMS)} coupling")
            given = sorted({"unbalance", "exciter_unbalance", "exciter_unbalance_phase_rad",
                            "coupling_phase_rad"} & op.model_fields_set)
            if given:
                raise ValueError(f"operating.{given[0]} is the lumped model's; a train's unbalance is its balance "
                                 "grade (plant.set.balance_grade_mm_s, ISO 21940 G in mm/s, at the generator's "
                                 "middle, phase operating.unbalance_phase_rad)")
        s_lo, s_hi = self.speed_bounds_rpm
        nyquist_need = 4.0 * s_hi / 60.0  # resolve 2X: fs > 2 × (2 × f_max)
        if self.measurement.sample_rate_hz < nyquist_need:
            raise ValueError(f"measurement.sample_rate_hz = {self.measurement.sample_rate_hz:g} Hz is too low "
                             f"for speed up to {s_hi:g} r/min: need ≥ {nyquist_need:g} Hz to resolve 2X")
        if self.n_points > 2**22:
            raise ValueError(f"measurement: {self.n_points} points per channel is too many (max 4194304); "
                             "shorten the duration or lower the sample rate")
        if self.n_points < 16:
            raise ValueError(f"measurement: only {self.n_points} points per channel; lengthen the duration")
        return self

    def _transient_consistent(self) -> None:
        """The checks of a ``[transient]`` spec: what steady samples take and a run-up does not, and the
        simulator's own rate rule, so that nothing is refused after the file is written."""
        op, m = self.operating, self.measurement
        if op.speed_rpm is not None:
            raise ValueError("operating.speed_rpm: a run-up's or coast-down's speed is its [transient] profile's; "
                             "remove operating.speed_rpm")
        given = [k for k in ("duration_s", "duration_revs") if getattr(m, k) is not None]
        if given:
            raise ValueError(f"measurement.{given[0]}: a transient sample lasts its [transient] profile "
                             "(duration_s of a ramp, the last of times_s); remove it")
        if m.speed_fluctuation:
            raise ValueError("measurement.speed_fluctuation: a transient sample's speed is its profile's; "
                             "set it to 0 or remove it")
        set_sim = sorted(set(STEADY_ONLY_SIMULATION) & self.simulation.model_fields_set)
        if set_sim:
            raise ValueError(f"simulation.{set_sim[0]} applies to steady samples; a run-up starts settled after "
                             "transient.settle_revs revolutions and is recorded at measurement.sample_rate_hz "
                             "(rtol and atol apply)")
        top = max(self.transient.profile.speeds_rpm)  # type: ignore[union-attr]
        need = 8.0 * top / 60.0
        if m.sample_rate_hz < need:
            raise ValueError(f"measurement.sample_rate_hz = {m.sample_rate_hz:g} Hz is too low for a run-up to "
                             f"{top:g} r/min: the transient simulator needs ≥ {need:g} Hz (8 samples per "
                             "revolution at the top speed)")

    @property
    def speed_bounds_rpm(self) -> tuple[float, float]:
        """Slowest and fastest running speed of any sample (r/min): the operating range, or the profile's."""
        if self.transient is not None:
            n = self.transient.profile.speeds_rpm
            return float(min(n)), float(max(n))
        assert self.operating.speed_rpm is not None  # validated
        return _bounds(self.operating.speed_rpm)

    @property
    def n_points(self) -> int:
        """Points per channel: fixed for the whole dataset.

        With ``duration_revs`` the record covers at least that many revolutions
        at the slowest speed of the spec (faster samples cover more). A transient
        sample covers its profile up to its last whole revolution (as
        :func:`rotordiag.simulator.transient.simulate_transient` records it).
        """
        m = self.measurement
        if self.transient is not None:
            last_rev_s = float(self.transient.profile.revolution_times_s()[-1])
            return int(math.ceil(last_rev_s * m.sample_rate_hz - 1e-9))  # the samples before the last mark
        if m.duration_s is not None:
            return int(round(m.duration_s * m.sample_rate_hz))
        s_lo, _ = self.speed_bounds_rpm
        assert m.duration_revs is not None  # exactly one of the two is set (validated)
        return int(math.ceil(m.duration_revs * 60.0 * m.sample_rate_hz / s_lo - 1e-9))


#: keys a spec writer reaches for to ask for run-ups or coast-downs outside the ``[transient]`` table
_TRANSIENT_KEYS = frozenset({"profile", "speed_profile", "ramp", "runup", "run_up", "coast_down", "coastdown"})


def _one_error(err: Mapping[str, Any]) -> str:
    loc = ".".join(str(p) for p in err["loc"])
    msg = err["msg"].removeprefix("Value error, ")
    if err["type"] == "extra_forbidden" and err["loc"] and str(err["loc"][-1]) in _TRANSIENT_KEYS:
        msg = ("run-ups and coast-downs go in a [transient] table: start_rpm, end_rpm and duration_s (a linear "
               "ramp) or times_s and speeds_rpm (a table), with settle_revs; operating.speed_rpm and the "
               "measurement's duration are then the profile's (docs/datasets.md)")
    elif err["type"] == "extra_forbidden":
        msg = "unknown key (check the spelling; see examples/dataset_small.toml)"
    elif err["type"] == "missing":
        msg = "required key is missing"
    return f"{loc}: {msg}" if loc else msg


def _format_validation_error(exc: ValidationError) -> str:
    lines = dict.fromkeys("  " + _one_error(e) for e in exc.errors())
    return "invalid dataset spec:\n" + "\n".join(lines)


def parse_spec(text: str, *, base_dir: str | Path | None = None) -> ResolvedSpec:
    """Validate TOML text; resolve the plant file relative to ``base_dir``.

    Raises
    ------
    SpecError
        For invalid TOML, unknown keys, empty ranges, values outside MODEL.md's
        ranges, an unreadable plant file or an invalid plant.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"the spec is not valid TOML: {exc}") from None
    try:
        spec = DatasetSpec.model_validate(data)
    except ValidationError as exc:
        raise SpecError(_format_validation_error(exc)) from None
    return ResolvedSpec(spec, text, Path(base_dir) if base_dir is not None else Path.cwd())


def load_spec(path: str | Path) -> ResolvedSpec:
    """Read and validate a spec file (see :func:`parse_spec`)."""
    path = Path(path)
    if not path.is_file():
        raise SpecError(f"spec file {str(path)!r} does not exist")
    return parse_spec(path.read_text(), base_dir=path.resolve().parent)


class ResolvedSpec:
    """A validated spec plus its resolved base plant(s) and identity hash.

    Attributes
    ----------
    spec : DatasetSpec
    text : str
        The TOML text as written (stored in the HDF5 file).
    sources : dict[str, simulator.Plant | simulator.train.plant.TrainPlant]
        Every base plant (a shaft train's with ``plant.model = "train"``) by its label (``"default"``, ``"file:NAME"``, ``"preset:NAME"``,
        ``"shaftline:NAME"``, ``"shaftline:inline"``), ``plant.set`` applied: one entry, or the
        members of a machine family in the spec's order.
    source_weights : dict[str, float]
        Probability of each source (sums to 1).
    base_plant : simulator.Plant
        The first source (the only one unless the spec names a family).
    spec_hash : str
        SHA-256 of the normalised spec and the resolved base plants: comments,
        formatting and the folders of the files do not change it, any value does.
    """

    def __init__(self, spec: DatasetSpec, text: str, base_dir: Path):
        self.spec = spec
        self.text = text
        ps = spec.plant
        try:
            members = _plant_members(ps, base_dir)
            self.sources = {label: (p.replace(**ps.set) if ps.set else p) for label, (p, _) in members.items()}
        except (ValueError, TypeError) as exc:
            raise SpecError(f"invalid dataset spec:\n  plant: {exc}") from None
        total = sum(w for _, w in members.values())
        self.source_weights = {label: w / total for label, (_, w) in members.items()}
        self.base_plant = next(iter(self.sources.values()))
        for label, plant in self.sources.items():
            _check_extremes(plant, ps, label if len(self.sources) > 1 else "")
            if ps.model == "train" and max(spec.measurement.bearings) > plant.n_bearings:
                raise SpecError(f"invalid dataset spec:\n  measurement.bearings {spec.measurement.bearings}: "
                                f"the train {label} has bearings 1..{plant.n_bearings} only (its exciter is "
                                f"overhung on its coupling-end bearing)")
        dumped = spec.model_dump(mode="json", exclude={"plant": {"file", "shaftline", "shaftlines"}})
        for key in ("presets", "scale"):  # absent when unused, so specs written before them keep their hash
            if not dumped["plant"].get(key):
                dumped["plant"].pop(key, None)
        if dumped["plant"].get("model") == "lumped":  # likewise
            dumped["plant"].pop("model")
        if dumped["operating"].get("angular_misalignment_mrad") == 0.0:  # likewise
            dumped["operating"].pop("angular_misalignment_mrad")
        if dumped["simulation"].get("transient_stop") == "fixed":  # the transient before it existed: same hash
            dumped["simulation"].pop("transient_stop")
        if dumped.get("transient") is None:  # steady specs keep the hash they had before [transient] existed
            dumped.pop("transient", None)
        if dumped["simulation"].get("integrator") == "auto":  # likewise (the per-sample code version tells runs apart)
            dumped["simulation"].pop("integrator")
        canonical: dict[str, Any] = {"spec": dumped, "base_plant": _hashed_plant(self.base_plant)}
        if ps.is_family:
            canonical["sources"] = {k: [_hashed_plant(p), self.source_weights[k]] for k, p in self.sources.items()}
        blob = json.dumps(canonical, sort_keys=True, allow_nan=True).encode()
        self.spec_hash = hashlib.sha256(blob).hexdigest()


def _hashed_plant(plant: Any) -> dict[str, Any]:
    """The plant as the spec hash sees it: ``exciter_bearing_span_m`` (added with the angular offset)
    is left out at its default, so specs hashed before it keep their hash."""
    d = plant.to_dict()
    if d.get("exciter_bearing_span_m") == DEFAULT_EXCITER_BEARING_SPAN_M:
        d.pop("exciter_bearing_span_m")
    return d


def _plant_members(ps: PlantSpec, base_dir: Path) -> dict[str, tuple[Any, float]]:
    """label → (plant before ``set``, weight) of the spec's base plant or family (raises ValueError)."""
    from rotordiag.simulator import Plant, shaftline
    from rotordiag.simulator.train.plant import TrainPlant

    lumped = ps.model == "lumped"

    def plant_of(line: Any) -> Any:
        return shaftline.to_plant(line) if lumped else TrainPlant.of(line)

    def path(name: str) -> Path:
        f = Path(name)
        return f if f.is_absolute() else base_dir / f

    def members(v: list[str] | dict[str, float] | None) -> list[tuple[str, float]]:
        if v is None:
            return []
        return [(k, 1.0) for k in v] if isinstance(v, list) else [(k, float(w)) for k, w in v.items()]

    if ps.shaftline is not None:
        if isinstance(ps.shaftline, dict):
            return {"shaftline:inline": (plant_of(shaftline.ShaftLine.from_dict(ps.shaftline)), 1.0)}
        f = path(ps.shaftline)
        return {f"shaftline:{f.name}": (plant_of(shaftline.ShaftLine.from_file(f)), 1.0)}
    if ps.preset is not None:
        return {f"preset:{ps.preset}": (plant_of(shaftline.preset(ps.preset)), 1.0)}
    if ps.file is not None:
        f = path(ps.file)
        return {f"file:{f.name}": (Plant.from_file(f), 1.0)}
    if not ps.is_family:
        return {"default": (Plant.default(), 1.0)}
    out: dict[str, tuple[Any, float]] = {}
    for name, w in members(ps.presets):
        try:
            out[f"preset:{name}"] = (plant_of(shaftline.preset(name)), w)
        except ValueError as exc:
            raise ValueError(f"presets: {exc}") from None
    for name, w in members(ps.shaftlines):
        f = path(name)
        label = f"shaftline:{f.name}"
        if label in out:
            raise ValueError(f"shaftlines: two files are named {f.name!r}; rename one (the file name labels "
                             "the samples)")
        try:
            out[label] = (plant_of(shaftline.ShaftLine.from_file(f)), w)
        except ValueError as exc:
            raise ValueError(f"shaftlines: {exc}") from None
    if sum(w for _, w in out.values()) <= 0:
        raise ValueError("presets/shaftlines: the weights are all zero")
    return out


def _check_extremes(plant: Any, ps: PlantSpec, label: str) -> None:
    """Refuse a perturbation or scale range whose extremes make an invalid plant (each field alone)."""
    base = plant.to_dict()
    where = f" (base plant {label})" if label else ""
    changes: list[tuple[str, str, float]] = []
    for name, r in ps.perturb.items():
        changes += [(name, f"plant.perturb.{name} = {r}", 1 + sign * r) for sign in (-1.0, 1.0)]
    for name, rng in ps.scale.items():
        changes += [(name, f"plant.scale.{name} = {rng.min:g}..{rng.max:g}", f) for f in (rng.min, rng.max)]
    for name, what, factor in changes:
        v = base[name]
        scaled = [x * factor for x in v] if isinstance(v, list) else v * factor
        try:
            plant.replace(**{name: scaled})
        except (ValueError, TypeError) as exc:
            raise SpecError(f"invalid dataset spec:\n  {what} gives an invalid plant at its extreme{where}: "
                            f"{exc}") from None
