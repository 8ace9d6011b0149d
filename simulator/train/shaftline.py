"""The finite-element train of a shaft-line description (``rotordiag.simulator.shaftline.ShaftLine``).

A shaft line names, per rotor, its segments between its bearings, the overhang from the coupling-end
bearing to the coupling flange, body masses and disks; four bearing slots (types of
``rotordiag.simulator.bearings``, or ``none`` at bearing 4 for an exciter overhung on its coupling-end
bearing), their centres, and the coupling. :func:`train_from_shaftline` turns it into a :class:`Train`
directly, with no lumped reduction:

- generator stations from bearing 1 (z = 0) over its segments to bearing 2, then its overhang to the
  flange; exciter stations from the flange over its overhang to bearing 3, then its segments to
  bearing 4 (or its free end);
- every segment cut into elements of at most ``max_element_m``, a station at every body mass and disk;
- the generator's two-pole asymmetry ρ (``generator_asymmetry``) on its body: the segments of its
  largest diameter;
- body masses as point masses (no inertia: the old tables give none), disks with their inertias;
- the generator's residual unbalance (``generator_unbalance_kg_m``; a preset's ISO 21940-11 G2.5) at the
  middle of its span, along the keyphasor mark;
- stationary stiffness-proportional damping β = 2ζ/ω₁ with ω₁ the generator's first pinned bending
  frequency, so that mode has the description's ``damping_ratio`` (the lumped model's rotor damping).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ..bearings import bearing_from_dict
from ..shaftline import MATERIALS, ShaftLine, reduce_rotor
from ..shaftline import Rotor as LineRotor
from .model import Coupling, Disk, Material, Rotor, ShaftElement, Support, Train, TrainError, Unbalance

#: a shaft-line train has at most this many stations (the static solution and modes stay seconds)
MAX_STATIONS = 160
#: shear modulus from E with ν = 0.3 (rotor steel)
_POISSON = 0.3


def _stations(pieces: list[tuple[float, float, float]], points: list[float], max_element_m: float,
              ) -> tuple[list[ShaftElement], np.ndarray]:
    """Elements (length, diameter, asymmetry) of ``pieces`` in order, a station at every point of ``points``."""
    xs = [0.0]
    props: list[tuple[float, float]] = []
    for length, dia, rho in pieces:
        n = max(1, math.ceil(length / max_element_m - 1e-9))
        for _ in range(n):
            xs.append(xs[-1] + length / n)
            props.append((dia, rho))
    for x in sorted(points):
        arr = np.array(xs)
        if np.min(np.abs(arr - x)) <= 1e-9:
            continue
        i = int(np.searchsorted(arr, x))
        xs.insert(i, x)
        props.insert(i - 1, props[i - 1])
    elems = [ShaftElement(xs[k + 1] - xs[k], d, 0.0, r) for k, (d, r) in enumerate(props)]
    return elems, np.array(xs)


def _at(xs: np.ndarray, x: float) -> int:
    return int(np.argmin(np.abs(xs - x)))


def _bearing(line: ShaftLine, k: int):
    t = line.bearing_types[k]
    d: dict[str, Any] = {"type": t, "diameter_m": line.bearing_diameter_m[k], "length_m": line.bearing_length_m[k],
                         "clearance_m": line.clearance_m}
    if t != "linear":
        d["viscosity_pa_s"] = line.viscosity_pa_s
    d.update(line.bearing_options[k])
    try:
        return bearing_from_dict(d)
    except (TypeError, ValueError) as exc:
        raise TrainError(f"bearing {k + 1} ({t}): {exc}") from None


def _rotor(name: str, lr: LineRotor, rho: float, material: Material, max_element_m: float, *, first: bool,
           bearings: list[tuple[int, Any, tuple[float, float]]], unbalance_kg_m: float = 0.0) -> tuple[Rotor, float]:
    """One train rotor; ``bearings`` = (slot, bearing, centre) at the two ends of the segments (slot −1: none);
    ``unbalance_kg_m`` at the middle of its span, along the keyphasor mark."""
    body_d = max(d for _, d in lr.segments)
    seg = [(length, d, rho if (rho and d == body_d) else 0.0) for length, d in lr.segments]
    over = [(length, d, 0.0) for length, d in lr.overhang]
    over_l = sum(x[0] for x in lr.overhang)
    span = lr.span_m
    if first:  # bearing a at z = 0, segments, bearing b, overhang to the flange
        pieces, shift = seg + over, 0.0
    else:  # flange, overhang (reversed: given from the flange), bearing a, segments, bearing b
        pieces, shift = over + seg, over_l
    points = [shift + x for x, _ in lr.body_masses] + [shift + d[0] for d in lr.disks] + [shift, shift + span]
    if unbalance_kg_m > 0:
        points.append(shift + span / 2)
    elems, xs = _stations(pieces, points, max_element_m)
    disks = [Disk(_at(xs, shift + x), m) for x, m in lr.body_masses]
    disks += [Disk(_at(xs, shift + x), m, jp, jt) for x, m, jp, jt in lr.disks]
    sup = []
    for (slot, brg, (cx, cy)), z in zip(bearings, (shift, shift + span), strict=True):
        if brg is not None:
            sup.append(Support(_at(xs, z), brg, cx, cy, name=f"B{slot + 1}"))
    unb = (Unbalance(_at(xs, shift + span / 2), unbalance_kg_m, 0.0),) if unbalance_kg_m > 0 else ()
    return Rotor(name, tuple(elems), disks=tuple(disks), supports=tuple(sup), unbalances=unb,
                 material=material), span


def train_from_shaftline(line: ShaftLine, *, max_element_m: float = 0.3) -> Train:
    """The :class:`Train` of a shaft line (module docstring); raises :class:`TrainError` saying what to fix."""
    if not (math.isfinite(max_element_m) and 0.02 <= max_element_m <= 5.0):
        raise TrainError(f"max_element_m must be within 0.02..5 m (got {max_element_m!r})")
    E, rho_m = MATERIALS[line.material]
    material = Material(young_pa=E, shear_pa=E / (2 * (1 + _POISSON)), density_kg_m3=rho_m)
    brg = [None if t == "none" else _bearing(line, k) for k, t in enumerate(line.bearing_types)]
    c = line.bearing_centres_m
    gen, _ = _rotor("generator", line.generator, line.generator_asymmetry, material, max_element_m, first=True,
                    bearings=[(0, brg[0], c[0]), (1, brg[1], c[1])], unbalance_kg_m=line.generator_unbalance_kg_m)
    exc, _ = _rotor("exciter", line.exciter, 0.0, material, max_element_m, first=False,
                    bearings=[(2, brg[2], c[2]), (3, brg[3], c[3])])
    n = gen.n_stations + exc.n_stations
    if n > MAX_STATIONS:
        raise TrainError(f"the shaft line makes {n} stations, more than {MAX_STATIONS}: raise max_element_m "
                         f"(now {max_element_m:g} m) or give fewer body masses and disks")
    if line.coupling == "rigid":
        cpl = Coupling("rigid")
    else:
        cpl = Coupling("flexible", lateral_stiffness_n_m=line.coupling_stiffness_n_m,
                       angular_stiffness_n_m_rad=line.coupling_angular_stiffness_n_m_rad,
                       lateral_damping_n_s_m=line.coupling_damping_n_s_m,
                       angular_damping_n_m_s_rad=line.coupling_angular_damping_n_m_s_rad)
    w1 = 2 * math.pi * reduce_rotor(line.generator, line.material).first_pinned_hz
    return Train((gen, exc), (cpl,), rayleigh_stiffness_s=2 * line.damping_ratio / w1)


def shaftline_of(preset: str | None = None, path: str | Path | None = None) -> tuple[ShaftLine, float | None]:
    """The shaft line of a preset name or a shaft-line TOML file (exactly one), and its rated speed (r/min;
    a preset's first, None for a file); a ``ValueError`` saying what to fix otherwise."""
    from ..shaftline import PRESETS
    from ..shaftline import preset as named

    if (preset is None) == (path is None):
        raise ValueError("give either a preset name or a shaft-line file, not both or neither")
    if preset is not None:
        line = named(preset)
        return line, float(PRESETS[preset]["rated_speed_rpm"][0])
    return ShaftLine.from_file(path), None  # type: ignore[arg-type]
