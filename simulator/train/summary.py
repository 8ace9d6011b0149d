"""What a plant engineer checks first about a shaft train: its stations, its bearings with their static
loads, eccentricities and attitude angles, and its stability margin at a speed.

One function, :func:`train_summary`, the same for every door (the service's ``POST /trains/summary`` and
the web page's plant card): the static state of :func:`.static.static_state` and the least-damped mode of
:func:`.stability.stability` at ``speed_rpm``, in plain numbers with their units.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .fe import assemble
from .model import Train
from .stability import speed_warning, stability
from .static import static_state

__all__ = ["BearingSummary", "RotorSummary", "TrainSummary", "train_summary"]


@dataclass(frozen=True)
class RotorSummary:
    """One rotor: its stations, length and mass (shaft and disks)."""

    name: str
    n_stations: int
    length_m: float
    mass_kg: float
    n_bearings: int


@dataclass(frozen=True)
class BearingSummary:
    """One bearing at the static state: the journal's load on it (kN, + up / + in x), |e|/c, attitude."""

    name: str
    rotor: str
    type: str
    z_m: float
    load_vertical_kn: float
    load_horizontal_kn: float
    eccentricity: float
    attitude_angle_deg: float


@dataclass(frozen=True)
class TrainSummary:
    """The train at ``speed_rpm``: rotors, bearings and the stability margin (log decrement of the
    least-damped mode, its frequency and whirl direction); ``warning`` when beyond the threshold."""

    speed_rpm: float
    n_stations: int
    coupling: str
    rotors: list[RotorSummary]
    bearings: list[BearingSummary]
    log_decrement: float
    mode_frequency_hz: float
    mode_forward: bool
    stable: bool
    warning: str | None


def _mass_kg(rotor) -> float:
    rho = rotor.material.density_kg_m3
    shaft = sum(rho * math.pi / 4 * (e.outer_diameter_m**2 - e.inner_diameter_m**2) * e.length_m
                for e in rotor.elements)
    return float(shaft + sum(d.mass_kg for d in rotor.disks))


def train_summary(train: Train, speed_rpm: float) -> TrainSummary:
    """:class:`TrainSummary` of ``train`` at ``speed_rpm`` (a :class:`.model.TrainError` saying what to
    fix when the static state cannot be found, e.g. a journal pushed out of its clearance)."""
    asm = assemble(train)
    st = static_state(asm, speed_rpm)
    stab = stability(asm, speed_rpm, static=st)
    z = train.support_z_m()
    bearings = []
    for b, (i, s) in enumerate(train.supports()):
        load = st.bearing_load_n[b]
        bearings.append(BearingSummary(
            name=s.name or f"B{b + 1}", rotor=train.rotors[i].name, type=type(s.bearing).__name__,
            z_m=float(z[b]), load_vertical_kn=float(load[1]) / 1e3, load_horizontal_kn=float(load[0]) / 1e3,
            eccentricity=float(st.eccentricity[b]), attitude_angle_deg=float(st.attitude_angle_deg[b])))
    rotors = [RotorSummary(r.name, r.n_stations, float(r.length_m), _mass_kg(r), len(r.supports))
              for r in train.rotors]
    kinds = sorted({c.kind for c in train.couplings}) or ["none"]
    warn = None if stab.stable else speed_warning(asm, speed_rpm)
    return TrainSummary(speed_rpm=float(speed_rpm), n_stations=int(sum(r.n_stations for r in train.rotors)),
                        coupling="/".join(kinds), rotors=rotors, bearings=bearings,
                        log_decrement=float(stab.log_decrement), mode_frequency_hz=float(stab.frequency_hz),
                        mode_forward=bool(stab.forward), stable=bool(stab.stable), warning=warn)


