"""Which way the exciter sits relative to the generator, and the angular offset at the coupling, with intervals.

A model trained on data that records each sample's offset direction (``offset_angle_rad``: a shaft train's exciter
bearings moved by δ = Δ·c along it, ``simulator.train.model.misaligned``) carries *direction heads*: three
:class:`~rotordiag.models.estimators.ConformalIntervalRegressor` on the same feature row as the verdict's model —
the offset's horizontal and vertical components per clearance, Δ·cos φ and Δ·sin φ (signed), and the angular
offset α in mrad where training varied it. They are fitted on the rows whose shaft centreline is known
(``b{n}_centre_[xy]_per_c``: DC-coupled probes and the clearance stated), since the direction of a *static* offset
shows in where the journals sit (the load it moves between the bearings, the attitude), which the AC part of a
recording does not carry. The direction's angle is read from the two component heads' point models (fitted on
every plant), and its 90 % half-width is the split-conformal quantile of the angle errors that the heads' centre
models (fitted without the heads' calibration plants) make on those calibration plants, one per bin of the
estimated offset size (Mondrian conformal: a small offset's direction is less certain than a large one's). The
half-width is thus calibrated for the centre models, not exactly for the point models the answer reads (more
plants, on the report's recordings the more accurate: docs/models.md); its coverage is measured, not guaranteed.
α keeps its head's own conformal interval.

:func:`direction_answer` turns the heads' output into the verdict's ``direction`` and ``angular_offset`` (or says
why there is none: a model without heads, an AC-coupled recording or one without the clearance, an aligned or
inconclusive verdict). Frame: x horizontal, y vertical up, the features' frame (docs/recordings.md: angles
counter-clockwise from the horizontal to the observer's right, seen from the end from which the shaft turns
counter-clockwise).
"""
from __future__ import annotations

import math
import weakref
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from sklearn.base import clone

from ._patterns import name_mask

#: the shaft-centreline features (journal DC positions per clearance) that carry a static offset's direction
DC_PATTERNS: tuple[str, ...] = ("b*_centre_x_per_c", "b*_centre_y_per_c")
#: the heads' names and what each regresses
HEADS: tuple[str, ...] = ("horizontal_per_c", "vertical_per_c", "angular_mrad")
#: fewest training rows with a known centreline to fit the heads on
MIN_DC_ROWS = 30
#: edges of the bins of the estimated offset size |(horizontal, vertical)| (per clearance) within which the angle's
#: conformal half-width is calibrated apart
MAGNITUDE_EDGES: tuple[float, ...] = (0.1, 0.25)
#: the viewing convention every answer states
CONVENTION = ("x horizontal, y vertical up, in the features' frame: seen from the end from which the shaft turns "
              "counter-clockwise (docs/recordings.md), 'right' is the observer's right; the exciter's offset is "
              "its line's position relative to the generator's at the coupling")


def dc_columns(feature_names: Sequence[str]) -> np.ndarray:
    """Indices of the shaft-centreline columns among ``feature_names``."""
    return np.flatnonzero(name_mask(tuple(feature_names), DC_PATTERNS))


