"""Bearing types as validated, immutable parameter sets with their film force, linearised
coefficients and static equilibrium (SI units; conventions in :mod:`._film`)."""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from . import _film as F

#: Central-difference steps of :meth:`coefficients`: positions by this fraction of the clearance,
#: velocities by this fraction of c·max(|Ω|, 1 rad/s).
FD_STEP = 1e-6
#: :meth:`equilibrium` stops when |F + W| ≤ this × |W| (or the step is below 1e-13 c).
EQ_RTOL = 1e-11
#: Static positions whose eccentricity (|r|/c) reaches this are refused: the film no longer carries the load.
EQ_MAX_ECCENTRICITY = 0.99


def _positive(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return v


class _Bearing:
    """Methods shared by every bearing type (a mix-in of the frozen dataclasses below)."""

    TYPE: ClassVar[str] = ""
    diameter_m: float
    length_m: float
    clearance_m: float

    def _check_geometry(self) -> None:
        for name in ("diameter_m", "length_m", "clearance_m"):
            object.__setattr__(self, name, _positive(name, getattr(self, name)))
        if self.clearance_m >= 0.05 * self.diameter_m:
            raise ValueError(f"clearance_m ({self.clearance_m} m) must be a radial clearance much smaller than "
                             f"the diameter ({self.diameter_m} m): give it in metres (e.g. 0.35e-3)")
        if hasattr(self, "viscosity_pa_s"):
            object.__setattr__(self, "viscosity_pa_s", _positive("viscosity_pa_s", self.viscosity_pa_s))

    # -- compiled form
    def kernel(self) -> tuple[int, np.ndarray]:
        """Type code and float64 parameter array for :func:`bearing_force` in compiled code."""
        raise NotImplementedError

    def _force(self, params: np.ndarray, x: float, y: float, vx: float, vy: float, w: float) -> tuple[float, float]:
        return F.bearing_force(self.kernel()[0], params, x, y, vx, vy, w)

    # -- public methods
    def force_n(self, x_m: float, y_m: float, vx_m_s: float, vy_m_s: float,
                speed_rad_s: float) -> tuple[float, float]:
        """Fluid force (N) on the journal at position (x, y) and velocity (vx, vy) relative to the
        bearing centre, shaft speed Ω (rad/s; Ω < 0 turns the other way). NaN outside the film."""
        _, p = self.kernel()
        fx, fy = self._force(p, float(x_m), float(y_m), float(vx_m_s), float(vy_m_s), float(speed_rad_s))
        return float(fx), float(fy)

    def coefficients(self, x_m: float, y_m: float, speed_rad_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Stiffness K (N/m) and damping C (N·s/m), 2×2, of the film linearised about the journal
        at rest at (x, y): ΔF = −K Δr − C Δv. Central differences, steps ``FD_STEP``·c in position
        and ``FD_STEP``·c·max(|Ω|, 1) in velocity (truncation ~1e-12, round-off ~1e-10 relative)."""
        _, p = self.kernel()
        x, y, w = float(x_m), float(y_m), float(speed_rad_s)
        hr = FD_STEP * self.clearance_m
        hv = FD_STEP * self.clearance_m * max(abs(w), 1.0)
        K = np.empty((2, 2))
        C = np.empty((2, 2))
        for j in range(2):
            e = np.zeros(4)
            e[j] = hr
            fp = np.array(self._force(p, x + e[0], y + e[1], 0.0, 0.0, w))
            fm = np.array(self._force(p, x - e[0], y - e[1], 0.0, 0.0, w))
            K[:, j] = -(fp - fm) / (2.0 * hr)
            v = np.zeros(2)
            v[j] = hv
            fp = np.array(self._force(p, x, y, v[0], v[1], w))
            fm = np.array(self._force(p, x, y, -v[0], -v[1], w))
            C[:, j] = -(fp - fm) / (2.0 * hv)
        if not (np.all(np.isfinite(K)) and np.all(np.isfinite(C))):
            raise ValueError(f"the journal at ({x_m:.4g}, {y_m:.4g}) m is outside (or at the edge of) the film "
                             f"of this {self.TYPE} bearing (clearance {self.clearance_m:.4g} m)")
        return K, C

    def reduced_coefficients(self, x_m: float, y_m: float, speed_rad_s: float,
                             whirl_rad_s: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """K and C for a linear analysis at the whirl frequency ω: for a film of fixed geometry they do
        not depend on ω and are :meth:`coefficients`; tilting pads reduce their tilts (Lund)."""
        return self.coefficients(x_m, y_m, speed_rad_s)

    def equilibrium(self, load_x_n: float, load_y_n: float, speed_rad_s: float) -> tuple[float, float]:
        """Static journal position (m, from the bearing centre) under a static load W = (load_x, load_y)
        applied to the journal (gravity: load_y < 0): the root of F(r, 0) + W = 0.

        Newton's method with the film stiffness, each step halved until the journal stays in the
        film and the residual falls; if that fails, the load is applied in 20 increments.

        Raises
        ------
        ValueError
            At Ω = 0 (no hydrodynamic film carries a static load), or when the film cannot carry the
            load (the journal reaches an eccentricity of ``EQ_MAX_ECCENTRICITY``).
        """
        W = np.array([float(load_x_n), float(load_y_n)])
        w = float(speed_rad_s)
        if not (np.all(np.isfinite(W)) and math.isfinite(w)):
            raise ValueError("load_x_n, load_y_n and speed_rad_s must be finite numbers")
        if not np.any(W):
            r = self._newton(np.zeros(2), W, w)
            if r is not None:
                return float(r[0]), float(r[1])
        if w == 0.0:
            raise ValueError(f"a {self.TYPE} bearing carries no static load at speed 0 (no hydrodynamic film): "
                             "give a speed > 0")
        r = self._newton(np.zeros(2), W, w)
        if r is None:
            r = np.zeros(2)
            for lam in np.linspace(0.05, 1.0, 20):
                r = self._newton(r, lam * W, w)
                if r is None:
                    break
        if r is None or self.film_eccentricity(r[0], r[1]) >= EQ_MAX_ECCENTRICITY:
            raise ValueError(f"the {self.TYPE} bearing cannot carry a load of {np.hypot(*W):.4g} N at "
                             f"{w:.4g} rad/s: the journal reaches eccentricity ≥ {EQ_MAX_ECCENTRICITY} of a film's "
                             "clearance (raise the speed, the length, the viscosity, or lower the load)")
        return float(r[0]), float(r[1])

    def _newton(self, r0: np.ndarray, W: np.ndarray, w: float) -> np.ndarray | None:
        _, p = self.kernel()
        c = self.clearance_m
        scale = float(np.hypot(*W))
        if scale == 0.0:        # no load: "zero" relative to the force the film makes at 0.1 c (round-off)
            scale = float(np.hypot(*self._force(p, 0.1 * c, 0.0, 0.0, 0.0, w)))
        scale = max(scale, 1e-300) if math.isfinite(scale) else 1e-300
        r = r0.copy()
        res = np.array(self._force(p, r[0], r[1], 0.0, 0.0, w)) + W
        if not np.all(np.isfinite(res)):
            return None
        for _ in range(100):
            if np.hypot(*res) <= EQ_RTOL * scale:
                return r
            try:
                K, _C = self.coefficients(r[0], r[1], w)
                step = np.linalg.solve(K, res)          # F + W − K Δr = 0
            except (ValueError, np.linalg.LinAlgError):
                return None
            ok = False
            for _h in range(40):
                rn = r + step
                if self.film_eccentricity(rn[0], rn[1]) < 1.0:
                    rn_res = np.array(self._force(p, rn[0], rn[1], 0.0, 0.0, w)) + W
                    if np.all(np.isfinite(rn_res)) and np.hypot(*rn_res) < np.hypot(*res):
                        ok = True
                        break
                step *= 0.5
            if not ok:
                return None
            r, res = rn, rn_res
            if np.hypot(*step) <= 1e-13 * c:
                return r
        return r if np.hypot(*res) <= 1e-8 * scale else None

    def film_eccentricity(self, x_m: float, y_m: float) -> float:
        """The journal's largest eccentricity in any of its films, as a fraction of that film's
        clearance (1: touching): |r|/c for the plain bearing."""
        return float(math.hypot(x_m, y_m) / self.clearance_m)

    # -- TOML / JSON
    def to_dict(self) -> dict[str, Any]:
        """Plain dict (``type`` first) that :func:`bearing_from_dict` reads back."""
        d: dict[str, Any] = {"type": self.TYPE}
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            d[f.name] = _listify(v)
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> _Bearing:
        """Build from a dict such as a TOML table; unknown keys are refused by name."""
        d = dict(data)
        t = d.pop("type", cls.TYPE)
        if _TYPE_ALIASES.get(t, t) != cls.TYPE:
            raise ValueError(f"type {t!r} does not name a {cls.TYPE} bearing")
        names = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
        unknown = sorted(set(d) - names)
        if unknown:
            raise ValueError(f"unknown key(s) {unknown} for a {cls.TYPE} bearing; expected some of {sorted(names)}")
        return cls(**d)


def _listify(v: Any) -> Any:
    if isinstance(v, tuple | list):
        return [_listify(x) for x in v]
    return v


@dataclasses.dataclass(frozen=True)
class PlainBearing(_Bearing):
    """Plain cylindrical bearing: Capone's closed form of the short (Ocvirk) bearing with the
    half-Sommerfeld condition, the film the simulator's paper model uses (MODEL.md section 4)."""

    TYPE: ClassVar[str] = "plain"
    diameter_m: float
    length_m: float
    clearance_m: float
    viscosity_pa_s: float

    def __post_init__(self) -> None:
        self._check_geometry()

    def kernel(self) -> tuple[int, np.ndarray]:
        return F.PLAIN, np.array([0.5 * self.diameter_m, self.length_m, self.clearance_m, self.viscosity_pa_s])

    def _force(self, params, x, y, vx, vy, w):  # type: ignore[no-untyped-def]
        return F.plain_force(params, x, y, vx, vy, w)


@dataclasses.dataclass(frozen=True)
class EllipticalBearing(_Bearing):
    """Two-lobe (elliptical, lemon-bore) bearing, split horizontally: a lower and an upper lobe,
    each an arc of ``lobe_arc_deg`` centred on the vertical, with the lobe clearance c_l =
    c/(1 − m) and its centre of curvature m·c_l from the bearing centre, away from the lobe.

    ``clearance_m`` is the assembled (minimum, vertical) radial clearance c; ``preload`` m =
    1 − c/c_l the ellipticity. Each lobe's film is the short-bearing solution with the
    half-Sommerfeld condition over its arc; the lobes' forces are summed.
    """

    TYPE: ClassVar[str] = "elliptical"
    diameter_m: float
    length_m: float
    clearance_m: float
    viscosity_pa_s: float
    preload: float = 0.5
    lobe_arc_deg: float = 150.0

    def __post_init__(self) -> None:
        self._check_geometry()
        m = float(self.preload)
        if not (0.0 <= m < 0.95):
            raise ValueError(f"preload must be in [0, 0.95), got {self.preload!r}")
        a = float(self.lobe_arc_deg)
        if not (0.0 < a <= 180.0):
            raise ValueError(f"lobe_arc_deg must be in (0, 180], got {self.lobe_arc_deg!r}")
        object.__setattr__(self, "preload", m)
        object.__setattr__(self, "lobe_arc_deg", a)

    def kernel(self) -> tuple[int, np.ndarray]:
        cl = self.clearance_m / (1.0 - self.preload)
        half = 0.5 * math.radians(self.lobe_arc_deg)
        p = [0.5 * self.diameter_m, self.length_m, self.clearance_m, self.viscosity_pa_s, 2.0]
        for th in (-0.5 * math.pi, 0.5 * math.pi):
            d = self.preload * cl
            p += [-d * math.cos(th), -d * math.sin(th), cl, th - half, th + half]
        return F.LOBED, np.array(p)

    def _force(self, params, x, y, vx, vy, w):  # type: ignore[no-untyped-def]
        return F.lobed_force(params, x, y, vx, vy, w)

    def film_eccentricity(self, x_m: float, y_m: float) -> float:
        """Largest |r − r_lobe|/c_l over the lobes (each lobe's circle of curvature bounds its film)."""
        _, p = self.kernel()
        return max(math.hypot(x_m - p[o], y_m - p[o + 1]) / p[o + 2] for o in (F.HEADER, F.HEADER + F.LOBE_STRIDE))


@dataclasses.dataclass(frozen=True)
class TiltingPadBearing(_Bearing):
    """Tilting-pad bearing, pad by pad: ``pads`` pads of ``pad_arc_deg`` (default: 80 % of the pitch
    360°/pads), pivoted at the fraction
    ``pivot_offset`` of the arc from the leading edge (for Ω > 0), pad clearance c_p = c/(1 − m)
    (``preload`` m), the load (−y) on a pad or between two pads.

    Each pad's film is the short-bearing solution over its arc; its tilt is the one that puts the
    film force through the pivot (moment equilibrium; pad inertia and pivot friction neglected,
    small tilt, and the pad taken at rest in tilt: :func:`._film.pad_force`). ``clearance_m`` is
    the assembled radial clearance c (at the pivots).

    :meth:`coefficients` linearises that quasi-static force; :meth:`reduced_coefficients` are Lund's
    pad-assembly coefficients at a whirl frequency (what a linear analysis wants), and
    :meth:`force_with_pad_states` carries the tilts as states (docs/bearings.md).
    """

    TYPE: ClassVar[str] = "tilting_pad"
    diameter_m: float
    length_m: float
    clearance_m: float
    viscosity_pa_s: float
    pads: int = 4
    pad_arc_deg: float | None = None
    pivot_offset: float = 0.5
    preload: float = 0.0
    load: str = "between_pads"

    LOADS: ClassVar[tuple[str, str]] = ("between_pads", "on_pad")

    def __post_init__(self) -> None:
        self._check_geometry()
        if isinstance(self.pads, bool) or not isinstance(self.pads, int | np.integer) or not 2 <= self.pads <= 12:
            raise ValueError(f"pads must be an integer from 2 to 12, got {self.pads!r}")
        a = 0.8 * 360.0 / self.pads if self.pad_arc_deg is None else float(self.pad_arc_deg)
        if not (0.0 < a and self.pads * a < 360.0):
            raise ValueError(f"pad_arc_deg must be > 0 and leave room between the {self.pads} pads "
                             f"(pads × arc < 360°), got {self.pad_arc_deg!r}")
        off = float(self.pivot_offset)
        if not (0.0 < off < 1.0):
            raise ValueError(f"pivot_offset (fraction of the arc from the leading edge) must be in (0, 1), got {self.pivot_offset!r}")
        m = float(self.preload)
        if not (0.0 <= m < 0.95):
            raise ValueError(f"preload must be in [0, 0.95), got {self.preload!r}")
        if self.load not in self.LOADS:
            raise ValueError(f"load must be one of {self.LOADS}, got {self.load!r}")
        object.__setattr__(self, "pads", int(self.pads))
        object.__setattr__(self, "pad_arc_deg", a)
        object.__setattr__(self, "pivot_offset", off)
        object.__setattr__(self, "preload", m)

    def pivot_angles_rad(self) -> np.ndarray:
        """Pivot angles θ_p (rad, from +x towards +y): a pad at −90° (``on_pad``) or two pads
        symmetric about −90° (``between_pads``)."""
        first = -0.5 * math.pi + (math.pi / self.pads if self.load == "between_pads" else 0.0)
        return first + 2.0 * math.pi * np.arange(self.pads) / self.pads

    def kernel(self) -> tuple[int, np.ndarray]:
        cp = self.clearance_m / (1.0 - self.preload)
        arc = math.radians(float(self.pad_arc_deg or 0.0))
        p = [0.5 * self.diameter_m, self.length_m, self.clearance_m, self.viscosity_pa_s, float(self.pads)]
        for th in self.pivot_angles_rad():
            d = cp - self.clearance_m
            ct, st = math.cos(th), math.sin(th)
            p += [-d * ct, -d * st, cp, th - self.pivot_offset * arc, th + (1.0 - self.pivot_offset) * arc, -st, ct]
        return F.TILTING_PAD, np.array(p)

    def _force(self, params, x, y, vx, vy, w):  # type: ignore[no-untyped-def]
        return F.tilting_pad_force(params, x, y, vx, vy, w)

    def film_eccentricity(self, x_m: float, y_m: float) -> float:
        """Largest approach to a pad along its pivot line, (r − r_pad)·e_pivot / c_p (pads tilt
        tangentially, so this is what bounds each pad's film)."""
        _, p = self.kernel()
        out = 0.0
        for k in range(self.pads):
            o = F.HEADER + F.PAD_STRIDE * k
            tx, ty = p[o + 5], p[o + 6]
            out = max(out, ((x_m - p[o]) * ty - (y_m - p[o + 1]) * tx) / p[o + 2])
        return float(out)

    def pad_tilts(self, x_m: float, y_m: float, speed_rad_s: float) -> np.ndarray:
        """Each pad's equilibrium tilt state u (centre-of-curvature shift along its pivot tangent, in
        units of the pad clearance) with the journal at rest at (x, y): the initial pad states of
        :meth:`force_with_pad_states`."""
        _, p = self.kernel()
        return np.array([F.pad_force(p, k, float(x_m), float(y_m), 0.0, 0.0, float(speed_rad_s))[2]
                         for k in range(self.pads)])

    def force_with_pad_states(self, x_m: float, y_m: float, vx_m_s: float, vy_m_s: float, speed_rad_s: float,
                              pad_tilts: np.ndarray) -> tuple[float, float, np.ndarray]:
        """Force (N) with the pad tilts as states (massless pads, each in moment equilibrium with its
        own squeeze film) and their rates du/dt (1/s): the pad dynamics that :meth:`force_n` freezes.
        Compiled: ``_film.tilting_pad_force_states`` (exported as ``tilting_pad_force_states``)."""
        _, p = self.kernel()
        u = np.ascontiguousarray(pad_tilts, dtype=float)
        if u.shape != (self.pads,):
            raise ValueError(f"pad_tilts must hold {self.pads} values, got shape {u.shape}")
        du = np.zeros(self.pads)
        fx, fy = F.tilting_pad_force_states(p, float(x_m), float(y_m), float(vx_m_s), float(vy_m_s),
                                            float(speed_rad_s), u, du)
        return float(fx), float(fy), du

    def pad_coefficients(self, x_m: float, y_m: float, speed_rad_s: float) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Per pad, at the journal at rest at (x, y): the pad's film K_p, C_p (2×2, the pad held at
        its equilibrium tilt; central differences as :meth:`coefficients`) and its tangent t."""
        _, p = self.kernel()
        x, y, w = float(x_m), float(y_m), float(speed_rad_s)
        hr = FD_STEP * self.clearance_m
        hv = FD_STEP * self.clearance_m * max(abs(w), 1.0)
        out = []
        for k in range(self.pads):
            fx, fy, u = F.pad_force(p, k, x, y, 0.0, 0.0, w)
            if not (math.isfinite(fx) and math.isfinite(fy)):
                raise ValueError(f"the journal at ({x_m:.4g}, {y_m:.4g}) m is outside the film of pad {k}")
            Kp = np.empty((2, 2))
            Cp = np.empty((2, 2))
            for j in range(2):
                e = np.eye(2)[j]
                fp = np.array(F.pad_fixed_force(p, k, u, x + hr * e[0], y + hr * e[1], 0.0, 0.0, w))
                fm = np.array(F.pad_fixed_force(p, k, u, x - hr * e[0], y - hr * e[1], 0.0, 0.0, w))
                Kp[:, j] = -(fp - fm) / (2.0 * hr)
                fp = np.array(F.pad_fixed_force(p, k, u, x, y, hv * e[0], hv * e[1], w))
                fm = np.array(F.pad_fixed_force(p, k, u, x, y, -hv * e[0], -hv * e[1], w))
                Cp[:, j] = -(fp - fm) / (2.0 * hv)
            o = F.HEADER + F.PAD_STRIDE * k
            out.append((Kp, Cp, p[o + 5:o + 7].copy()))
        return out

    def reduced_coefficients(self, x_m: float, y_m: float, speed_rad_s: float,
                             whirl_rad_s: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """K and C reduced at the whirl frequency ω (synchronous, ω = Ω, by default) by Lund's pad
        assembly method: each massless pad moves with the film (its tilt a degree of freedom), so
        with Z_p = K_p + iωC_p its reduced impedance is Z_p − Z_p t tᵀ Z_p / (tᵀ Z_p t), a purely
        radial term; K = Re ΣZ, C = Im ΣZ / ω. These are the coefficients tilting-pad tables quote.
        :meth:`coefficients` linearises the compiled force instead (pad at rest in tilt): its K is
        this K at ω → 0, its damping differs (see docs/bearings.md)."""
        w = float(speed_rad_s)
        om = w if whirl_rad_s is None else float(whirl_rad_s)
        if om <= 0.0:
            raise ValueError(f"whirl_rad_s must be > 0 (got {om!r}); at ω → 0 use coefficients()")
        Z = np.zeros((2, 2), dtype=complex)
        for Kp, Cp, t in self.pad_coefficients(x_m, y_m, w):
            Zp = Kp + 1j * om * Cp
            den = t @ Zp @ t
            Z += Zp - np.outer(Zp @ t, t @ Zp) / den if den != 0 else Zp
        return Z.real.copy(), Z.imag / om


def _matrices(value: Any, name: str, n: int | None) -> tuple:
    arr = np.asarray(value, dtype=float)
    if arr.shape == (2, 2):
        arr = arr[None]
    if arr.ndim != 3 or arr.shape[1:] != (2, 2) or (n is not None and arr.shape[0] != n):
        want = "a 2×2 matrix" if n in (None, 1) else f"{n} 2×2 matrices (one per speed)"
        raise ValueError(f"{name} must be {want}, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    return tuple(tuple(tuple(float(v) for v in row) for row in m) for m in arr)


@dataclasses.dataclass(frozen=True)
class LinearBearing(_Bearing):
    """Linear bearing: F = −K r − C v with the 8 coefficients, constant or tabulated against
    speed (``speeds_rad_s``, increasing) and interpolated linearly, held at the end values outside
    the table. ``diameter_m``, ``length_m`` and ``clearance_m`` describe the bearing (the probes'
    clearance); the force does not use them."""

    TYPE: ClassVar[str] = "linear"
    diameter_m: float
    length_m: float
    clearance_m: float
    stiffness_n_m: Any
    damping_n_s_m: Any
    speeds_rad_s: Any = None

    def __post_init__(self) -> None:
        self._check_geometry()
        n = None
        if self.speeds_rad_s is not None:
            s = np.atleast_1d(np.asarray(self.speeds_rad_s, dtype=float))
            if s.ndim != 1 or s.size < 1 or not np.all(np.isfinite(s)) or np.any(np.diff(s) <= 0):
                raise ValueError("speeds_rad_s must be a list of increasing finite speeds (rad/s)")
            n = s.size
            object.__setattr__(self, "speeds_rad_s", tuple(float(v) for v in s))
        k = _matrices(self.stiffness_n_m, "stiffness_n_m", n)
        c = _matrices(self.damping_n_s_m, "damping_n_s_m", n if n is not None else len(k))
        if n is None and len(k) != 1:
            raise ValueError("several stiffness matrices need speeds_rad_s (one speed per matrix)")
        object.__setattr__(self, "stiffness_n_m", k if n is not None else k[0])
        object.__setattr__(self, "damping_n_s_m", c if n is not None else c[0])

    def kernel(self) -> tuple[int, np.ndarray]:
        if self.speeds_rad_s is None:
            speeds, K, C = [0.0], [self.stiffness_n_m], [self.damping_n_s_m]
        else:
            speeds, K, C = list(self.speeds_rad_s), list(self.stiffness_n_m), list(self.damping_n_s_m)
        p = [float(len(speeds))] + speeds
        for k, c in zip(K, C, strict=True):
            p += list(np.ravel(k)) + list(np.ravel(c))
        return F.LINEAR, np.array(p, dtype=float)

    def _force(self, params, x, y, vx, vy, w):  # type: ignore[no-untyped-def]
        return F.linear_force(params, x, y, vx, vy, w)

    def coefficients(self, x_m: float, y_m: float, speed_rad_s: float) -> tuple[np.ndarray, np.ndarray]:
        """The (interpolated) K and C at this speed, exactly; the position does not matter."""
        _, p = self.kernel()
        w = float(speed_rad_s)
        K = np.empty((2, 2))
        C = np.empty((2, 2))
        for j in range(2):
            e = np.eye(2)[j]
            K[:, j] = -np.array(F.linear_force(p, e[0], e[1], 0.0, 0.0, w))
            C[:, j] = -np.array(F.linear_force(p, 0.0, 0.0, e[0], e[1], w))
        return K, C

    def equilibrium(self, load_x_n: float, load_y_n: float, speed_rad_s: float) -> tuple[float, float]:
        """r = K⁻¹ W (the linear bearing has no clearance limit)."""
        K, _ = self.coefficients(0.0, 0.0, speed_rad_s)
        try:
            r = np.linalg.solve(K, [float(load_x_n), float(load_y_n)])
        except np.linalg.LinAlgError:
            raise ValueError("the stiffness matrix of this linear bearing is singular: it carries no static load") from None
        return float(r[0]), float(r[1])


Bearing = PlainBearing | EllipticalBearing | TiltingPadBearing | LinearBearing
BEARING_TYPES: dict[str, type[_Bearing]] = {
    "plain": PlainBearing, "elliptical": EllipticalBearing, "tilting_pad": TiltingPadBearing, "linear": LinearBearing,
}
_TYPE_ALIASES = {"cylindrical": "plain", "two_lobe": "elliptical", "lemon": "elliptical", "tilting-pad": "tilting_pad"}


def bearing_from_dict(data: Mapping[str, Any]) -> Bearing:
    """The bearing a table names: ``{type = "tilting_pad", pads = 5, ...}`` (types: plain, elliptical
    (or two_lobe), tilting_pad, linear)."""
    if not isinstance(data, Mapping):
        raise ValueError(f"a bearing must be a table with a 'type' key, got {type(data).__name__}")
    t = data.get("type")
    cls = BEARING_TYPES.get(_TYPE_ALIASES.get(t, t)) if isinstance(t, str) else None
    if cls is None:
        raise ValueError(f"bearing type must be one of {sorted(BEARING_TYPES)}, got {t!r}")
    return cls.from_dict(data)  # type: ignore[return-value]
