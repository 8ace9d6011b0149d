"""The description of a shaft train: rotors of beam elements, disks, bearings, couplings, misalignment.

Coordinates: z along the shaft line (the first rotor's first station at z = 0), x horizontal, y
vertical up; the shaft spins about +z (from +x toward +y). Every rotor's stations are numbered from
its coupling-free end (the first rotor) or from its coupling flange (the rotors after it); the
coupling joins the last station of rotor i to the first station of rotor i + 1. Bearing centres are
given per bearing (``centre_x_m``, ``centre_y_m``), so a misalignment is a set of bearing positions.
All quantities are SI. Every part checks its own fields when it is built (``__post_init__``), a
:class:`TrainError` naming the part, the field and the value; a rotor and the train check how their parts
fit together.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from numbers import Integral, Real
from typing import Any, Protocol

import numpy as np

#: Coupling kinds: ``rigid`` (bolted flanges: displacement and slope continuous) or ``flexible``.
COUPLING_KINDS = ("rigid", "flexible")
#: the most stations a train may have (1600 DOFs): its dense static solution, modes and reduction grow as the cube of
#: the DOFs (a 40-node train takes well under a second, 400 stations about a thousand times its work)
MAX_TRAIN_STATIONS = 400


class TrainError(ValueError):
    """A train description that cannot be built; the message says what to fix."""


#: what each rule of :func:`_check_fields` allows, and how its message says it
_RULES: dict[str, tuple[Callable[[float], bool], str]] = {
    "finite": (lambda v: True, "a finite number"),
    "positive": (lambda v: v > 0, "a positive finite number"),
    "non_negative": (lambda v: v >= 0, "zero or a positive finite number"),
    "asymmetry": (lambda v: 0 <= v < 0.5, "a number in [0, 0.5)"),
}


def _check_number(value: object, what: str, rule: str) -> None:
    """Refuse ``value`` (named ``what`` in the message) unless it is a real finite number ``rule`` allows."""
    ok, says = _RULES[rule]
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value) or not ok(float(value)):
        raise TrainError(f"{what} must be {says} (got {value!r})")


def _check_fields(item: object, where: str, **rules: str) -> None:
    """Every field ``name=rule`` of ``item``: one way of validating a train's parts (each in its
    ``__post_init__``), a :class:`TrainError` naming ``where``, the field and the value."""
    for name, rule in rules.items():
        _check_number(getattr(item, name), f"{where} {name}", rule)


def _check_station(item: Disk | Support | Unbalance) -> str:
    """Refuse a station that is not a whole number ≥ 0; return how messages name the part."""
    name = getattr(item, "name", "")
    where = type(item).__name__ + (f" {name!r}" if name else "")
    st = item.station
    if isinstance(st, bool) or not isinstance(st, Integral) or st < 0:
        raise TrainError(f"{where} station must be a whole number ≥ 0, a station of its rotor (got {st!r})")
    return f"{where} at station {st}"


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

    def __post_init__(self) -> None:
        _check_fields(self, "Material", young_pa="positive", shear_pa="positive", density_kg_m3="positive")

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

    def __post_init__(self) -> None:
        _check_fields(self, "ShaftElement", length_m="positive", outer_diameter_m="positive",
                      inner_diameter_m="non_negative", asymmetry="asymmetry")
        if self.inner_diameter_m >= self.outer_diameter_m:
            raise TrainError(f"ShaftElement inner_diameter_m must be smaller than outer_diameter_m "
                             f"(got {self.inner_diameter_m!r} ≥ {self.outer_diameter_m!r}): the bore is inside the shaft")


@dataclass(frozen=True)
class Disk:
    """A rigid body at a station: mass, polar and transverse (diametral) moments of inertia."""

    station: int
    mass_kg: float
    polar_kg_m2: float = 0.0
    transverse_kg_m2: float = 0.0

    def __post_init__(self) -> None:
        _check_fields(self, _check_station(self), mass_kg="positive", polar_kg_m2="non_negative",
                      transverse_kg_m2="non_negative")


@dataclass(frozen=True)
class Support:
    """A bearing under a station, its centre at (``centre_x_m``, ``centre_y_m``) from the shaft-line axis."""

    station: int
    bearing: Any
    centre_x_m: float = 0.0
    centre_y_m: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise TrainError(f"Support name must be a string (got {self.name!r})")
        where = _check_station(self)
        _check_fields(self, where, centre_x_m="finite", centre_y_m="finite")
        _check_number(getattr(self.bearing, "clearance_m", None), f"{where} bearing clearance_m", "positive")


@dataclass(frozen=True)
class Unbalance:
    """An unbalance ``amount_kg_m`` at a station, along +x at t = 0 turned by ``angle_rad`` in the
    direction of rotation."""

    station: int
    amount_kg_m: float
    angle_rad: float = 0.0

    def __post_init__(self) -> None:
        _check_fields(self, _check_station(self), amount_kg_m="non_negative", angle_rad="finite")


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

    def __post_init__(self) -> None:
        _check_rotor(self)

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

    def __post_init__(self) -> None:
        if not (isinstance(self.kind, str) and self.kind in COUPLING_KINDS):
            raise TrainError(f"Coupling kind must be one of {COUPLING_KINDS} (got {self.kind!r})")
        _check_fields(self, "Coupling", lateral_stiffness_n_m="non_negative", angular_stiffness_n_m_rad="non_negative",
                      lateral_damping_n_s_m="non_negative", angular_damping_n_m_s_rad="non_negative",
                      kinematic_offset_m="non_negative", kinematic_phase_rad="finite",
                      kinematic_direction_rad="finite")
        if self.kind == "flexible":
            _check_fields(self, "Coupling (flexible)", lateral_stiffness_n_m="positive")


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


def _parts(owner: object, where: str, field: str, cls: type) -> tuple:
    """``owner.field`` as a tuple of ``cls``, or a :class:`TrainError` naming what else it holds."""
    items = getattr(owner, field)
    if not isinstance(items, tuple | list):
        raise TrainError(f"{where} {field} must be a tuple of {cls.__name__} (got {items!r})")
    for x in items:
        if not isinstance(x, cls):
            raise TrainError(f"{where} {field} must hold {cls.__name__} objects (got {x!r})")
    return tuple(items)


def _check_rotor(r: Rotor) -> None:
    """A rotor's parts (each checked its own fields when built) and how they sit on its shaft."""
    if not isinstance(r.name, str):
        raise TrainError(f"Rotor name must be a string (got {r.name!r})")
    where = f"rotor {r.name!r}"
    if not isinstance(r.material, Material):
        raise TrainError(f"{where} material must be a Material (got {r.material!r})")
    _check_fields(r, where, stiff_axis_rad="finite")
    if not _parts(r, where, "elements", ShaftElement):
        raise TrainError(f"{where} has no shaft elements: give at least one (length, diameter)")
    n = r.n_stations
    parts = [(item, "disk") for item in _parts(r, where, "disks", Disk)] + \
        [(item, "bearing") for item in _parts(r, where, "supports", Support)] + \
        [(item, "unbalance") for item in _parts(r, where, "unbalances", Unbalance)]
    for item, label in parts:
        if item.station >= n:
            raise TrainError(f"{where}: a {label} at station {item.station} is beyond the shaft "
                             f"(stations 0..{n - 1}); put it on the shaft or lengthen the rotor")
    if not r.supports:
        raise TrainError(f"{where} has no bearing: every rotor needs at least one bearing under it "
                         f"(two, or one when it is overhung on a rigid coupling)")
    stations = [s.station for s in r.supports]
    if len(set(stations)) != len(stations):
        raise TrainError(f"{where}: two bearings at the same station {stations}; give each its own station")