def has_dc(X: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """Per row, whether any shaft-centreline feature is known (DC-coupled probes read with the clearance), bool."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    if columns.size == 0:
        return np.zeros(X.shape[0], dtype=bool)
    return np.isfinite(X[:, columns]).any(axis=1)


def fit_direction_heads(X: np.ndarray, feature_names: Sequence[str], delta: np.ndarray, offset_angle_rad: np.ndarray,
                        angular_mrad: np.ndarray | None, groups: np.ndarray | None, regressor: Any) -> dict[str, Any]:
    """The direction heads of a model: fitted on the rows of ``X`` with a known centreline.

    Parameters
    ----------
    X : (n, p) feature rows, the model's columns (NaN = missing); ``feature_names`` their names
    delta, offset_angle_rad : (n,) the true Δ = δ/c and the offset's direction (rad, from +x toward +y)
    angular_mrad : (n,) or None — the true angular offset α (mrad); None or constant: no α head
    groups : (n,) plant ids (the conformal calibration holds out whole plants), or None
    regressor : an unfitted ``ConformalIntervalRegressor`` (its ``lower_bound`` is cleared: the targets are signed)

    Returns
    -------
    dict
        ``heads`` (name → fitted regressor or None), ``dc_columns``, ``n_rows``, ``n_plants``, ``interval_level``,
        ``angular_range_mrad`` (None without an α head), ``magnitude_edges``, ``angle_halfwidth_deg`` (the angle's
        calibrated half-width per size bin) and ``angle_calibration_rows`` (the calibration rows behind each).

    Raises
    ------
    ValueError
        Fewer than :data:`MIN_DC_ROWS` rows with a known centreline, or labels of the wrong length.
    """
    X = np.asarray(X, dtype=float)
    n = X.shape[0]
    delta = np.asarray(delta, dtype=float)
    phi = np.asarray(offset_angle_rad, dtype=float)
    if delta.shape != (n,) or phi.shape != (n,):
        raise ValueError(f"direction labels: expected {n} values each, got Δ {delta.shape}, angle {phi.shape}")
    cols = dc_columns(feature_names)
    rows = has_dc(X, cols) & np.isfinite(delta) & np.isfinite(phi)
    if int(rows.sum()) < MIN_DC_ROWS:
        raise ValueError(f"direction heads: {int(rows.sum())} training rows carry the shaft centreline (DC positions "
                         f"with the clearance); at least {MIN_DC_ROWS} are needed")
    g = None if groups is None else np.asarray(groups)[rows]
    targets: dict[str, np.ndarray | None] = {
        "horizontal_per_c": delta[rows] * np.cos(phi[rows]),
        "vertical_per_c": delta[rows] * np.sin(phi[rows]),
        "angular_mrad": None,
    }
    alpha_range = None
    if angular_mrad is not None:
        a = np.asarray(angular_mrad, dtype=float)
        if a.shape != (n,):
            raise ValueError(f"angular offset labels: expected {n} values, got {a.shape}")
        a = a[rows]
        if np.isfinite(a).all() and np.ptp(a) > 0:
            targets["angular_mrad"] = a
            alpha_range = [float(a.min()), float(a.max())]
    heads: dict[str, Any] = {}
    for name, y in targets.items():
        heads[name] = None if y is None else clone(regressor).set_params(lower_bound=None).fit(X[rows], y, groups=g)
    level = 1.0 - float(heads["horizontal_per_c"].alpha)
    out = {"heads": heads, "dc_columns": cols, "n_rows": int(rows.sum()),
           "n_plants": int(rows.sum()) if g is None else int(len(np.unique(g))),
           "interval_level": level, "angular_range_mrad": alpha_range, "magnitude_edges": list(MAGNITUDE_EDGES)}
    out.update(_calibrate_angle(out, X[rows], delta[rows], phi[rows], g, level))
    return out


def _calibration_rows(reg: Any, X: np.ndarray, groups: np.ndarray | None) -> np.ndarray:
    """The rows a fitted ``ConformalIntervalRegressor`` held out of its centre model (its calibration part), drawn
    again by the same split it made (same fraction, seed and groups)."""
    from sklearn.model_selection import GroupShuffleSplit, ShuffleSplit

    if groups is not None and len(np.unique(groups)) >= 2:
        split = GroupShuffleSplit(n_splits=1, test_size=reg.calibration_fraction, random_state=reg.random_state)
        return next(split.split(X, None, groups))[1]
    split = ShuffleSplit(n_splits=1, test_size=reg.calibration_fraction, random_state=reg.random_state)
    return next(split.split(X))[1]


def offset_angle(direction: Mapping[str, Any], X: np.ndarray, *, calibration: bool = False
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(angle rad, size per clearance) of the offset of each row of ``X``: from the component heads' point models
    (fitted on every plant: the answer's), or with ``calibration`` from their centre models (fitted without the
    calibration plants: what the half-width is calibrated on)."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    col = 1 if calibration else 0                       # CompiledRegressor.raw: point, centre(, scale)
    hc = _compiled(direction["heads"]["horizontal_per_c"], X.shape[1]).raw(X)[:, col]
    vc = _compiled(direction["heads"]["vertical_per_c"], X.shape[1]).raw(X)[:, col]
    return np.arctan2(vc, hc), np.hypot(hc, vc)


def _calibrate_angle(direction: Mapping[str, Any], X: np.ndarray, delta: np.ndarray, phi: np.ndarray,
                     groups: np.ndarray | None, level: float) -> dict[str, Any]:
    """Split-conformal half-width of the angle in each size bin (:data:`MAGNITUDE_EDGES`): the
    ⌈(m + 1)·level⌉-th smallest angle error of the m calibration rows with a true offset (Δ > 0) in that bin
    (180°: too few rows for the level, or none)."""
    h = direction["heads"]["horizontal_per_c"]
    cal = _calibration_rows(h, X, groups)
    cal = cal[delta[cal] > 0]
    theta, size = offset_angle(direction, X[cal], calibration=True)
    err = np.abs((np.degrees(theta - phi[cal]) + 180.0) % 360.0 - 180.0)
    bins = np.searchsorted(MAGNITUDE_EDGES, size, side="right")
    half, counts = [], []
    for b in range(len(MAGNITUDE_EDGES) + 1):
        e = np.sort(err[bins == b])
        rank = math.ceil((e.size + 1) * level)
        half.append(float(e[rank - 1]) if rank <= e.size else 180.0)
        counts.append(int(e.size))
    return {"angle_halfwidth_deg": half, "angle_calibration_rows": counts}


def angle_halfwidth_deg(direction: Mapping[str, Any], size_per_c: float) -> float:
    """The angle's calibrated 90 % half-width (degrees) for an offset of estimated size ``size_per_c``."""
    edges = direction.get("magnitude_edges", list(MAGNITUDE_EDGES))
    return float(direction["angle_halfwidth_deg"][int(np.searchsorted(edges, size_per_c, side="right"))])


_COMPILED: weakref.WeakKeyDictionary[Any, Any] = weakref.WeakKeyDictionary()


def _compiled(reg: Any, n_features: int) -> Any:
    """The head's ``models.compiled.CompiledRegressor`` (built once per fitted head): a verdict's single row through
    scikit-learn's predict methods costs ~4 ms per ensemble, through the flattened trees a few µs (the same numbers,
    tests/test_models_direction.py)."""
    from .compiled import CompiledRegressor

    try:
        return _COMPILED[reg]
    except KeyError:
        fast = _COMPILED[reg] = CompiledRegressor(reg, n_features)
        return fast


def predict_heads(direction: Mapping[str, Any], X: np.ndarray, names: Sequence[str] = HEADS
                  ) -> dict[str, tuple[np.ndarray, np.ndarray] | None]:
    """Each of the ``names`` heads' ``(point (n,), interval (n, 2))`` of rows ``X`` (None for a head the model
    lacks), as the heads' ``predict`` and ``predict_interval``."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    out: dict[str, tuple[np.ndarray, np.ndarray] | None] = {}
    for name in names:
        reg = direction["heads"].get(name)
        out[name] = None if reg is None else _compiled(reg, X.shape[1]).predict_interval(X)
    return out


def _not_given(code: str, why: str) -> dict[str, Any]:
    return {"estimated": False, "code": code, "why_not": why}


def direction_answer(direction: Mapping[str, Any] | None, row: np.ndarray, *, aligned_call: bool,
                     inconclusive: bool, delta: float | None, delta_interval: tuple[float | None, float | None],
                     clearance_um: float | None, dc_removed: bool) -> tuple[dict[str, Any], dict[str, Any]]:
    """The verdict's ``direction`` and ``angular_offset`` from a model's direction heads (``direction``: the
    model's ``direction_heads_``, None for a model trained without them) and the row it answered.

    Direction: none for an inconclusive verdict, an "aligned" call (no offset to point), a recording without the
    shaft centreline (AC-coupled, means removed, or no clearance). Otherwise the angle θ (:func:`offset_angle`) with
    its calibrated 90 % half-width q (:func:`angle_halfwidth_deg`), and the components δ·cos θ, δ·sin θ of the
    verdict's own offset δ = Δ·c, so that the direction's size is the verdict's Δ (never a second, contradicting
    one). Each component's interval is its range over the verdict's Δ interval and the arc θ ± q (both 90 %: the
    pair holds with at least 80 %). A side (high/low, right/left) is named only where the whole arc lies on it —
    then that component's interval does not cross 0; otherwise the component is "not resolved".

    Angular offset: α with its head's 90 % interval where the model has an α head, under the same conditions except
    that an "aligned" call still gets it (α is not part of the band).
    """
    if direction is None:
        why = ("this model was trained without direction labels (the shipped v0001: the paper's lumped model, whose "
               "datasets do not teach where the exciter sits); a model retrained for the plant on its shaft train "
               "(rotordiag retrain) estimates it")
        return _not_given("model_without_direction", why), _not_given("model_without_direction", why)
    if inconclusive:
        why = "the verdict is inconclusive: no offset is given, so neither is its direction"
        return _not_given("inconclusive", why), _not_given("inconclusive", why)
    row = np.asarray(row, dtype=float)[None, :]
    cols = np.asarray(direction["dc_columns"], dtype=np.intp)
    if not has_dc(row, cols)[0]:
        why = ("the recording carries no DC position (AC-coupled probes, or each channel's mean removed): the "
               "direction of a static offset shows only in where the journals sit" if dc_removed else
               "the shaft centreline is not known: give the bearing clearance (clearance_um) with DC-coupled, "
               "gap-referenced probes; the direction is read from the journals' positions per clearance")
        code = "no_dc_position" if dc_removed else "no_centreline"
        return _not_given(code, why), _not_given(code, why)
    level = float(direction["interval_level"])
    ang: dict[str, Any]
    a = predict_heads(direction, row, ("angular_mrad",)).get("angular_mrad")
    if a is None:
        ang = _not_given("angular_not_trained", "the model's training data carried no angular offset")
    else:
        ang = {"estimated": True, "angular_mrad": float(a[0][0]),
               "interval_mrad": [float(a[1][0, 0]), float(a[1][0, 1])], "interval_level": level,
               "training_range_mrad": direction.get("angular_range_mrad"),
               "meaning": "α > 0: the exciter's line rises away from the coupling along the offset's direction"}
    if aligned_call or delta is None:
        return _not_given("aligned", "the call is aligned: there is no offset to give a direction to"), ang
    theta_rad, size = offset_angle(direction, row)
    theta = float(np.degrees(theta_rad[0])) % 360.0
    half = angle_halfwidth_deg(direction, float(size[0]))
    scale = float(clearance_um) if clearance_um is not None else 1.0
    lo_d = float(delta if delta_interval[0] is None else delta_interval[0])
    hi_d = float(delta if delta_interval[1] is None else delta_interval[1])
    comps = {}
    for name, fn, peaks in (("horizontal", math.cos, (0.0, 180.0)), ("vertical", math.sin, (90.0, 270.0))):
        lo_t, hi_t = _arc_range(fn, theta, half, peaks)
        shown = float(delta) * fn(math.radians(theta)) * scale
        ends = [x * scale for x in (lo_d * lo_t, hi_d * lo_t, lo_d * hi_t, hi_d * hi_t)]
        comps[name] = {"value": shown, "interval": [min(*ends, shown), max(*ends, shown)],
                       "side": 1 if lo_t > 0 else (-1 if hi_t < 0 else 0)}
    out = {"estimated": True, "angle_deg": theta, "angle_halfwidth_deg": half,
           "unit": "um" if clearance_um is not None else "per_c",
           "horizontal": comps["horizontal"], "vertical": comps["vertical"], "interval_level": level,
           "convention": CONVENTION}
    out["text"] = direction_text(out)
    return out, ang


def _arc_range(fn: Any, centre_deg: float, half_deg: float, peaks: tuple[float, float]) -> tuple[float, float]:
    """(min, max) of ``fn`` (cos or sin) over the arc centre ± half (degrees); ``peaks``: where it is +1 and −1."""
    if half_deg >= 180.0:
        return -1.0, 1.0

    def inside(p: float) -> bool:
        return abs((p - centre_deg + 180.0) % 360.0 - 180.0) <= half_deg

    ends = [fn(math.radians(centre_deg - half_deg)), fn(math.radians(centre_deg + half_deg))]
    return (-1.0 if inside(peaks[1]) else min(ends)), (1.0 if inside(peaks[0]) else max(ends))


def _side(comp: Mapping[str, Any], pos: str, neg: str, unit: str, scale: float) -> str:
    lo, hi = (scale * float(x) for x in comp["interval"])
    value = scale * float(comp["value"])
    nd = {"µm": 0, "mil": 2}.get(unit, 3)
    span = f"{lo:.{nd}f} … {hi:.{nd}f} {unit}"
    if comp["side"] > 0:
        return f"{pos} by {abs(value):.{nd}f} {unit} ({span})"
    if comp["side"] < 0:
        return f"{neg} by {abs(value):.{nd}f} {unit} ({span})"
    return f"{pos}/{neg} not resolved ({span})"


def direction_text(d: Mapping[str, Any], output_units: str = "um") -> str:
    """One line: "exciter toward 254° ± 30°: low by 280 µm (…), to the left by 81 µm (…)" with the intervals'
    level; lengths in ``output_units`` (um | mil) when the components are in µm."""
    from rotordiag.core.units import um_to

    if d["unit"] == "um":
        mil = str(output_units).strip().lower().startswith("mil")
        unit, scale = ("mil", float(um_to(1.0, "mil"))) if mil else ("µm", 1.0)
    else:
        unit, scale = "× c", 1.0
    arc = ("any direction" if d["angle_halfwidth_deg"] >= 180.0
           else f"{d['angle_deg']:.0f}° ± {d['angle_halfwidth_deg']:.0f}°")
    return (f"exciter toward {arc} (from horizontal-right, counter-clockwise): "
            f"{_side(d['vertical'], 'high', 'low', unit, scale)}, "
            f"{_side(d['horizontal'], 'to the right', 'to the left', unit, scale)} "
            f"({d['interval_level']:.0%} intervals; seen from the end from which the shaft turns counter-clockwise)")


def angle_error_deg(estimated_deg: float, true_rad: float) -> float:
    """Smallest angle between an estimated direction (degrees) and the true one (radians), 0–180°."""
    d = (float(estimated_deg) - math.degrees(float(true_rad))) % 360.0
    return min(d, 360.0 - d)
