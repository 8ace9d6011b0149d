"""The description of a shaft train: rotors of beam elements, disks, bearings, couplings, misalignment.

Coordinates: z along the shaft line (the first rotor's first station at z = 0), x horizontal, y
vertical up; the shaft spins about +z (from +x toward +y). Every rotor's stations are numbered from
its coupling-free end (the first rotor) or from its coupling flange (the rotors after it); the
coupling joins the last station of rotor i to the first station of rotor i + 1. Bearing centres are
given per bearing (``centre_x_m``, ``centre_y_m``), so a misalignment is a set of bearing positions.
All quantities are SI.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np

#: Coupling kinds: ``rigid`` (bolted flanges: displacement and slope continuous) or ``flexible``.
COUPLING_KINDS = ("rigid", "flexible")
#: the most stations a train may have (1600 DOFs): its dense static solution, modes and reduction grow as the cube of
#: the DOFs (a 40-node train takes well under a second, 400 stations about a thousand times its work)
MAX_TRAIN_STATIONS = 400


class TrainError(ValueError):
    """A train description that cannot be built; the message says what to fix."""


class Bearing(Protocol):
    """What the train needs of a bearing (``rotordiag.simulator.bearings`` provides them)."""

    clearance_m: float

    def force_n(self, x_m: float, y_m: float, vx_m_s: float, vy_m_s: float,
                speed_rad_s: float) -> tuple[float, float]: ...

    def coefficients(self, x_m: float, y_m: float, speed_rad_s: float) -> tuple[np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class Material:
    """Linear-elastic isotropic shaft material."""

    young_pa: float = 2.11e11
    shear_pa: float = 8.12e10
    density_kg_m3: float = 7810.0

    @property
    def poisson(self) -> float:
        return self.young_pa / (2.0 * self.shear_pa) - 1.0


STEEL = Material()


@dataclass(frozen=True)
class ShaftElement:
    """One Timoshenko beam element: a hollow or solid circular section of constant diameter.

    ``asymmetry`` is the rotating-frame bending-stiffness asymmetry ρ of the element (a two-pole
    generator body's winding slots: stiffnesses EI(1 ± ρ) about its two principal axes).
    """

    length_m: float
    outer_diameter_m: float
    inner_diameter_m: float = 0.0
    asymmetry: float = 0.0


@dataclass(frozen=True)
class Disk:
    """A rigid body at a station: mass, polar and transverse (diametral) moments of inertia."""

    station: int
    mass_kg: float
    polar_kg_m2: float = 0.0
    transverse_kg_m2: float = 0.0


@dataclass(frozen=True)
class Support:
    """A bearing under a station, its centre at (``centre_x_m``, ``centre_y_m``) from the shaft-line axis."""

    station: int
    bearing: Any
    centre_x_m: float = 0.0
    centre_y_m: float = 0.0
    name: str = ""


@dataclass(frozen=True)
class Unbalance:
    """An unbalance ``amount_kg_m`` at a station, along +x at t = 0 turned by ``angle_rad`` in the
    direction of rotation."""

    station: int
    amount_kg_m: float
    angle_rad: float = 0.0


@dataclass(frozen=True)
class Rotor:
    """One rotor: beam elements (stations 0..n), disks, bearings and unbalances at stations.

    ``stiff_axis_rad`` is the angle of the stiffer principal axis (EI(1 + ρ)) from +x at t = 0.
    """

    name: str
    elements: tuple[ShaftElement, ...]
    disks: tuple[Disk, ...] = ()
    supports: tuple[Support, ...] = ()
    unbalances: tuple[Unbalance, ...] = ()
    material: Material = STEEL
    stiff_axis_rad: float = 0.0

    @property
    def n_stations(self) -> int:
        return len(self.elements) + 1

    @property
    def length_m(self) -> float:
        return float(sum(e.length_m for e in self.elements))

    def station_z_m(self) -> np.ndarray:
        """Axial position of each station from the rotor's station 0, m."""
        return np.concatenate([[0.0], np.cumsum([e.length_m for e in self.elements])])


@dataclass(frozen=True)
class Coupling:
    """The coupling between the last station of one rotor and the first of the next.

    ``rigid``: bolted flanges, the two stations are one node. ``flexible``: two nodes joined by a
    lateral and an angular spring-damper; under a parallel offset ``kinematic_offset_m`` a
    double-engagement coupling's floating member runs round a circle of that diameter at 2Ω,
    which enters as the relative hub displacement u(t) = (δ/2)·(cos(2Ωt + ψ + γ), sin(2Ωt + ψ + γ))
    (the paper model's ``flexible`` forcing, docs/model.md), γ = ``kinematic_direction_rad``.
    """

    kind: str = "rigid"
    lateral_stiffness_n_m: float = 0.0
    angular_stiffness_n_m_rad: float = 0.0
    lateral_damping_n_s_m: float = 0.0
    angular_damping_n_m_s_rad: float = 0.0
    kinematic_offset_m: float = 0.0
    kinematic_phase_rad: float = 0.0
    kinematic_direction_rad: float = 0.0


@dataclass(frozen=True)
class Train:
    """Rotors in a line with the couplings between them.

    ``internal_damping_s``: structural (rotating, stiffness-proportional) damping of the shafts,
    the force −η·K_shaft·(q̇ − Ω × q) in the rotating frame; ``rayleigh_mass_1_s`` and
    ``rayleigh_stiffness_s``: stationary proportional damping α·M + β·K_shaft.
    """

    rotors: tuple[Rotor, ...]
    couplings: tuple[Coupling, ...] = ()
    gravity_m_s2: float = 9.81
    internal_damping_s: float = 0.0
    rayleigh_mass_1_s: float = 0.0
    rayleigh_stiffness_s: float = 0.0

    def __post_init__(self) -> None:
        validate(self)

    def rotor_start_z_m(self) -> np.ndarray:
        """Axial position of each rotor's station 0 in the train, m."""
        return np.concatenate([[0.0], np.cumsum([r.length_m for r in self.rotors])[:-1]])

    def supports(self) -> list[tuple[int, Support]]:
        """(rotor index, support) for every bearing, in train order."""
        return [(i, s) for i, r in enumerate(self.rotors) for s in r.supports]

    def support_z_m(self) -> np.ndarray:
        z0 = self.rotor_start_z_m()
        return np.array([z0[i] + self.rotors[i].station_z_m()[s.station] for i, s in self.supports()])


def _positive(value: float, what: str) -> None:
    if not (np.isfinite(value) and value > 0):
        raise TrainError(f"{what} must be a positive finite number (got {value!r})")


def _non_negative(value: float, what: str) -> None:
    if not (np.isfinite(value) and value >= 0):
        raise TrainError(f"{what} must be zero or a positive finite number (got {value!r})")


def validate(train: Train) -> None:
    """Check a train: every message names the rotor or item and what to change."""
    if not train.rotors:
        raise TrainError("a train needs at least one rotor")
    if len(train.couplings) != len(train.rotors) - 1:
        raise TrainError(f"{len(train.rotors)} rotors need {len(train.rotors) - 1} coupling(s), "
                         f"one between each pair (got {len(train.couplings)})")
    n_stations = sum(len(r.elements) + 1 for r in train.rotors)
    if n_stations > MAX_TRAIN_STATIONS:
        raise TrainError(f"the train has {n_stations} stations, more than {MAX_TRAIN_STATIONS}: too large to solve and "
                         f"reduce within the limits; use longer elements (a few per span between bearings suffice for "
                         f"the first modes) or fewer rotors")
    _non_negative(train.gravity_m_s2, "gravity_m_s2")
    _non_negative(train.internal_damping_s, "internal_damping_s")
    _non_negative(train.rayleigh_mass_1_s, "rayleigh_mass_1_s")
    _non_negative(train.rayleigh_stiffness_s, "rayleigh_stiffness_s")
    for r in train.rotors:
        where = f"rotor {r.name!r}"
        if not r.elements:
            raise TrainError(f"{where} has no shaft elements: give at least one (length, diameter)")
        for k, e in enumerate(r.elements):
            _positive(e.length_m, f"{where} element {k} length_m")
            _positive(e.outer_diameter_m, f"{where} element {k} outer_diameter_m")
            _non_negative(e.inner_diameter_m, f"{where} element {k} inner_diameter_m")
            if e.inner_diameter_m >= e.outer_diameter_m:
                raise TrainError(f"{where} element {k}: the bore ({e.inner_diameter_m} m) must be smaller than "
                                 f"the outer diameter ({e.outer_diameter_m} m)")
            if not (0.0 <= e.asymmetry < 0.5):
                raise TrainError(f"{where} element {k}: asymmetry must be in [0, 0.5) (got {e.asymmetry})")
        _positive(r.material.young_pa, f"{where} material young_pa")
        _positive(r.material.shear_pa, f"{where} material shear_pa")
        _positive(r.material.density_kg_m3, f"{where} material density_kg_m3")
        n = r.n_stations
        for item, label in [(d, "disk") for d in r.disks] + [(s, "bearing") for s in r.supports] + \
                [(u, "unbalance") for u in r.unbalances]:
            if not (isinstance(item.station, int | np.integer) and 0 <= item.station < n):
                raise TrainError(f"{where}: a {label} at station {item.station} is beyond the shaft "
                                 f"(stations 0..{n - 1}); put it on the shaft or lengthen the rotor")
        for d in r.disks:
            _positive(d.mass_kg, f"{where} disk at station {d.station} mass_kg")
            _non_negative(d.polar_kg_m2, f"{where} disk at station {d.station} polar_kg_m2")
            _non_negative(d.transverse_kg_m2, f"{where} disk at station {d.station} transverse_kg_m2")
        for u in r.unbalances:
            _non_negative(u.amount_kg_m, f"{where} unbalance at station {u.station} amount_kg_m")
        if not r.supports:
            raise TrainError(f"{where} has no bearing: every rotor needs at least one bearing under it "
                             f"(two, or one when it is overhung on a rigid coupling)")
        stations = [s.station for s in r.supports]
        if len(set(stations)) != len(stations):
            raise TrainError(f"{where}: two bearings at the same station {stations}; give each its own station")
        for s in r.supports:
            for attr in ("clearance_m",):
                _positive(float(getattr(s.bearing, attr)), f"{where} bearing at station {s.station} {attr}")
            if not (np.isfinite(s.centre_x_m) and np.isfinite(s.centre_y_m)):
                raise TrainError(f"{where} bearing at station {s.station}: centre position must be finite")
    for i, c in enumerate(train.couplings):
        if c.kind not in COUPLING_KINDS:
            raise TrainError(f"coupling {i}: kind must be one of {COUPLING_KINDS} (got {c.kind!r})")
        for name in ("lateral_stiffness_n_m", "angular_stiffness_n_m_rad", "lateral_damping_n_s_m",
                     "angular_damping_n_m_s_rad", "kinematic_offset_m"):
            _non_negative(getattr(c, name), f"coupling {i} {name}")
        if c.kind == "flexible":
            _positive(c.lateral_stiffness_n_m, f"coupling {i} (flexible) lateral_stiffness_n_m")
    for i, r in enumerate(train.rotors):
        if len(r.supports) == 1:
            rigid_neighbour = (i > 0 and train.couplings[i - 1].kind == "rigid") or \
                (i < len(train.couplings) and train.couplings[i].kind == "rigid")
            flex_neighbour = (i > 0 and train.couplings[i - 1].angular_stiffness_n_m_rad > 0) or \
                (i < len(train.couplings) and train.couplings[i].angular_stiffness_n_m_rad > 0)
            if not (rigid_neighbour or flex_neighbour):
                raise TrainError(f"rotor {r.name!r} has one bearing and no coupling that can carry a moment: "
                                 f"give it a second bearing or couple it rigidly (or with angular stiffness)")


def misaligned(train: Train, offset_m: float = 0.0, angle_rad: float = 0.0, direction_rad: float = -math.pi / 2,
               rotor: int = 1) -> Train:
    """The train with ``rotor``'s bearings (and every rotor after it) moved as a rigid line: a parallel offset
    ``offset_m`` and an angular offset ``angle_rad`` (rad, positive = the line rising away from the coupling)
    at the coupling in front of ``rotor``, both along ``direction_rad`` (from +x toward +y; the default
    −π/2 is downward). Moves are added to the bearings' given centres."""
    if not (0 < rotor < len(train.rotors)):
        raise TrainError(f"misalignment is set at the coupling in front of a rotor 1..{len(train.rotors) - 1} "
                         f"(got rotor {rotor})")
    zc = float(train.rotor_start_z_m()[rotor])
    e = np.array([math.cos(direction_rad), math.sin(direction_rad)])
    z0 = train.rotor_start_z_m()
    rotors = list(train.rotors)
    for i in range(rotor, len(rotors)):
        r = rotors[i]
        zs = z0[i] + r.station_z_m()
        sup = tuple(replace(s, centre_x_m=s.centre_x_m + (offset_m + angle_rad * (zs[s.station] - zc)) * e[0],
                            centre_y_m=s.centre_y_m + (offset_m + angle_rad * (zs[s.station] - zc)) * e[1])
                    for s in r.supports)
        rotors[i] = replace(r, supports=sup)
    return replace(train, rotors=tuple(rotors))


def bearing_moved(train: Train, rotor: int, index: int, dx_m: float = 0.0, dy_m: float = 0.0) -> Train:
    """The train with bearing ``index`` of ``rotor`` moved by (``dx_m``, ``dy_m``)."""
    if not (0 <= rotor < len(train.rotors)) or not (0 <= index < len(train.rotors[rotor].supports)):
        raise TrainError(f"no bearing {index} on rotor {rotor}")
    r = train.rotors[rotor]
    sup = list(r.supports)
    s = sup[index]
    sup[index] = replace(s, centre_x_m=s.centre_x_m + dx_m, centre_y_m=s.centre_y_m + dy_m)
    rotors = list(train.rotors)
    rotors[rotor] = replace(r, supports=tuple(sup))
    return replace(train, rotors=tuple(rotors))


def uniform_elements(length_m: float, diameter_m: float, n: int, asymmetry: float = 0.0,
                     inner_diameter_m: float = 0.0) -> tuple[ShaftElement, ...]:
    """``n`` equal elements of one section over ``length_m``."""
    if n < 1:
        raise TrainError(f"a segment needs at least one element (got {n})")
    _positive(length_m, "segment length_m")
    return tuple(ShaftElement(length_m / n, diameter_m, inner_diameter_m, asymmetry) for _ in range(n))