def validate(train: Train) -> None:
    """Check a train as a whole (its rotors and couplings checked themselves when built): every message
    names the rotor or coupling and what to change."""
    rotors = _parts(train, "Train", "rotors", Rotor)
    couplings = _parts(train, "Train", "couplings", Coupling)
    if not rotors:
        raise TrainError("a train needs at least one rotor")
    if len(couplings) != len(rotors) - 1:
        raise TrainError(f"{len(rotors)} rotors need {len(rotors) - 1} coupling(s), "
                         f"one between each pair (got {len(couplings)})")
    n_stations = sum(len(r.elements) + 1 for r in rotors)
    if n_stations > MAX_TRAIN_STATIONS:
        raise TrainError(f"the train has {n_stations} stations, more than {MAX_TRAIN_STATIONS}: too large to solve and "
                         f"reduce within the limits; use longer elements (a few per span between bearings suffice for "
                         f"the first modes) or fewer rotors")
    _check_fields(train, "Train", gravity_m_s2="non_negative", internal_damping_s="non_negative",
                  rayleigh_mass_1_s="non_negative", rayleigh_stiffness_s="non_negative")
    for i, r in enumerate(rotors):
        if len(r.supports) == 1:
            rigid_neighbour = (i > 0 and couplings[i - 1].kind == "rigid") or \
                (i < len(couplings) and couplings[i].kind == "rigid")
            flex_neighbour = (i > 0 and couplings[i - 1].angular_stiffness_n_m_rad > 0) or \
                (i < len(couplings) and couplings[i].angular_stiffness_n_m_rad > 0)
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
    if isinstance(n, bool) or not isinstance(n, Integral) or n < 1:
        raise TrainError(f"a segment needs at least one element (got n={n!r})")
    _check_number(length_m, "segment length_m", "positive")
    return tuple(ShaftElement(length_m / n, diameter_m, inner_diameter_m, asymmetry) for _ in range(n))
