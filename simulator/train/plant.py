"""A shaft train as a dataset's plant: a base shaft line and the values a machine family varies around it.

A dataset samples plants by perturbing and scaling flat named values (``simulator.dataset.design``). For a
shaft train those values are the ones a plant's drawings carry and manufacturing varies: the rotors' spans
and largest diameters, their body masses, the overhangs from the coupling-end bearings to the flange, bearing
sizes, the clearance, the oil, the coupling's stiffnesses, the generator's two-pole asymmetry ρ, the rotor
damping and the balance grade. :class:`TrainPlant` holds the base line and those values; :meth:`TrainPlant.line`
applies them to the line (every segment of a rotor scaled by the rotor's span or diameter ratio, body masses
and their positions with them), so each sample records real values, never factors.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass
from typing import Any

from ..shaftline import Rotor as LineRotor
from ..shaftline import ShaftLine, balance_grade_unbalance_kg_m, rotor_mass_kg

__all__ = ["TRAIN_PERTURBABLE", "TrainPlant", "rotor_mass_kg", "is_train_plant"]

#: The values of a :class:`TrainPlant` that a dataset spec may perturb or scale (tuples per bearing / rotor).
TRAIN_PERTURBABLE: tuple[str, ...] = (
    "generator_span_m", "exciter_span_m", "generator_diameter_m", "exciter_diameter_m",
    "generator_body_mass_kg", "exciter_body_mass_kg", "overhang_m", "bearing_diameter_m", "bearing_length_m",
    "clearance_m", "viscosity_pa_s", "coupling_stiffness_n_m", "coupling_angular_stiffness_n_m_rad",
    "generator_asymmetry", "damping_ratio", "balance_grade_mm_s",
)

#: ISO 21940-11 balance grade of a sample's generator unbalance unless the spec sets one (G2.5: turbo-generators)
DEFAULT_BALANCE_GRADE_MM_S = 2.5


def is_train_plant(plant_dict: dict[str, Any]) -> bool:
    """Whether a dataset sample's plant values describe a shaft train (else the paper's lumped plant)."""
    return plant_dict.get("model") == "train"


def _max_d(r: LineRotor) -> float:
    return max(d for _, d in r.segments)


@dataclass(frozen=True)
class TrainPlant:
    """A base shaft line and the values a dataset varies (module docstring). Build with :meth:`of`."""

    base: ShaftLine
    generator_span_m: float
    exciter_span_m: float
    generator_diameter_m: float
    exciter_diameter_m: float
    generator_body_mass_kg: float
    exciter_body_mass_kg: float
    overhang_m: list[float]
    bearing_diameter_m: list[float]
    bearing_length_m: list[float]
    clearance_m: float
    viscosity_pa_s: float
    coupling_stiffness_n_m: float
    coupling_angular_stiffness_n_m_rad: float
    generator_asymmetry: float
    damping_ratio: float
    balance_grade_mm_s: float = DEFAULT_BALANCE_GRADE_MM_S

    @classmethod
    def of(cls, line: ShaftLine) -> TrainPlant:
        """The plant of a shaft line at its own values."""
        return cls(
            base=line, generator_span_m=line.generator.span_m, exciter_span_m=line.exciter.span_m,
            generator_diameter_m=_max_d(line.generator), exciter_diameter_m=_max_d(line.exciter),
            generator_body_mass_kg=sum(m for _, m in line.generator.body_masses),
            exciter_body_mass_kg=sum(m for _, m in line.exciter.body_masses),
            overhang_m=[sum(s[0] for s in line.generator.overhang), sum(s[0] for s in line.exciter.overhang)],
            bearing_diameter_m=list(line.bearing_diameter_m), bearing_length_m=list(line.bearing_length_m),
            clearance_m=line.clearance_m, viscosity_pa_s=line.viscosity_pa_s,
            coupling_stiffness_n_m=line.coupling_stiffness_n_m,
            coupling_angular_stiffness_n_m_rad=line.coupling_angular_stiffness_n_m_rad,
            generator_asymmetry=line.generator_asymmetry, damping_ratio=line.damping_ratio)

    def __post_init__(self) -> None:
        self.line()  # every value checked by the shaft line's own validation (a ValueError saying which)

    @staticmethod
    def field_names() -> list[str]:
        return ["model", "shaftline", *TRAIN_PERTURBABLE]

    def replace(self, **changes: Any) -> TrainPlant:
        """A validated copy with some values changed (unknown names raise ``ValueError``)."""
        unknown = set(changes) - set(TRAIN_PERTURBABLE)
        if unknown:
            raise ValueError(f"unknown train plant value(s) {sorted(unknown)}; known: {list(TRAIN_PERTURBABLE)}")
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """``model = "train"``, the base ``shaftline`` (its tables) and the flat values."""
        d: dict[str, Any] = {"model": "train", "shaftline": self.base.to_dict()}
        for name in TRAIN_PERTURBABLE:
            v = getattr(self, name)
            d[name] = [float(x) for x in v] if isinstance(v, (list, tuple)) else float(v)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TrainPlant:
        if not is_train_plant(d):
            raise ValueError("not a train plant (model must be \"train\")")
        unknown = set(d) - set(cls.field_names())
        if unknown:
            raise ValueError(f"unknown train plant value(s) {sorted(unknown)}")
        base = ShaftLine.from_dict(d["shaftline"])
        own = cls.of(base)
        return own.replace(**{k: d[k] for k in TRAIN_PERTURBABLE if k in d})

    def plant_id(self) -> str:
        """Short stable hash of the values (for grouping samples by plant)."""
        return hashlib.sha256(json.dumps(self.to_dict(), sort_keys=True).encode()).hexdigest()[:16]

    def line(self, coupling: str | None = None) -> ShaftLine:
        """The shaft line with these values applied (``coupling``: "rigid"/"flexible" overrides its type)."""
        b = self.base

        def scaled(r: LineRotor, span: float, dia: float, mass: float, over: float, what: str) -> LineRotor:
            for name, v in ((f"{what}_span_m", span), (f"{what}_diameter_m", dia)):
                if not (math.isfinite(v) and v > 0):
                    raise ValueError(f"{name} must be a positive number, got {v!r}")
            m0 = sum(m for _, m in r.body_masses)
            o0 = sum(s[0] for s in r.overhang)
            if not (math.isfinite(mass) and mass >= 0) or (m0 == 0 and mass > 0):
                raise ValueError(f"{what}_body_mass_kg must be ≥ 0 (and 0 when the base line has none), got {mass!r}")
            if not (math.isfinite(over) and over >= 0) or (o0 == 0 and over > 0):
                raise ValueError(f"overhang_m of the {what} must be ≥ 0 (and 0 when the base line has none), "
                                 f"got {over!r}")
            fl, fd = span / r.span_m, dia / _max_d(r)
            fm = mass / m0 if m0 else 1.0
            fo = over / o0 if o0 else 1.0
            return LineRotor(
                segments=tuple((length * fl, d * fd) for length, d in r.segments),
                body_masses=tuple((x * fl, m * fm) for x, m in r.body_masses),
                overhang=tuple((length * fo, d * fd) for length, d in r.overhang),
                disks=tuple((x * fl, m, jp, jt) for x, m, jp, jt in r.disks))

        if len(self.overhang_m) != 2 or len(self.bearing_diameter_m) != 4 or len(self.bearing_length_m) != 4:
            raise ValueError("overhang_m needs 2 values (generator, exciter); bearing_diameter_m and "
                             "bearing_length_m 4 (bearings 1..4)")
        d = b.to_dict()
        gen = scaled(b.generator, self.generator_span_m, self.generator_diameter_m, self.generator_body_mass_kg,
                     self.overhang_m[0], "generator")
        exc = scaled(b.exciter, self.exciter_span_m, self.exciter_diameter_m, self.exciter_body_mass_kg,
                     self.overhang_m[1], "exciter")
        line = ShaftLine.from_dict({
            **d,
            "generator": {"segments": [list(s) for s in gen.segments], "body_masses": [list(m) for m in gen.body_masses],
                          "overhang": [list(s) for s in gen.overhang], "disks": [list(k) for k in gen.disks]},
            "exciter": {"segments": [list(s) for s in exc.segments], "body_masses": [list(m) for m in exc.body_masses],
                        "overhang": [list(s) for s in exc.overhang], "disks": [list(k) for k in exc.disks]},
            "bearings": {**d["bearings"], "diameter_m": list(self.bearing_diameter_m),
                         "length_m": list(self.bearing_length_m), "clearance_m": self.clearance_m},
            "oil": {"viscosity_pa_s": self.viscosity_pa_s},
            "coupling": {**d["coupling"], "type": coupling or b.coupling, "stiffness_n_m": self.coupling_stiffness_n_m,
                         "angular_stiffness_n_m_rad": self.coupling_angular_stiffness_n_m_rad},
            "generator_asymmetry": self.generator_asymmetry, "damping_ratio": self.damping_ratio,
        })
        if not (math.isfinite(self.balance_grade_mm_s) and 0.0 <= self.balance_grade_mm_s <= 100.0):
            raise ValueError(f"balance_grade_mm_s must be within 0..100 mm/s (ISO 21940 G), got "
                             f"{self.balance_grade_mm_s!r}")
        return line

    @property
    def n_bearings(self) -> int:
        """Bearings that carry the train (3 when the exciter is overhung on its coupling-end bearing)."""
        return sum(t != "none" for t in self.base.bearing_types)

    def unbalance_kg_m(self, speed_rpm: float) -> float:
        """The generator's unbalance U = G·M/Ω for the balance grade G at ``speed_rpm`` (kg·m)."""
        return balance_grade_unbalance_kg_m(self.line().generator, self.balance_grade_mm_s, speed_rpm,
                                            self.base.material)
