"""Plant parameters of the generator–exciter rotor (MODEL.md section 6).

A :class:`Plant` is immutable and validated on construction; it round-trips
through TOML and JSON files and flat dictionaries.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

#: Node numbers (MODEL.md) of the journals in bearings 1..4.
JOURNAL_NODES: tuple[int, int, int, int] = (1, 3, 4, 6)

#: Coupling mechanisms: MODEL.md section 3's ``pin``, ``rigid`` (a rotating coupling
#: eccentricity) and ``aligned``, plus the stationary shaft-line ``offset`` and the
#: ``flexible`` coupling with its 2X misalignment reaction (docs/model.md).
MECHANISMS: tuple[str, ...] = ("pin", "rigid", "aligned", "offset", "flexible")
#: Default bearing-3-to-bearing-4 span (m): the ``gen200_2pole`` shaft line's exciter (examples/shaftline_200mw.toml).
DEFAULT_EXCITER_BEARING_SPAN_M = 3.4

#: Physically sourced range of the flexible coupling's radial stiffness (N/m), docs/model.md.
COUPLING_STIFFNESS_RANGE_N_M: tuple[float, float] = (1.0e6, 1.0e10)

#: Bearing force models: Capone short bearing, or linear isotropic springs
#: (used for the energy and symmetry checks, and for users who want them).
BEARING_MODELS: tuple[str, ...] = ("short", "linear")

# User-settable ranges (MODEL.md section 6).
SPEED_RANGE_RPM: tuple[float, float] = (100.0, 6000.0)
MISALIGNMENT_RANGE: tuple[float, float] = (0.0, 0.9)
UNBALANCE_RANGE: tuple[float, float] = (0.0, 0.5)
ASYMMETRY_RANGE: tuple[float, float] = (0.0, 0.5)  # upper bound exclusive


def _pair4(value: Any, name: str) -> tuple[float, float, float, float]:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (4,):
        raise ValueError(f"{name} must have 4 values (bearings 1..4), got shape {arr.shape}")
    return tuple(float(v) for v in arr)  # type: ignore[return-value]


def _offsets(value: Any) -> tuple[tuple[float, float], ...]:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (4, 2):
        raise ValueError(
            f"bearing_offset_m must be 4 pairs [x, y] in metres (bearings 1..4), got shape {arr.shape}"
        )
    return tuple((float(a), float(b)) for a, b in arr)


@dataclass(frozen=True)
class Plant:
    """Physical parameters of the generator–exciter train (SI units).

    Defaults are MODEL.md's 200 MW-class two-pole generator and exciter.

    Attributes
    ----------
    journal1_mass_kg, generator_mass_kg, journal3_mass_kg : float
        m1, M1 (generator body, lumped at mid-span), m3.
    journal4_mass_kg, exciter_mass_kg, journal6_mass_kg : float
        m4, M2 (exciter body), m6.
    generator_stiffness_n_m : float
        k̄, mean stiffness of each generator half-span.
    asymmetry : float
        ρ, generator stiffness asymmetry: half-span stiffnesses k̄(1 ± ρ) in the rotating frame.
    stiff_axis_angle_rad : float
        β0, angle of the stiff axis at t = 0.
    generator_damping_n_s_m, exciter_damping_n_s_m : float
        c1, c2: viscous damping on the disk nodes 2 and 5.
    exciter_stiffness_n_m : float
        k2, stiffness of each exciter half-span.
    clearance_m : float
        c, radial clearance of all four bearings (the non-dimensionalisation base).
    viscosity_pa_s : float
        μ, oil dynamic viscosity.
    bearing_radius_m, bearing_length_m : tuple of 4 floats
        R and L of bearings 1..4.
    bearing_offset_m : tuple of 4 (x, y) pairs
        Bearing-centre offsets (MODEL.md 3d), metres.
    gravity_m_s2 : float
        g, acting in −y.
    bearing_model : {"short", "linear"}
        Capone short-bearing oil film (default) or linear isotropic springs.
    linear_bearing_stiffness_n_m, linear_bearing_damping_n_s_m : float
        Coefficients of the ``"linear"`` bearing model.
    coupling_stiffness_n_m, coupling_damping_n_s_m : float
        Radial stiffness k_c and damping c_c of the ``flexible`` mechanism's coupling.
    exciter_bearing_span_m : float
        Axial distance from bearing 3 (at the coupling) to bearing 4, metres: the lever of an
        angular shaft-line offset (``simulate(angular_misalignment_mrad=...)``). Default 3.4 m,
        the exciter span of the ``gen200_2pole`` shaft line.
    """

    journal1_mass_kg: float = 4000.0
    generator_mass_kg: float = 32000.0
    journal3_mass_kg: float = 4000.0
    journal4_mass_kg: float = 500.0
    exciter_mass_kg: float = 3000.0
    journal6_mass_kg: float = 500.0
    generator_stiffness_n_m: float = 2.8e8
    asymmetry: float = 0.0549
    stiff_axis_angle_rad: float = 0.0
    generator_damping_n_s_m: float = 7.0e4
    exciter_stiffness_n_m: float = 6.8e7
    exciter_damping_n_s_m: float = 2.5e4
    clearance_m: float = 0.35e-3
    viscosity_pa_s: float = 0.018
    bearing_radius_m: tuple[float, float, float, float] = (0.225, 0.225, 0.125, 0.125)
    bearing_length_m: tuple[float, float, float, float] = (0.35, 0.35, 0.15, 0.15)
    bearing_offset_m: tuple[tuple[float, float], ...] = field(
        default=((0.0, 0.0), (0.0, 0.0), (0.0, 0.0), (0.0, 0.0))
    )
    gravity_m_s2: float = 9.81
    bearing_model: str = "short"
    linear_bearing_stiffness_n_m: float = 1.0e9
    linear_bearing_damping_n_s_m: float = 0.0
    coupling_stiffness_n_m: float = 1.0e8
    coupling_damping_n_s_m: float = 0.0
    exciter_bearing_span_m: float = DEFAULT_EXCITER_BEARING_SPAN_M

    # ------------------------------------------------------------------ validation
    def __post_init__(self) -> None:
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731  (frozen dataclass)
        set_("bearing_radius_m", _pair4(self.bearing_radius_m, "bearing_radius_m"))
        set_("bearing_length_m", _pair4(self.bearing_length_m, "bearing_length_m"))
        set_("bearing_offset_m", _offsets(self.bearing_offset_m))
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "bearing_model":
                if v not in BEARING_MODELS:
                    raise ValueError(f"bearing_model must be one of {BEARING_MODELS}, got {v!r}")
                continue
            values = np.ravel(np.asarray(v, dtype=float))
            if not np.all(np.isfinite(values)):
                raise ValueError(f"{f.name} must be finite, got {v!r}")
            if not isinstance(v, tuple):
                set_(f.name, float(v))
        positive = [
            "journal1_mass_kg", "generator_mass_kg", "journal3_mass_kg", "journal4_mass_kg",
            "exciter_mass_kg", "journal6_mass_kg", "generator_stiffness_n_m",
            "exciter_stiffness_n_m", "clearance_m", "viscosity_pa_s", "linear_bearing_stiffness_n_m",
            "coupling_stiffness_n_m", "exciter_bearing_span_m",
        ]
        for name in positive:
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        for name in ("bearing_radius_m", "bearing_length_m"):
            if min(getattr(self, name)) <= 0:
                raise ValueError(f"{name} must be > 0 for every bearing, got {getattr(self, name)!r}")
        for name in ("generator_damping_n_s_m", "exciter_damping_n_s_m",
                     "linear_bearing_damping_n_s_m", "gravity_m_s2", "coupling_damping_n_s_m"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        lo, hi = ASYMMETRY_RANGE
        if not lo <= self.asymmetry < hi:
            raise ValueError(f"asymmetry must be in [{lo}, {hi}), got {self.asymmetry!r}")
        c = self.clearance_m
        for b, (ox, oy) in enumerate(self.bearing_offset_m, start=1):
            if math.hypot(ox, oy) >= c:
                raise ValueError(
                    f"bearing_offset_m of bearing {b} must be smaller than the clearance "
                    f"({c:g} m), got ({ox:g}, {oy:g})"
                )

    # ------------------------------------------------------------------ constructors
    @classmethod
    def default(cls) -> Plant:
        """The MODEL.md default plant."""
        return cls()

    def replace(self, **changes: Any) -> Plant:
        """A validated copy with some fields changed (unknown names raise ``ValueError``)."""
        unknown = set(changes) - set(self.field_names())
        if unknown:
            raise ValueError(f"unknown plant parameter(s) {sorted(unknown)}; known: {self.field_names()}")
        return dataclasses.replace(self, **changes)

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Names of all plant parameters."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Plant:
        """Build from a (possibly partial) mapping; missing fields take the defaults."""
        if not isinstance(data, dict):
            raise ValueError(f"a plant must be a mapping of parameter names to values, got {type(data).__name__}")
        unknown = set(data) - set(cls.field_names())
        if unknown:
            raise ValueError(f"unknown plant parameter(s) {sorted(unknown)}; known: {cls.field_names()}")
        return cls(**data)

    def to_dict(self) -> dict[str, Any]:
        """JSON/TOML-serialisable dictionary (tuples become lists)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = json.loads(json.dumps(v)) if isinstance(v, tuple) else v
        return out

    @classmethod
    def from_file(cls, path: str | Path) -> Plant:
        """Load from a ``.toml`` or ``.json`` file (a ``[plant]`` table is accepted in TOML)."""
        path = Path(path)
        if not path.is_file():
            raise ValueError(f"plant file {str(path)!r} does not exist")
        text = path.read_text()
        try:
            if path.suffix.lower() == ".json":
                data = json.loads(text)
            elif path.suffix.lower() == ".toml":
                data = tomllib.loads(text)
            else:
                raise ValueError(f"plant file must end in .toml or .json, got {path.name!r}")
        except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
            raise ValueError(f"plant file {path.name!r} is not valid {path.suffix[1:].upper()}: {exc}") from exc
        if isinstance(data, dict) and set(data) == {"plant"}:
            data = data["plant"]
        return cls.from_dict(data)

    def to_file(self, path: str | Path) -> None:
        """Write to a ``.toml`` or ``.json`` file."""
        path = Path(path)
        if path.suffix.lower() == ".json":
            path.write_text(json.dumps(self.to_dict(), indent=2) + "\n")
        elif path.suffix.lower() == ".toml":
            import tomli_w

            path.write_text(tomli_w.dumps(self.to_dict()))
        else:
            raise ValueError(f"plant file must end in .toml or .json, got {path.name!r}")

    def plant_id(self) -> str:
        """Short stable hash of the parameter values (for grouping samples by plant)."""
        data = self.to_dict()
        # Fields added after plants were first hashed leave the id unchanged at their defaults.
        for name, default in _LATER_FIELD_DEFAULTS.items():
            if data.get(name) == default:
                data.pop(name)
        blob = json.dumps(data, sort_keys=True).encode()
        return hashlib.sha256(blob).hexdigest()[:16]

    # ------------------------------------------------------------------ derived values
    def bearing_force_scale_n(self, speed_rad_s: float) -> np.ndarray:
        """s_b = μ Ω R L³ / (4 c²) for bearings 1..4 (N), the Capone force scale."""
        r = np.asarray(self.bearing_radius_m)
        length = np.asarray(self.bearing_length_m)
        return self.viscosity_pa_s * speed_rad_s * r * length**3 / (4.0 * self.clearance_m**2)


#: Plant fields added later, with the defaults that keep earlier plant ids.
_LATER_FIELD_DEFAULTS: dict[str, float] = {"coupling_stiffness_n_m": 1.0e8, "coupling_damping_n_s_m": 0.0,
                                           "exciter_bearing_span_m": DEFAULT_EXCITER_BEARING_SPAN_M}


def check_range(name: str, value: float, lo: float, hi: float, *, hi_inclusive: bool = True) -> float:
    """Validate a scalar input against its allowed range; return it as ``float``.

    Raises
    ------
    ValueError
        Naming the parameter and its allowed range.
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number in [{lo}, {hi}], got {value!r}") from None
    ok = math.isfinite(v) and lo <= v and (v <= hi if hi_inclusive else v < hi)
    if not ok:
        close = "]" if hi_inclusive else ")"
        raise ValueError(f"{name} must be in [{lo}, {hi}{close}, got {value!r}")
    return v
