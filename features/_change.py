"""Change against a baseline (issue 17): the same machine's known-good state versus now.

A :func:`signature` is the compact, JSON-able record of one recording that a comparison needs
(per bearing: 1X and 2X vectors of each probe direction with their phase validity, the shaft
centreline, orbit shape; the speed and the phase reference). :func:`change_features` compares
two signatures of the same asset:

* **1X / 2X vector change** per probe direction, ``|V_now − V_base|`` with ``V = A·e^{−jφ}``
  (µm pk-pk): a 180° phase change at equal amplitude is a change of ``2A``. The vector change is
  missing (NaN) when either phase is missing — the order is below the noise floor there
  (``BearingDetail.phase_valid``), or a recording has no keyphasor, so its phases are
  relative to an arbitrary first sample. The amplitude change ``|A_now| − |A_base|`` is always
  given; per bearing, ``{k}x_change_um_pp`` is the larger of the two directions' vector
  changes, or, where a vector change is missing, the amplitude change's size (a lower bound
  of the vector change).
* **Shaft-centreline displacement** per bearing (the mean position's change, µm).
* **Orbit shape change**: the 1X + 2X orbit's minor/major ratio and 2X/1X of the orbit axes.

Lengths come in µm and, when the clearance is known, as fractions of it (``_per_c``).
Comparisons are only meaningful at a comparable operating condition:
:data:`SPEED_BAND_FRAC` (±5 % of the baseline's speed); :func:`change_features` says when the
speeds are further apart (``comparable`` False) and then computes nothing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["SPEED_BAND_FRAC", "CHANGE_QUANTITIES", "ChangeResult", "signature", "change_features",
           "speed_comparable", "change_array", "average_signatures"]

#: relative speed difference within which two recordings of an asset are compared (±5 %)
SPEED_BAND_FRAC = 0.05
#: the per-bearing summary quantities a change verdict and the trend alarms use (µm, or 1 for ratios)
CHANGE_QUANTITIES: tuple[str, ...] = ("1x_change_um_pp", "2x_change_um_pp", "dc_shift_um",
                                      "orbit_ellipticity_change", "orbit_2x_1x_change")
_DIRS = ("x", "y")
_ORDERS = (1, 2)


def _f(v: Any) -> float:
    try:
        out = float(v)
    except (TypeError, ValueError):
        return math.nan
    return out


def _opt(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def signature(fr: Any) -> dict[str, Any]:
    """The JSON-able signature of a feature result (what a baseline stores).

    Parameters
    ----------
    fr : features.FeatureResult

    Returns
    -------
    dict
        ``speed_rpm``, ``phase_reference`` (``"keyphasor"`` or ``"first sample"``) and
        ``bearings``: a list of ``{"bearing", "clearance_um", "mean_x_um", "mean_y_um",
        "vectors": {"x_1x": {"amp_um_pp", "phase_deg"}, ...}, "orbit": {"ellipticity",
        "ratio_2x_1x"}}``; a phase is ``None`` where it is in the noise.
    """
    bearings = []
    for b, det in sorted((fr.bearings or {}).items()):
        vectors = {}
        for d in _DIRS:
            coeffs = det.x_coeffs_um if d == "x" else det.y_coeffs_um
            for k in _ORDERS:
                amp = 2.0 * abs(complex(coeffs[k - 1])) if len(coeffs) >= k else math.nan
                vectors[f"{d}_{k}x"] = {"amp_um_pp": _opt(amp), "phase_deg": _opt(det.phase_deg(d, k))}
        f = det.features
        bearings.append({
            "bearing": int(b), "clearance_um": _opt(_f(det.clearance_um)),
            # a recording without a DC position (dc_removed) has no centreline to compare: its shift is missing
            "mean_x_um": _opt(math.nan if det.dc_removed else _f(det.mean_um[0])),
            "mean_y_um": _opt(math.nan if det.dc_removed else _f(det.mean_um[1])),
            "vectors": vectors,
            "orbit": {"ellipticity": _opt(_f(f.get(f"b{b}_orbit12_ellipticity"))),
                      "ratio_2x_1x": _opt(_f(f.get(f"b{b}_2x_1x_major_ratio")))},
        })
    return {"speed_rpm": _opt(_f(fr.speed_rpm)), "phase_reference": str(fr.phase_reference), "bearings": bearings}


def speed_comparable(base_rpm: float | None, now_rpm: float | None, band: float = SPEED_BAND_FRAC) -> bool:
    """Whether ``now_rpm`` lies within ``band`` (relative) of ``base_rpm``; False when either is unknown."""
    b, n = _f(base_rpm), _f(now_rpm)
    return bool(math.isfinite(b) and math.isfinite(n) and b > 0 and abs(n / b - 1.0) <= band)


@dataclass(frozen=True)
class ChangeResult:
    """The comparison of a recording with its asset's baseline.

    Attributes
    ----------
    comparable : bool
        False when the speeds differ by more than the band (nothing else is computed then).
    speed_change_frac : float
        ``speed_now / speed_baseline − 1`` (NaN when a speed is unknown).
    values : dict
        ``b{n}_{d}_{k}x_dvec_um_pp`` (vector change per probe direction, NaN when a phase is
        missing), ``b{n}_{d}_{k}x_damp_um_pp`` (amplitude change, signed),
        ``b{n}_{k}x_change_um_pp`` (per bearing, see the module docstring), ``b{n}_dc_dx_um``,
        ``b{n}_dc_dy_um``, ``b{n}_dc_shift_um``, ``b{n}_orbit_ellipticity_change``,
        ``b{n}_orbit_2x_1x_change`` and the ``_per_c`` twins of the µm ones; bearings present
        in both signatures only.
    notes : tuple of str
        Why some quantities are missing.
    """

    comparable: bool
    speed_change_frac: float
    values: dict[str, float] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def per_bearing(self, quantity: str) -> dict[int, float]:
        """``{bearing: value}`` of a :data:`CHANGE_QUANTITIES` entry (finite values only)."""
        out = {}
        for b in range(1, 10):
            v = self.values.get(f"b{b}_{quantity}", math.nan)
            if math.isfinite(v):
                out[b] = v
        return out

    def largest(self, quantity: str) -> tuple[float, int | None]:
        """The largest value of a quantity over the bearings and its bearing (NaN, None when none)."""
        per = self.per_bearing(quantity)
        if not per:
            return math.nan, None
        b = max(per, key=lambda k: abs(per[k]))
        return abs(per[b]), b

    def to_dict(self) -> dict[str, Any]:
        return {"comparable": self.comparable, "speed_change_frac": _opt(self.speed_change_frac),
                "values": {k: _opt(v) for k, v in self.values.items()}, "notes": list(self.notes)}


def _vector(entry: dict[str, Any] | None) -> tuple[float, complex | None]:
    """(amplitude µm pk-pk, vector or None when the phase is missing) of a signature entry."""
    if not entry:
        return math.nan, None
    amp = _f(entry.get("amp_um_pp"))
    ph = _f(entry.get("phase_deg"))
    if not (math.isfinite(amp) and math.isfinite(ph)):
        return amp, None
    return amp, amp * complex(math.cos(math.radians(ph)), -math.sin(math.radians(ph)))


def change_features(base: dict[str, Any], now: dict[str, Any], *, band: float = SPEED_BAND_FRAC,
                    clearance_um: float | None = None) -> ChangeResult:
    """Compare the signature ``now`` with the baseline signature ``base``.

    Parameters
    ----------
    base, now : dict
        :func:`signature` outputs (as stored, i.e. after a JSON round trip).
    band : float
        Relative speed band within which the two are compared.
    clearance_um : float, optional
        Radial clearance for the ``_per_c`` values when a signature carries none.

    Returns
    -------
    ChangeResult
    """
    sb, sn = _f(base.get("speed_rpm")), _f(now.get("speed_rpm"))
    frac = sn / sb - 1.0 if math.isfinite(sb) and math.isfinite(sn) and sb > 0 else math.nan
    if not speed_comparable(sb, sn, band):
        why = ("a speed is unknown" if not math.isfinite(frac) else
               f"the speed differs from the baseline's by {100 * frac:+.1f} % (compared within ±{100 * band:g} %)")
        return ChangeResult(False, frac, {}, (why,))
    notes = []
    keyed = base.get("phase_reference") == "keyphasor" and now.get("phase_reference") == "keyphasor"
    if not keyed:
        notes.append("no keyphasor in the baseline or this recording: phases are relative to the first sample, "
                     "so only amplitude changes (lower bounds of the vector changes) are compared")
    bb = {int(e["bearing"]): e for e in base.get("bearings") or []}
    values: dict[str, float] = {}
    missing_phase = []
    for e in now.get("bearings") or []:
        b = int(e["bearing"])
        if b not in bb:
            continue
        eb = bb[b]
        c = _f(e.get("clearance_um"))
        if not (math.isfinite(c) and c > 0):
            c = _f(eb.get("clearance_um"))
        if not (math.isfinite(c) and c > 0):
            c = _f(clearance_um)
        p = f"b{b}_"
        um: dict[str, float] = {}
        for k in _ORDERS:
            change = math.nan
            for d in _DIRS:
                a0, v0 = _vector(eb["vectors"].get(f"{d}_{k}x"))
                a1, v1 = _vector(e["vectors"].get(f"{d}_{k}x"))
                dvec = abs(v1 - v0) if keyed and v0 is not None and v1 is not None else math.nan
                if keyed and math.isfinite(a0) and math.isfinite(a1) and not math.isfinite(dvec):
                    missing_phase.append(f"bearing {b} {d} {k}X")
                damp = a1 - a0
                um[f"{d}_{k}x_dvec_um_pp"] = dvec
                um[f"{d}_{k}x_damp_um_pp"] = damp
                best = dvec if math.isfinite(dvec) else abs(damp)
                if math.isfinite(best):
                    change = best if not math.isfinite(change) else max(change, best)
            um[f"{k}x_change_um_pp"] = change
        dx = _f(e.get("mean_x_um")) - _f(eb.get("mean_x_um"))
        dy = _f(e.get("mean_y_um")) - _f(eb.get("mean_y_um"))
        um["dc_dx_um"], um["dc_dy_um"], um["dc_shift_um"] = dx, dy, math.hypot(dx, dy)
        for name, v in um.items():
            values[p + name] = v
            values[p + name.replace("_um_pp", "_pp_per_c").replace("_um", "_per_c")] = \
                v / c if math.isfinite(c) and c > 0 else math.nan
        o0, o1 = eb.get("orbit") or {}, e.get("orbit") or {}
        values[p + "orbit_ellipticity_change"] = _f(o1.get("ellipticity")) - _f(o0.get("ellipticity"))
        values[p + "orbit_2x_1x_change"] = _f(o1.get("ratio_2x_1x")) - _f(o0.get("ratio_2x_1x"))
    if missing_phase:
        notes.append("phase in the noise (vector change missing, amplitude change used): "
                     + ", ".join(missing_phase[:8]) + (" …" if len(missing_phase) > 8 else ""))
    if not values:
        notes.append("no bearing is measured in both the baseline and this recording")
    return ChangeResult(True, frac, values, tuple(notes))


def change_array(result: ChangeResult, quantities: tuple[str, ...] = CHANGE_QUANTITIES) -> np.ndarray:
    """The largest value over the bearings of each quantity (absolute; NaN when not measured)."""
    return np.array([result.largest(q)[0] for q in quantities], dtype=float)


def average_signatures(signatures: list[dict[str, Any]]) -> dict[str, Any]:
    """One signature from several recordings of the same state (an automatic baseline).

    Vectors are averaged as vectors where every phase is known (else the amplitude is averaged and
    the phase is missing), centreline positions, orbit shape values and speeds as numbers, over the
    bearings present in every signature. The phase reference is ``"keyphasor"`` only if all have it.
    """
    if not signatures:
        raise ValueError("average_signatures needs at least one signature")

    def mean(vals: list[Any]) -> float | None:
        arr = np.array([_f(v) for v in vals], dtype=float)
        return _opt(float(arr.mean())) if len(arr) and np.isfinite(arr).all() else None

    common = set.intersection(*({int(e["bearing"]) for e in s.get("bearings") or []} for s in signatures))
    per = [{int(e["bearing"]): e for e in s.get("bearings") or []} for s in signatures]
    bearings = []
    for b in sorted(common):
        entries = [p[b] for p in per]
        vectors = {}
        for key in entries[0]["vectors"]:
            amps, vecs = [], []
            for e in entries:
                a, v = _vector(e["vectors"].get(key))
                amps.append(a)
                vecs.append(v)
            if all(v is not None for v in vecs):
                m = complex(np.mean(np.array(vecs, dtype=complex)))
                vectors[key] = {"amp_um_pp": _opt(abs(m)), "phase_deg": _opt(math.degrees(-math.atan2(m.imag, m.real)) % 360.0)}
            else:
                vectors[key] = {"amp_um_pp": mean(amps), "phase_deg": None}
        bearings.append({
            "bearing": b, "clearance_um": mean([e.get("clearance_um") for e in entries]),
            "mean_x_um": mean([e.get("mean_x_um") for e in entries]),
            "mean_y_um": mean([e.get("mean_y_um") for e in entries]),
            "vectors": vectors,
            "orbit": {k: mean([(e.get("orbit") or {}).get(k) for e in entries]) for k in ("ellipticity", "ratio_2x_1x")},
        })
    keyed = all(s.get("phase_reference") == "keyphasor" for s in signatures)
    return {"speed_rpm": mean([s.get("speed_rpm") for s in signatures]),
            "phase_reference": "keyphasor" if keyed else "first sample", "bearings": bearings}
