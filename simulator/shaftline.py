"""Plants from what a plant engineer knows: a shaft-line description reduced to the lumped plant.

A :class:`ShaftLine` gives, for the generator and the exciter rotor, the shaft as
segments (length, outer diameter) between its two bearings, extra body masses
(windings, wedges, fans, the exciter armature) at positions along the span, the
material, the four bearings (diameter, length, radial clearance), the oil
viscosity and the coupling (type and radial stiffness).

Reduction (docs/model.md, "Plants from a shaft line"): each rotor is modelled
with Euler–Bernoulli beam finite elements (2 DOF per node in one plane,
consistent mass) on pinned supports at its bearings. Its first bending mode,
normalised to unit displacement at its largest point, gives the modal mass
M = φᵀMφ and modal stiffness K = ω₁²M; the lumped rotor is a disk of mass M on
two half-spans of stiffness k = K/2 (so its pinned-pinned frequency is ω₁
exactly), and the rest of the rotor's mass goes to the two journals in the
proportions of the static bearing reactions of the full beam (so the total mass
and static bearing loads are kept). :func:`train_critical_speeds` gives the
critical speeds of the whole train (both rotors, the coupling, linear bearing
springs) from the full beam model, the reference for the reduction's test.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .params import Plant

#: Materials by name: (Young's modulus Pa, density kg/m³).
MATERIALS: dict[str, tuple[float, float]] = {
    "steel": (2.07e11, 7850.0),            # rotor forging steel (NiCrMoV), room temperature
    "steel_hot": (1.95e11, 7850.0),        # same at ≈ 100 °C
}
COUPLING_TYPES: tuple[str, ...] = ("rigid", "flexible")


#: Bounds that keep the beam model small whatever a description (or an uploaded one) says.
MAX_SPAN_M = 40.0
MAX_DIAMETER_M = 4.0
MAX_ITEMS = 200


def _number(name: str, v: Any) -> float:
    if isinstance(v, bool):
        raise ValueError(f"{name} must be a number, got {v!r}")
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {v!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{name} must be a finite number, got {v!r}")
    return x


def _table(name: str, v: Any) -> dict[str, Any]:
    if not isinstance(v, dict):
        raise ValueError(f"[{name}] must be a table, got {v!r}")
    return dict(v)


def _pos(name: str, v: Any) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number, got {v!r}") from None
    if not (math.isfinite(x) and x > 0):
        raise ValueError(f"{name} must be a positive number, got {v!r}")
    return x


@dataclass(frozen=True)
class Rotor:
    """One rotor between its two bearings.

    Attributes
    ----------
    segments : list of (length_m, diameter_m)
        Shaft segments from the first bearing (non-coupling end for the generator,
        coupling end for the exciter) to the second; bearings at both ends.
    body_masses : list of (position_m, mass_kg)
        Extra masses that add weight and inertia but no stiffness, at distances
        from the first bearing (windings and wedges of a generator body, an armature).
    """

    segments: tuple[tuple[float, float], ...]
    body_masses: tuple[tuple[float, float], ...] = ()
    overhang: tuple[tuple[float, float], ...] = ()
    disks: tuple[tuple[float, float, float, float], ...] = ()

    @classmethod
    def from_dict(cls, name: str, d: dict[str, Any]) -> Rotor:
        if not isinstance(d, dict):
            raise ValueError(f"[{name}] must be a table with 'segments' (and optionally 'body_masses')")
        unknown = set(d) - {"segments", "body_masses", "overhang", "disks"}
        if unknown:
            raise ValueError(f"[{name}] has unknown keys {sorted(unknown)}; known: segments, body_masses, "
                             f"overhang, disks")
        segs = d.get("segments")
        if not isinstance(segs, list) or not segs:
            raise ValueError(f"{name}.segments must be a non-empty list of [length_m, diameter_m]")
        body = d.get("body_masses", [])
        if not isinstance(body, list):
            raise ValueError(f"{name}.body_masses must be a list of [position_m, mass_kg]")
        if len(segs) > MAX_ITEMS or len(body) > MAX_ITEMS:
            raise ValueError(f"{name}: at most {MAX_ITEMS} segments and {MAX_ITEMS} body masses")
        segments = []
        for i, s in enumerate(segs):
            if not (isinstance(s, (list, tuple)) and len(s) == 2):
                raise ValueError(f"{name}.segments[{i}] must be [length_m, diameter_m], got {s!r}")
            segments.append((_pos(f"{name}.segments[{i}] length_m", s[0]), _pos(f"{name}.segments[{i}] diameter_m", s[1])))
        span = sum(s[0] for s in segments)
        if span > MAX_SPAN_M or max(s[1] for s in segments) > MAX_DIAMETER_M:
            raise ValueError(f"{name}: a rotor span of at most {MAX_SPAN_M:g} m and diameters of at most "
                             f"{MAX_DIAMETER_M:g} m, got {span:g} m and {max(s[1] for s in segments):g} m")
        masses = []
        for i, b in enumerate(body):
            if not (isinstance(b, (list, tuple)) and len(b) == 2):
                raise ValueError(f"{name}.body_masses[{i}] must be [position_m, mass_kg], got {b!r}")
            x = _number(f"{name}.body_masses[{i}] position_m", b[0])
            if not 0 <= x <= span:
                raise ValueError(f"{name}.body_masses[{i}] position {x} m is outside the span [0, {span:g}] m")
            masses.append((x, _pos(f"{name}.body_masses[{i}] mass_kg", b[1])))
        over = d.get("overhang", [])
        if not isinstance(over, list) or len(over) > MAX_ITEMS:
            raise ValueError(f"{name}.overhang must be a list of at most {MAX_ITEMS} [length_m, diameter_m] "
                             f"(the shaft from the coupling-end bearing to the coupling flange)")
        overhang = []
        for i, s in enumerate(over):
            if not (isinstance(s, (list, tuple)) and len(s) == 2):
                raise ValueError(f"{name}.overhang[{i}] must be [length_m, diameter_m], got {s!r}")
            overhang.append((_pos(f"{name}.overhang[{i}] length_m", s[0]), _pos(f"{name}.overhang[{i}] diameter_m", s[1])))
        if sum(s[0] for s in overhang) > MAX_SPAN_M / 4:
            raise ValueError(f"{name}.overhang: at most {MAX_SPAN_M / 4:g} m from the bearing to the flange")
        dk = d.get("disks", [])
        if not isinstance(dk, list) or len(dk) > MAX_ITEMS:
            raise ValueError(f"{name}.disks must be a list of at most {MAX_ITEMS} "
                             f"[position_m, mass_kg, polar_kg_m2, transverse_kg_m2]")
        disks = []
        for i, b in enumerate(dk):
            if not (isinstance(b, (list, tuple)) and len(b) == 4):
                raise ValueError(f"{name}.disks[{i}] must be [position_m, mass_kg, polar_kg_m2, transverse_kg_m2], "
                                 f"got {b!r}")
            x = _number(f"{name}.disks[{i}] position_m", b[0])
            if not 0 <= x <= span:
                raise ValueError(f"{name}.disks[{i}] position {x} m is outside the span [0, {span:g}] m "
                                 f"(positions are from the rotor's first bearing)")
            jp = _number(f"{name}.disks[{i}] polar_kg_m2", b[2])
            jt = _number(f"{name}.disks[{i}] transverse_kg_m2", b[3])
            if jp < 0 or jt < 0:
                raise ValueError(f"{name}.disks[{i}]: inertias must be ≥ 0, got {jp}, {jt}")
            disks.append((x, _pos(f"{name}.disks[{i}] mass_kg", b[1]), jp, jt))
        return cls(tuple(segments), tuple(masses), tuple(overhang), tuple(disks))

    @property
    def span_m(self) -> float:
        return sum(s[0] for s in self.segments)


@dataclass(frozen=True)
class ShaftLine:
    """A generator–exciter shaft line as a plant engineer describes it (SI units)."""

    generator: Rotor
    exciter: Rotor
    material: str = "steel"
    bearing_diameter_m: tuple[float, float, float, float] = (0.45, 0.45, 0.25, 0.25)
    bearing_length_m: tuple[float, float, float, float] = (0.35, 0.35, 0.15, 0.15)
    clearance_m: float = 0.35e-3
    viscosity_pa_s: float = 0.018
    coupling: str = "rigid"
    coupling_stiffness_n_m: float = 1.0e8
    generator_asymmetry: float = 0.0549
    damping_ratio: float = 0.008
    extra: dict[str, Any] = field(default_factory=dict)
    #: per bearing 1..4: a type of ``simulator.bearings`` (plain, elliptical, tilting_pad, linear) or "none"
    bearing_types: tuple[str, str, str, str] = ("plain", "plain", "plain", "plain")
    #: per bearing: further keys of its bearing table (preload, pads, load, stiffness_n_m, ...)
    bearing_options: tuple[dict[str, Any], ...] = ({}, {}, {}, {})
    #: per bearing: centre (x horizontal, y vertical up) from the straight shaft-line axis, m
    bearing_centres_m: tuple[tuple[float, float], ...] = ((0.0, 0.0),) * 4
    coupling_angular_stiffness_n_m_rad: float = 0.0
    coupling_damping_n_s_m: float = 0.0
    coupling_angular_damping_n_m_s_rad: float = 0.0
    #: the generator's residual unbalance (kg·m) at the middle of its span, along the keyphasor mark; a preset
    #: carries its ISO 21940-11 G2.5 value, a file none unless it says (``generator_unbalance_kg_m``)
    generator_unbalance_kg_m: float = 0.0

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ShaftLine:
        """Validate a mapping (the TOML layout of ``examples/shaftline_200mw.toml``)."""
        if not isinstance(d, dict):
            raise ValueError("a shaft line must be a table")
        known = {"generator", "exciter", "material", "bearings", "oil", "coupling", "generator_asymmetry",
                 "damping_ratio", "plant", "generator_unbalance_kg_m"}
        unknown = set(d) - known
        if unknown:
            raise ValueError(f"unknown shaft-line key(s) {sorted(unknown)}; known: {sorted(known)}")
        for k in ("generator", "exciter"):
            if k not in d:
                raise ValueError(f"the shaft line needs a [{k}] table with its segments")
        material = d.get("material", "steel")
        if material not in MATERIALS:
            raise ValueError(f"material must be one of {list(MATERIALS)}, got {material!r}")
        b = d.get("bearings", {})
        if not isinstance(b, dict):
            raise ValueError("[bearings] must be a table with diameter_m, length_m (4 values each) and clearance_m")
        diam = tuple(_pos("bearings.diameter_m", v) for v in b.get("diameter_m", cls.bearing_diameter_m))
        length = tuple(_pos("bearings.length_m", v) for v in b.get("length_m", cls.bearing_length_m))
        if len(diam) != 4 or len(length) != 4:
            raise ValueError("bearings.diameter_m and bearings.length_m need 4 values (bearings 1..4)")
        oil = d.get("oil", {})
        coupling = d.get("coupling", {})
        for name, t in (("oil", oil), ("coupling", coupling)):
            if not isinstance(t, dict):
                raise ValueError(f"[{name}] must be a table, got {t!r}")
        for name, v in (("bearings.diameter_m", b.get("diameter_m", ())), ("bearings.length_m", b.get("length_m", ()))):
            if not isinstance(v, (list, tuple)):
                raise ValueError(f"{name} must be a list of 4 numbers (bearings 1..4), got {v!r}")
        ctype = coupling.get("type", "rigid")
        if ctype not in COUPLING_TYPES:
            raise ValueError(f"coupling.type must be one of {COUPLING_TYPES}, got {ctype!r}")
        cunknown = set(coupling) - {"type", "stiffness_n_m", "angular_stiffness_n_m_rad", "damping_n_s_m",
                                    "angular_damping_n_m_s_rad"}
        if cunknown:
            raise ValueError(f"[coupling] has unknown keys {sorted(cunknown)}; known: type, stiffness_n_m, "
                             f"angular_stiffness_n_m_rad, damping_n_s_m, angular_damping_n_m_s_rad")
        coupling_extra = {}
        for k in ("angular_stiffness_n_m_rad", "damping_n_s_m", "angular_damping_n_m_s_rad"):
            v = _number(f"coupling.{k}", coupling.get(k, 0.0))
            if v < 0:
                raise ValueError(f"coupling.{k} must be ≥ 0, got {v}")
            coupling_extra[k] = v
        types, options, centres = _bearing_tables(b)
        zeta = _number("damping_ratio", d.get("damping_ratio", 0.008))
        if not 0 <= zeta < 1:
            raise ValueError(f"damping_ratio must be in [0, 1), got {zeta!r}")
        unbalance = _number("generator_unbalance_kg_m", d.get("generator_unbalance_kg_m", 0.0))
        if not 0 <= unbalance <= 100:
            raise ValueError(f"generator_unbalance_kg_m must be within 0..100 kg·m, got {unbalance!r}")
        return cls(
            generator=Rotor.from_dict("generator", d["generator"]),
            exciter=Rotor.from_dict("exciter", d["exciter"]),
            material=material,
            bearing_diameter_m=diam,  # type: ignore[arg-type]
            bearing_length_m=length,  # type: ignore[arg-type]
            clearance_m=_pos("bearings.clearance_m", b.get("clearance_m", 0.35e-3)),
            viscosity_pa_s=_pos("oil.viscosity_pa_s", oil.get("viscosity_pa_s", 0.018)),
            coupling=ctype,
            coupling_stiffness_n_m=_pos("coupling.stiffness_n_m", coupling.get("stiffness_n_m", 1.0e8)),
            generator_asymmetry=_number("generator_asymmetry", d.get("generator_asymmetry", 0.0549)),
            damping_ratio=zeta,
            extra=_table("plant", d.get("plant", {})),
            bearing_types=types,
            bearing_options=options,
            bearing_centres_m=centres,
            coupling_angular_stiffness_n_m_rad=coupling_extra["angular_stiffness_n_m_rad"],
            coupling_damping_n_s_m=coupling_extra["damping_n_s_m"],
            coupling_angular_damping_n_m_s_rad=coupling_extra["angular_damping_n_m_s_rad"],
            generator_unbalance_kg_m=unbalance,
        )

    def to_dict(self) -> dict[str, Any]:
        """The TOML layout :meth:`from_dict` reads (``from_dict(line.to_dict()) == line``): for a dataset's
        record of its base shaft lines and for sending a line to a worker."""
        def rotor(r: Rotor) -> dict[str, Any]:
            return {"segments": [list(s) for s in r.segments], "body_masses": [list(b) for b in r.body_masses],
                    "overhang": [list(s) for s in r.overhang], "disks": [list(d) for d in r.disks]}

        return {
            "generator": rotor(self.generator), "exciter": rotor(self.exciter), "material": self.material,
            "bearings": {"diameter_m": list(self.bearing_diameter_m), "length_m": list(self.bearing_length_m),
                         "clearance_m": self.clearance_m, "type": list(self.bearing_types),
                         "options": [dict(o) for o in self.bearing_options],
                         "centre_x_m": [c[0] for c in self.bearing_centres_m],
                         "centre_y_m": [c[1] for c in self.bearing_centres_m]},
            "oil": {"viscosity_pa_s": self.viscosity_pa_s},
            "coupling": {"type": self.coupling, "stiffness_n_m": self.coupling_stiffness_n_m,
                         "angular_stiffness_n_m_rad": self.coupling_angular_stiffness_n_m_rad,
                         "damping_n_s_m": self.coupling_damping_n_s_m,
                         "angular_damping_n_m_s_rad": self.coupling_angular_damping_n_m_s_rad},
            "generator_asymmetry": self.generator_asymmetry, "damping_ratio": self.damping_ratio,
            "generator_unbalance_kg_m": self.generator_unbalance_kg_m, "plant": dict(self.extra),
        }

    @classmethod
    def from_file(cls, path: str | Path) -> ShaftLine:
        path = Path(path)
        if not path.is_file():
            raise ValueError(f"shaft-line file {str(path)!r} does not exist")
        try:
            return cls.from_dict(tomllib.loads(path.read_text()))
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"shaft-line file {path.name!r} is not valid TOML: {exc}") from exc


#: what a bearing slot may hold: a type of ``rotordiag.simulator.bearings`` or none (no bearing there)
BEARING_SLOT_TYPES: tuple[str, ...] = ("plain", "elliptical", "two_lobe", "tilting_pad", "linear", "none")
_BEARING_KEYS = {"diameter_m", "length_m", "clearance_m", "type", "options", "centre_x_m", "centre_y_m"}


def _bearing_tables(b: dict[str, Any]) -> tuple[tuple, tuple, tuple]:
    """Types, per-bearing option tables and centres from ``[bearings]`` (all optional: plain, none, centred)."""
    unknown = set(b) - _BEARING_KEYS
    if unknown:
        raise ValueError(f"[bearings] has unknown keys {sorted(unknown)}; known: {sorted(_BEARING_KEYS)}")
    types = b.get("type", ["plain"] * 4)
    if not (isinstance(types, list) and len(types) == 4 and all(isinstance(t, str) for t in types)):
        raise ValueError(f"bearings.type must be a list of 4 names (bearings 1..4) from {BEARING_SLOT_TYPES}, "
                         f"got {types!r}")
    for i, t in enumerate(types):
        if t not in BEARING_SLOT_TYPES:
            raise ValueError(f"bearings.type[{i}] {t!r} is not one of {BEARING_SLOT_TYPES}")
    if types[0] == "none" or types[1] == "none" or types[2] == "none":
        raise ValueError("bearings.type: only bearing 4 (the exciter's far end) may be \"none\" (an exciter "
                         "overhung on its coupling-end bearing); the generator needs bearings 1 and 2 and the "
                         "exciter bearing 3")
    opts = b.get("options", [{}] * 4)
    if not (isinstance(opts, list) and len(opts) == 4 and all(isinstance(o, dict) for o in opts)):
        raise ValueError("bearings.options must be a list of 4 tables (bearings 1..4), e.g. "
                         "[{pads = 4}, {pads = 4}, {preload = 0.5}, {}]")
    for i, o in enumerate(opts):
        bad = {"type", "diameter_m", "length_m", "viscosity_pa_s"} & set(o)
        if bad:
            raise ValueError(f"bearings.options[{i}] must not repeat {sorted(bad)}: give them in [bearings] / [oil]")
    cx = b.get("centre_x_m", [0.0] * 4)
    cy = b.get("centre_y_m", [0.0] * 4)
    for name, v in (("bearings.centre_x_m", cx), ("bearings.centre_y_m", cy)):
        if not (isinstance(v, list) and len(v) == 4):
            raise ValueError(f"{name} must be a list of 4 numbers (m, bearings 1..4), got {v!r}")
    centres = tuple((_number(f"bearings.centre_x_m[{i}]", cx[i]), _number(f"bearings.centre_y_m[{i}]", cy[i]))
                    for i in range(4))
    for i, (x, y) in enumerate(centres):
        if abs(x) > 0.05 or abs(y) > 0.05:
            raise ValueError(f"bearing {i + 1} centre ({x}, {y}) m is more than 50 mm off the shaft line; "
                             f"give offsets in metres (e.g. 0.2e-3 for 0.2 mm)")
    return tuple(types), tuple(dict(o) for o in opts), centres


# ----------------------------------------------------------------------------- beam finite elements
def _beam_matrices(rotor: Rotor, E: float, rho: float, max_elem_m: float = 0.25):
    """Global K, M (planar Euler–Bernoulli, DOF [w0, θ0, w1, θ1, ...]) and node coordinates."""
    xs = [0.0]
    props = []
    for length, dia in rotor.segments:
        n = max(1, int(math.ceil(length / max_elem_m)))
        for _ in range(n):
            xs.append(xs[-1] + length / n)
            props.append((length / n, dia))
    for x, _ in rotor.body_masses:  # a node at every body mass: split the element that holds it
        if min(abs(np.array(xs) - x)) > 1e-9:
            i = int(np.searchsorted(xs, x))
            le, d = props[i - 1]
            a = x - xs[i - 1]
            props[i - 1:i] = [(a, d), (le - a, d)]
            xs.insert(i, x)
    nn = len(xs)
    K = np.zeros((2 * nn, 2 * nn))
    M = np.zeros((2 * nn, 2 * nn))
    for e, (le, d) in enumerate(props):
        area = math.pi * d * d / 4
        inertia = math.pi * d ** 4 / 64
        k = E * inertia / le ** 3 * np.array([[12, 6 * le, -12, 6 * le], [6 * le, 4 * le * le, -6 * le, 2 * le * le],
                                              [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le * le, -6 * le, 4 * le * le]])
        m = rho * area * le / 420 * np.array([[156, 22 * le, 54, -13 * le], [22 * le, 4 * le * le, 13 * le, -3 * le * le],
                                              [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le * le, -22 * le, 4 * le * le]])
        idx = np.arange(2 * e, 2 * e + 4)
        K[np.ix_(idx, idx)] += k
        M[np.ix_(idx, idx)] += m
    for x, mass in rotor.body_masses:
        j = int(np.argmin(abs(np.array(xs) - x)))
        M[2 * j, 2 * j] += mass
    return K, M, np.array(xs)


@dataclass(frozen=True)
class LumpedRotor:
    journal_a_kg: float
    disk_kg: float
    journal_b_kg: float
    half_span_stiffness_n_m: float
    first_pinned_hz: float


def reduce_rotor(rotor: Rotor, material: str = "steel") -> LumpedRotor:
    """Lumped journal–disk–journal rotor matching the first pinned–pinned bending mode, total mass and
    static bearing reactions of the beam model (module docstring)."""
    from scipy.linalg import eigh

    E, rho = MATERIALS[material]
    K, M, xs = _beam_matrices(rotor, E, rho)
    n = K.shape[0]
    free = [i for i in range(n) if i not in (0, n - 2)]  # pinned: w = 0 at both bearings
    w2, vecs = eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], subset_by_index=[0, 0])
    phi = np.zeros(n)
    phi[free] = vecs[:, 0]
    phi /= phi[0::2][np.argmax(np.abs(phi[0::2]))]
    modal_mass = float(phi @ M @ phi)
    total = float(np.ones(n // 2) @ M[0::2, 0::2] @ np.ones(n // 2))
    # static reactions under gravity of the full beam (simply supported): moments of the mass distribution
    mass_vec = M[0::2, 0::2] @ np.ones(n // 2)  # consistent-mass lumping of weight to the nodes
    moment = float(mass_vec @ xs)
    r_b = moment / xs[-1]
    r_a = total - r_b
    rest = total - modal_mass
    if rest <= 0:
        raise ValueError("the rotor's first-mode modal mass exceeds its total mass; check the segments")
    return LumpedRotor(journal_a_kg=rest * r_a / total, disk_kg=modal_mass, journal_b_kg=rest * r_b / total,
                       half_span_stiffness_n_m=0.5 * float(w2[0]) * modal_mass,
                       first_pinned_hz=math.sqrt(float(w2[0])) / (2 * math.pi))


def to_plant(line: ShaftLine) -> Plant:
    """The lumped :class:`Plant` of a shaft line (module docstring; docs/model.md)."""
    g = reduce_rotor(line.generator, line.material)
    x = reduce_rotor(line.exciter, line.material)
    wg = math.sqrt(2 * g.half_span_stiffness_n_m / g.disk_kg)
    wx = math.sqrt(2 * x.half_span_stiffness_n_m / x.disk_kg)
    values: dict[str, Any] = dict(
        journal1_mass_kg=g.journal_a_kg, generator_mass_kg=g.disk_kg, journal3_mass_kg=g.journal_b_kg,
        journal4_mass_kg=x.journal_a_kg, exciter_mass_kg=x.disk_kg, journal6_mass_kg=x.journal_b_kg,
        generator_stiffness_n_m=g.half_span_stiffness_n_m, exciter_stiffness_n_m=x.half_span_stiffness_n_m,
        asymmetry=line.generator_asymmetry,
        generator_damping_n_s_m=2 * line.damping_ratio * g.disk_kg * wg,
        exciter_damping_n_s_m=2 * line.damping_ratio * x.disk_kg * wx,
        clearance_m=line.clearance_m, viscosity_pa_s=line.viscosity_pa_s,
        bearing_radius_m=tuple(d / 2 for d in line.bearing_diameter_m), bearing_length_m=line.bearing_length_m,
        coupling_stiffness_n_m=line.coupling_stiffness_n_m,
    )
    values.update(line.extra)
    return Plant.from_dict(values)


# ----------------------------------------------------------------------------- verification
def train_critical_speeds(line: ShaftLine, bearing_stiffness_n_m: float, n: int = 2) -> np.ndarray:
    """First ``n`` natural frequencies (Hz) of the whole train from the beam model: both rotors, linear
    isotropic bearings of the given stiffness, coupling joining the generator's last and the exciter's
    first node in displacement (free in slope, as the lumped model's r3 = r4), non-rotating."""
    from scipy.linalg import eigh

    E, rho = MATERIALS[line.material]
    Kg, Mg, _ = _beam_matrices(line.generator, E, rho)
    Kx, Mx, _ = _beam_matrices(line.exciter, E, rho)
    ng, nx = Kg.shape[0], Kx.shape[0]
    K = np.zeros((ng + nx, ng + nx))
    M = np.zeros_like(K)
    K[:ng, :ng], M[:ng, :ng] = Kg, Mg
    K[ng:, ng:], M[ng:, ng:] = Kx, Mx
    for i in (0, ng - 2, ng, ng + nx - 2):
        K[i, i] += bearing_stiffness_n_m
    # constraint w_gen_end = w_exc_start: T maps reduced DOFs to full ones
    keep = [i for i in range(ng + nx) if i != ng]
    T = np.zeros((ng + nx, len(keep)))
    for j, i in enumerate(keep):
        T[i, j] = 1.0
    T[ng, keep.index(ng - 2)] = 1.0
    w2 = eigh(T.T @ K @ T, T.T @ M @ T, eigvals_only=True, subset_by_index=[0, n - 1])
    return np.sqrt(w2) / (2 * math.pi)


def lumped_critical_speeds(plant: Plant, bearing_stiffness_n_m: float, n: int = 2) -> np.ndarray:
    """First ``n`` natural frequencies (Hz) of the lumped chain (nodes 1, 2, 3≡4, 5, 6), ρ = 0, linear bearings."""
    from scipy.linalg import eigh

    m = np.array([plant.journal1_mass_kg, plant.generator_mass_kg, plant.journal3_mass_kg + plant.journal4_mass_kg,
                  plant.exciter_mass_kg, plant.journal6_mass_kg])
    K = np.zeros((5, 5))
    for a, b, k in ((0, 1, plant.generator_stiffness_n_m), (1, 2, plant.generator_stiffness_n_m),
                    (2, 3, plant.exciter_stiffness_n_m), (3, 4, plant.exciter_stiffness_n_m)):
        K[a, a] += k
        K[b, b] += k
        K[a, b] -= k
        K[b, a] -= k
    for i, count in ((0, 1), (2, 2), (4, 1)):
        K[i, i] += count * bearing_stiffness_n_m
    w2 = eigh(K, np.diag(m), eigvals_only=True, subset_by_index=[0, n - 1])
    return np.sqrt(w2) / (2 * math.pi)


# ----------------------------------------------------------------------------- presets
#: residual asymmetry of a cross-slotted two-pole body (ΔEI/EĪ = 2 %) and of a four-pole body (0.4 %)
TWO_POLE_ASYMMETRY = 0.01
FOUR_POLE_ASYMMETRY = 0.002
#: ISO 21940-11 balance grade of a preset generator (G2.5: turbo-generator rotors), mm/s
PRESET_BALANCE_GRADE_MM_S = 2.5

def _preset(body, windings, shaft, journal, exc, bearings_d, bearings_l, clearance, rated, *, types, options,
            overhang=(0.5, 0.3), asymmetry=TWO_POLE_ASYMMETRY):
    """Two-bearing generator (journal, shaft, body, shaft, journal) and exciter (journal, shaft, journal),
    with overhangs from the coupling-end bearings to the flange (generator, exciter lengths in m, the
    journal diameter) and the bearing types of ``simulator.bearings``."""
    body_d, body_l = body
    jd, jl = journal
    sd, sl = shaft
    wpos = [jl + sl + body_l * (k + 0.5) / len(windings) for k in range(len(windings))]
    ejd, ejl, esd, esl, arm = exc
    return {
        "generator": {"segments": [[jl, jd], [sl, sd], [body_l, body_d], [sl, sd], [jl, jd]],
                      "body_masses": [[x, m] for x, m in zip(wpos, windings)], "overhang": [[overhang[0], jd]]},
        "exciter": {"segments": [[ejl, ejd], [esl, esd], [ejl, ejd]], "body_masses": [[ejl + esl / 2, arm]],
                    "overhang": [[overhang[1], ejd]]},
        "bearings": {"diameter_m": list(bearings_d), "length_m": list(bearings_l), "clearance_m": clearance,
                     "type": list(types), "options": [dict(o) for o in options]},
        "generator_asymmetry": asymmetry,
        "rated_speed_rpm": list(rated),
    }


_TP4 = {"pads": 4, "load": "between_pads"}
_LEMON = {"preload": 0.5}

#: Illustrative machine families (docs/model.md): dimensions from the usual proportions of two-pole
#: (body ≤ ≈ 1.2 m at 3000/3600 r/min) and four-pole (larger body, 1500/1800 r/min) generators — not a
#: vendor's drawings. Bearings as such machines have: four-pad tilting-pad journals on the large two-pole
#: generators, two-lobe (elliptical, preload 0.5) on the small generator, the four-pole generator and the
#: exciters. Rotor asymmetry ρ (stiffnesses K̄(1 ± ρ), so ΔEI/EĪ = 2ρ): a two-pole body with the transverse
#: slots that equalise its bending stiffnesses keeps a residual ρ = ``TWO_POLE_ASYMMETRY``; a four-pole
#: section has four-fold symmetry, so its second moments are equal and ρ = ``FOUR_POLE_ASYMMETRY`` is a
#: manufacturing tolerance (docs/train-misalignment.md, "The presets' asymmetry and unbalance"; the paper's
#: ρ = 0.0549 is an uncompensated rotor's and stays the default of a shaft-line file). Each preset carries
#: the residual unbalance of ISO 21940-11 grade ``PRESET_BALANCE_GRADE_MM_S`` at its first rated speed
#: (``generator_unbalance_kg_m``) and ``rated_speed_rpm`` (not a plant parameter) for the user's operating
#: points; its stability margin at rated speed is in docs/train-misalignment.md and
#: tests/test_train_shaftline.py. The lumped plant (:func:`to_plant`) reads only the span, masses, bearing
#: sizes, clearance and ρ.
PRESETS: dict[str, dict[str, Any]] = {
    "gen50_2pole": _preset((0.75, 3.2), [1200.0] * 4, (0.42, 0.6), (0.30, 0.4), (0.18, 0.3, 0.26, 1.8, 600.0),
                           (0.30, 0.30, 0.18, 0.18), (0.24, 0.24, 0.11, 0.11), 0.25e-3, (3000, 3600),
                           types=("elliptical",) * 4, options=(_LEMON,) * 4, overhang=(0.4, 0.25)),
    "gen200_2pole": _preset((1.0, 5.0), [3000.0] * 4, (0.6, 0.9), (0.45, 0.6), (0.25, 0.4, 0.36, 2.6, 1500.0),
                            (0.45, 0.45, 0.25, 0.25), (0.35, 0.35, 0.15, 0.15), 0.35e-3, (3000, 3600),
                            types=("tilting_pad", "tilting_pad", "elliptical", "elliptical"),
                            options=(_TP4, _TP4, _LEMON, _LEMON)),
    "gen600_2pole": _preset((1.15, 6.8), [5000.0] * 4, (0.75, 1.1), (0.55, 0.7), (0.30, 0.5, 0.45, 3.2, 3000.0),
                            (0.55, 0.55, 0.30, 0.30), (0.45, 0.45, 0.20, 0.20), 0.45e-3, (3000, 3600),
                            types=("tilting_pad", "tilting_pad", "elliptical", "elliptical"),
                            options=(_TP4, _TP4, _LEMON, _LEMON), overhang=(0.6, 0.35)),
    "gen600_4pole": _preset((1.6, 5.5), [7000.0] * 4, (0.85, 1.2), (0.60, 0.8), (0.30, 0.5, 0.45, 3.2, 3000.0),
                            (0.60, 0.60, 0.30, 0.30), (0.50, 0.50, 0.20, 0.20), 0.50e-3, (1500, 1800),
                            types=("elliptical",) * 4, options=(_LEMON,) * 4, overhang=(0.6, 0.35),
                            asymmetry=FOUR_POLE_ASYMMETRY),
}


def rotor_mass_kg(rotor: Rotor, material: str = "steel") -> float:
    """Mass of a shaft-line rotor: its segments and overhang as solid cylinders, its body masses and disks."""
    rho = MATERIALS[material][1]
    steel = sum(math.pi * d * d / 4.0 * length * rho for length, d in (*rotor.segments, *rotor.overhang))
    return steel + sum(m for _, m in rotor.body_masses) + sum(d[1] for d in rotor.disks)


def balance_grade_unbalance_kg_m(rotor: Rotor, grade_mm_s: float, speed_rpm: float, material: str = "steel") -> float:
    """The permissible residual unbalance U = G·M/Ω of ISO 21940-11 for grade G (mm/s) at ``speed_rpm`` (kg·m)."""
    return grade_mm_s * 1e-3 * rotor_mass_kg(rotor, material) / (speed_rpm * math.pi / 30.0)


for _d in PRESETS.values():  # the residual unbalance of grade G2.5 at the preset's first rated speed
    _line = ShaftLine.from_dict({k: v for k, v in _d.items() if k != "rated_speed_rpm"})
    _d["generator_unbalance_kg_m"] = balance_grade_unbalance_kg_m(
        _line.generator, PRESET_BALANCE_GRADE_MM_S, _d["rated_speed_rpm"][0], _line.material)
del _d, _line


def preset(name: str) -> ShaftLine:
    """The :class:`ShaftLine` of a named preset (``PRESETS``)."""
    if name not in PRESETS:
        raise ValueError(f"unknown shaft-line preset {name!r}; known: {sorted(PRESETS)}")
    d = {k: v for k, v in PRESETS[name].items() if k != "rated_speed_rpm"}
    return ShaftLine.from_dict(d)
