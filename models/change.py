"""The change verdict against an asset's baseline (issue 17): thresholds on the change features.

A small, documented JSON of thresholds rather than a fitted estimator: the change features
(``features.change_features``) are already the physical quantities an engineer alarms on (1X/2X
vector change, centreline shift, orbit shape change), the question per quantity is only *how
much change is more than re-recording the unchanged machine gives* (runout and noise redrawn,
speed within the band), and a threshold answers that, transfers to machines of other designs
and can be edited per asset (the trend alarms). The thresholds are fitted by
:func:`fit_thresholds` on simulated re-recordings of unchanged machines of the calibration
plants (``benchmarks/bench_baseline.py --write-thresholds``) and shipped as
``models/default/change_thresholds.json``.

Rule: the recording has **changed** when any quantity's largest value over the bearings
exceeds its threshold. A ``_per_c`` threshold applies only when the clearance is known, and a
quantity in µm together with its ``_per_c`` twin both have to be exceeded (a shift of 20 µm is
small in a 600 µm bearing and large in a 150 µm one; a fraction of a small clearance can be
within the runout).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rotordiag.core.notes import Length, Measured, Note
from rotordiag.core.timefmt import readable_time

__all__ = ["ChangeRule", "THRESHOLDS_PATH", "QUANTITIES", "fit_thresholds", "shipped_rule", "assess_change", "compare",
           "load_baseline_file", "format_change", "UNITS", "repeatability_thresholds", "REPEAT_MIN", "REPEAT_MARGIN",
           "REPEAT_FLOOR", "REPEAT_QUANTITIES", "thresholds_from_spread", "thresholds_basis", "BASIS_REASONS",
           "basis_note"]

THRESHOLDS_PATH = Path(__file__).resolve().parent / "default" / "change_thresholds.json"

#: quantity → (µm name, per-clearance name or None); each is the largest value over the bearings
QUANTITIES: dict[str, tuple[str, str | None]] = {
    "1x_change": ("1x_change_um_pp", "1x_change_pp_per_c"),
    "2x_change": ("2x_change_um_pp", "2x_change_pp_per_c"),
    "dc_shift": ("dc_shift_um", "dc_shift_per_c"),
    "orbit_ellipticity_change": ("orbit_ellipticity_change", None),
    "orbit_2x_1x_change": ("orbit_2x_1x_change", None),
}
UNITS = {"1x_change_um_pp": "µm pk-pk", "2x_change_um_pp": "µm pk-pk", "dc_shift_um": "µm",
         "orbit_ellipticity_change": "1", "orbit_2x_1x_change": "1"}
#: a fitted threshold is this factor times a quantile of the change seen on unchanged re-recordings
FIT_MARGIN = 1.25
#: quantities whose threshold quantile is searched by :func:`fit_thresholds`; the others stay at margin ×
#: the largest change seen on unchanged machines. Measured (``benchmarks/bench_baseline.py``): the
#: orbit-shape changes of unchanged machines (speed within the band, runout and noise redrawn) spread as
#: wide as those of misaligned ones, and their 2X vector change has a long tail (2X near its resonance
#: moves fast with speed: 12–25 µm on two held-out plants) that 30 calibration plants do not sample.
SEARCHED = ("1x_change", "dc_shift")
#: the false-alarm rate on the calibration re-recordings that the fit may not exceed
FIT_TARGET_FALSE_ALARM = 0.03

#: quantities whose threshold an asset's own repeatability sets, when its baseline is made of
#: ≥ :data:`REPEAT_MIN` recordings (:func:`repeatability_thresholds`); the orbit-shape changes keep the shipped
#: thresholds (their spread on unchanged machines is as wide as on misaligned ones)
REPEAT_QUANTITIES = ("1x_change", "2x_change", "dc_shift")
#: recordings a baseline needs before its own repeatability is used
REPEAT_MIN = 3
#: a repeatability threshold is this factor × the largest leave-one-out change among the baseline's recordings;
#: chosen on the calibration plants of ``benchmarks/bench_baseline.py`` (the smallest factor of 2, 2.5, … 6 whose
#: false-alarm rate there is ≤ 3 %), measured on its held-out plants and the ROSS machines
REPEAT_MARGIN = 4.0
#: below these no change is alarmed whatever the repeatability (µm pk-pk for vectors, µm for the centreline):
#: about the resolution of a proximity-probe system (noise ~0.1–0.3 µm pk-pk, 16-bit digitiser); a DC-gap
#: drift with probe temperature is not simulated and would need a larger centreline floor on a real machine
REPEAT_FLOOR = {"1x_change_um_pp": 0.5, "2x_change_um_pp": 0.3, "dc_shift_um": 0.3}


@dataclass
class ChangeRule:
    """Thresholds on the change features (names as :data:`QUANTITIES`' entries).

    ``thresholds`` maps a change-feature name (``dc_shift_um``, ``dc_shift_per_c``, …) to its
    threshold; a name absent or ``None`` is not alarmed on.
    """

    thresholds: dict[str, float | None]
    source: dict[str, Any] = field(default_factory=dict)
    path: Path = THRESHOLDS_PATH

    @classmethod
    def load(cls, path: str | Path = THRESHOLDS_PATH) -> ChangeRule:
        raw = json.loads(Path(path).read_text())
        return cls({k: (None if v is None else float(v)) for k, v in raw["thresholds"].items()},
                   dict(raw.get("source") or {}), Path(path))

    def save(self, path: str | Path | None = None) -> None:
        p = Path(path) if path is not None else self.path
        p.write_text(json.dumps({"thresholds": self.thresholds, "source": self.source}, indent=2,
                                ensure_ascii=False) + "\n")

    def with_overrides(self, overrides: dict[str, float | None] | None) -> ChangeRule:
        """A copy with some thresholds replaced (an asset's edited alarm thresholds)."""
        if not overrides:
            return self
        unknown = set(overrides) - set(self.thresholds)
        if unknown:
            raise ValueError(f"unknown change quantities {sorted(unknown)}; known: {sorted(self.thresholds)}")
        return ChangeRule({**self.thresholds, **overrides}, self.source, self.path)

    def with_repeatability(self, repeatability: dict[str, Any] | None) -> ChangeRule:
        """A copy whose :data:`REPEAT_QUANTITIES` thresholds are the asset's own (``repeatability`` as returned by
        :func:`repeatability_thresholds`, or None: unchanged). Their ``_per_c`` twins are dropped — the µm
        threshold is already this machine's own scale, the twin only carried a scale across machines."""
        if not repeatability or not repeatability.get("thresholds"):
            return self
        th = dict(self.thresholds)
        for name, value in repeatability["thresholds"].items():
            if name not in th:
                raise ValueError(f"unknown change quantity {name!r} in the repeatability thresholds")
            th[name] = None if value is None else float(value)
        src = {**self.source, "repeatability": {k: v for k, v in repeatability.items() if k != "thresholds"}}
        return ChangeRule(th, src, self.path)

    def describe(self) -> str:
        return ", ".join(f"{k} > {v:.3g}" for k, v in self.thresholds.items() if v is not None)


def shipped_rule() -> ChangeRule:
    """The thresholds shipped with the package (``models/default/change_thresholds.json``)."""
    return ChangeRule.load(THRESHOLDS_PATH)


def _exceeded_matrix(values: dict[str, np.ndarray], thresholds: dict[str, float | None]) -> np.ndarray:
    """(n, quantities) booleans: the rule of :func:`assess_change` on arrays of largest-over-bearing values."""
    cols = []
    for um_name, c_name in QUANTITIES.values():
        v_um, t_um = values[um_name], thresholds.get(um_name)
        over = np.zeros(len(v_um), bool) if t_um is None else np.nan_to_num(v_um, nan=-np.inf) > t_um
        if c_name is not None and thresholds.get(c_name) is not None:
            v_c = values[c_name]
            over &= ~np.isfinite(v_c) | (np.nan_to_num(v_c, nan=-np.inf) > thresholds[c_name])
        cols.append(over)
    return np.column_stack(cols)


def fit_thresholds(unchanged: list[Any], changed: list[Any] | None = None, *,
                   target_false_alarm: float = FIT_TARGET_FALSE_ALARM, margin: float = FIT_MARGIN,
                   source: dict[str, Any] | None = None) -> ChangeRule:
    """Thresholds from (baseline, later) comparisons of simulated pairs (``features.ChangeResult`` lists).

    Each threshold is ``margin`` × a quantile ``q`` of its quantity (largest over the bearings) over the
    re-recordings of ``unchanged`` machines (a quantity in µm and its ``_per_c`` twin share ``q``). The
    quantiles of :data:`SEARCHED` are searched exhaustively over 0.80, 0.805, …, 1 for the rule (any
    quantity over its threshold) that detects most of the ``changed`` comparisons while flagging at most
    ``target_false_alarm`` of the unchanged ones (ties: fewer false alarms, then higher quantiles); the
    others stay at ``q`` = 1 (``margin`` × the largest unchanged value). Without ``changed`` every ``q`` is 1.
    """
    import itertools

    unchanged = [r for r in unchanged if r.comparable]
    changed = [r for r in (changed or []) if r.comparable]
    if not unchanged:
        raise ValueError("fit_thresholds needs at least one comparable re-recording of an unchanged machine")
    names = [n for pair in QUANTITIES.values() for n in pair if n is not None]
    u = {n: np.array([r.largest(n)[0] for r in unchanged], dtype=float) for n in names}
    c = {n: np.array([r.largest(n)[0] for r in changed], dtype=float) for n in names}
    levels = np.round(np.arange(1.0, 0.7999, -0.005), 3) if changed else np.array([1.0])

    def family_thresholds(q: str, level: float) -> dict[str, float | None]:
        th: dict[str, float | None] = {}
        for n in QUANTITIES[q]:
            if n is not None:
                v = u[n][np.isfinite(u[n])]
                th[n] = float(margin * np.quantile(v, level)) if len(v) else None
        return th

    def over(values: dict[str, np.ndarray], q: str, th: dict[str, float | None]) -> np.ndarray:
        um_name, c_name = QUANTITIES[q]
        sub = {um_name: values[um_name]}
        if c_name is not None:
            sub[c_name] = values[c_name]
        only = {k: (th.get(k) if k in sub else None) for k in names}
        return _exceeded_matrix({k: values[k] for k in names}, only)[:, list(QUANTITIES).index(q)]

    searched = [q for q in QUANTITIES if q in SEARCHED]
    fixed = [q for q in QUANTITIES if q not in SEARCHED]
    table = {q: [(lv, family_thresholds(q, lv)) for lv in levels] for q in searched}
    flags = {q: [(over(u, q, th), over(c, q, th) if changed else np.zeros(0, bool)) for _, th in table[q]]
             for q in searched}
    fixed_th = {q: family_thresholds(q, 1.0) for q in fixed}
    base_u = np.zeros(len(unchanged), bool)
    base_c = np.zeros(len(changed), bool)
    for q in fixed:
        base_u |= over(u, q, fixed_th[q])
        if changed:
            base_c |= over(c, q, fixed_th[q])
    best: tuple | None = None
    for idx in itertools.product(*(range(len(levels)) for _ in searched)):
        fu, fc = base_u.copy(), base_c.copy()
        for q, i in zip(searched, idx):
            fu |= flags[q][i][0]
            fc |= flags[q][i][1]
        fa = float(fu.mean())
        if fa > target_false_alarm and any(idx):
            continue
        det = float(fc.mean()) if changed else 0.0
        key = (det, -fa, -sum(idx))
        if best is None or key > best[0]:
            best = (key, idx, fa, det)
    assert best is not None
    _, idx, fa, det = best
    th: dict[str, float | None] = {}
    quantiles: dict[str, float] = {}
    for q in QUANTITIES:
        level = float(levels[idx[searched.index(q)]]) if q in searched else 1.0
        quantiles[q] = level
        th.update(table[q][idx[searched.index(q)]][1] if q in searched else fixed_th[q])
    src = {"fit": f"{margin} × a quantile of each quantity over {len(unchanged)} re-recordings of unchanged "
                  f"machines; quantiles searched for the most detections of {len(changed)} changed ones with "
                  f"false alarms ≤ {target_false_alarm:.0%}", "quantiles": quantiles,
           "calibration_false_alarm": fa, "calibration_detection": det, **(source or {})}
    return ChangeRule(th, src)


def repeatability_thresholds(signatures: list[dict[str, Any]], *, margin: float = REPEAT_MARGIN,
                             floors: dict[str, float] | None = None) -> dict[str, Any] | None:
    """An asset's own thresholds from the recordings its baseline is made of (its repeatability).

    Each recording is compared with the average of the others (leave-one-out,
    ``features.average_signatures`` + ``features.change_features``); per quantity of
    :data:`REPEAT_QUANTITIES` the threshold is ``margin`` × the largest such change (over recordings and
    bearings), and at least its floor (:data:`REPEAT_FLOOR`). Machines differ far more from each other than
    re-recordings of one machine do: on a machine of another design (the ROSS set of
    ``benchmarks/bench_baseline.py``) a parallel offset moves the journals by 0.1–3 µm, far below the shipped
    thresholds, and far above that machine's own repeatability.

    Parameters
    ----------
    signatures : list of dict
        ``features.signature`` of each recording of the baseline (same asset, same operating condition).
    margin : float
        Factor on the largest leave-one-out change.
    floors : dict, optional
        Smallest threshold per µm quantity (default :data:`REPEAT_FLOOR`).

    Returns
    -------
    dict or None
        None with fewer than :data:`REPEAT_MIN` recordings or when one is more than 10 % in speed from the
        average of the others (an automatic baseline's recordings lie within ±5 % of their median);
        else ``{"thresholds": {name: value}, "spread": {name: largest leave-one-out change},
        "n_recordings", "margin"}`` where ``thresholds`` holds the µm names and their ``_per_c`` twins as None
        (a quantity measured in none of the comparisons is left out: its shipped threshold stays).
    """
    from rotordiag.features import SPEED_BAND_FRAC, average_signatures, change_features

    if len(signatures) < REPEAT_MIN:
        return None
    spread: dict[str, float] = {}
    for i, sig in enumerate(signatures):
        rest = average_signatures([s for j, s in enumerate(signatures) if j != i])
        # recordings each within ±5 % of their median speed can be 10 % apart from each other
        res = change_features(rest, sig, band=2 * SPEED_BAND_FRAC)
        if not res.comparable:
            return None
        for q in REPEAT_QUANTITIES:
            name = QUANTITIES[q][0]
            v = res.largest(name)[0]
            if math.isfinite(v):
                spread[name] = max(spread.get(name, 0.0), float(v))
    return {"thresholds": thresholds_from_spread(spread, margin=margin, floors=floors), "spread": spread,
            "n_recordings": len(signatures), "margin": float(margin)}


def thresholds_from_spread(spread: dict[str, float], *, margin: float = REPEAT_MARGIN,
                           floors: dict[str, float] | None = None) -> dict[str, float | None]:
    """Repeatability thresholds from the largest leave-one-out changes (``spread``, per µm quantity):
    ``max(margin × spread, floor)``, their ``_per_c`` twins None; a quantity absent from ``spread`` (never
    measured in the baseline) is left out, so its shipped threshold stays."""
    floors = REPEAT_FLOOR if floors is None else floors
    thresholds: dict[str, float | None] = {}
    for q in REPEAT_QUANTITIES:
        um_name, c_name = QUANTITIES[q]
        if um_name not in spread:
            continue
        thresholds[um_name] = max(margin * spread[um_name], floors.get(um_name, 0.0))
        if c_name is not None:
            thresholds[c_name] = None
    return thresholds


#: why a baseline's change thresholds are what they are (``thresholds_basis(...)["reason"]``)
BASIS_REASONS = {
    "own_repeatability": "the asset's own, from the spread of its baseline recordings",
    "too_few_recordings": f"fleet-wide: the baseline has fewer than {REPEAT_MIN} recordings",
    "recordings_not_comparable": "fleet-wide: the baseline's recordings are more than 10 % apart in speed, or one "
                                 "has no speed",
    "nothing_measured": "fleet-wide: the baseline's recordings carry no 1X/2X phase (no keyphasor) and no "
                        "centreline, so their spread cannot be measured",
}


def thresholds_basis(baseline: dict[str, Any]) -> dict[str, Any]:
    """Whether a stored baseline's 1X, 2X and centreline thresholds are the asset's own or the fleet-wide ones.

    Parameters
    ----------
    baseline : dict
        The stored baseline (``service.baseline.baseline_dict``, or a baseline file): its ``repeatability``
        (:func:`repeatability_thresholds`' result or None) and ``n_recordings`` (else ``diagnosis_ids``' length).

    Returns
    -------
    dict
        ``basis`` (``"own"`` or ``"fleet"``), ``reason`` (a key of :data:`BASIS_REASONS`), ``n_recordings``,
        ``needed`` (:data:`REPEAT_MIN`) and, for ``own``, the ``margin``.
    """
    rep = baseline.get("repeatability") or None
    n = baseline.get("n_recordings") or (rep or {}).get("n_recordings") or len(baseline.get("diagnosis_ids") or ()) or 1
    out: dict[str, Any] = {"n_recordings": int(n), "needed": REPEAT_MIN}
    if rep and rep.get("thresholds"):
        return {"basis": "own", "reason": "own_repeatability", **out, "margin": float(rep.get("margin", REPEAT_MARGIN))}
    reason = ("too_few_recordings" if n < REPEAT_MIN else "recordings_not_comparable" if rep is None
              else "nothing_measured")
    return {"basis": "fleet", "reason": reason, **out}


def basis_note(basis: dict[str, Any]) -> Note:
    """The answer's typed note saying where the change thresholds come from (:func:`thresholds_basis`)."""
    if basis["basis"] == "own":
        return Note("change_thresholds_own", n_recordings=basis["n_recordings"], margin=basis["margin"])
    n = basis["n_recordings"]
    why = {"too_few_recordings": f"this asset's baseline has {n} recording{'s' if n != 1 else ''}, its own "
                                 f"repeatability needs {basis['needed']} at one operating condition",
           "recordings_not_comparable": f"this asset's {n} baseline recordings are not at one operating condition "
                                        "(more than 10 % apart in speed)",
           "nothing_measured": f"this asset's {n} baseline recordings carry no 1X/2X phase (no keyphasor) and no "
                               "centreline"}[basis["reason"]]
    return Note("change_thresholds_fleet", why=why)


def assess_change(result: Any, rule: ChangeRule) -> dict[str, Any]:
    """The change verdict of a ``features.ChangeResult`` under ``rule``.

    Returns
    -------
    dict
        ``compared`` (False when the speeds are too far apart: nothing else is judged),
        ``changed`` (bool), ``exceeded`` (quantity names over their threshold), ``quantities``
        (per quantity: largest value, its bearing, the threshold(s), exceeded).
    """
    if not result.comparable:
        return {"compared": False, "changed": False, "exceeded": [], "quantities": {}}
    out: dict[str, Any] = {}
    exceeded = []
    for q, (um_name, c_name) in QUANTITIES.items():
        v_um, b = result.largest(um_name)
        t_um = rule.thresholds.get(um_name)
        v_c = result.largest(c_name)[0] if c_name else math.nan
        t_c = rule.thresholds.get(c_name) if c_name else None
        over_um = t_um is not None and math.isfinite(v_um) and v_um > t_um
        over = over_um and (t_c is None or not math.isfinite(v_c) or v_c > t_c)
        if t_um is None and t_c is not None and math.isfinite(v_c):
            over = v_c > t_c
        out[q] = {"value": None if not math.isfinite(v_um) else v_um, "unit": UNITS[um_name], "bearing": b,
                  "threshold": t_um, "value_per_c": None if not math.isfinite(v_c) else v_c,
                  "threshold_per_c": t_c, "exceeded": bool(over)}
        if over:
            exceeded.append(q)
    return {"compared": True, "changed": bool(exceeded), "exceeded": exceeded, "quantities": out}


def _measured_change(info: dict[str, Any]) -> Measured:
    """A change item's value as a typed text: lengths carried in µm (rendered in mil at the edge)."""
    is_length = info["unit"].startswith("µm")
    pp = " pk-pk" if info["unit"] == "µm pk-pk" else ""
    values: dict[str, Any] = {"value": Length(info["value"]) if is_length else f"{info['value']:+.3g}"}
    template = "{value}" + pp
    if info["value_per_c"] is not None and is_length:
        template += " = {per_c:.3g} c"
        values["per_c"] = info["value_per_c"]
    if info["bearing"] is not None:
        template += " at bearing {bearing}"
        values["bearing"] = info["bearing"]
    thr = info["threshold"]
    if thr is not None:
        template += " (alarm above {threshold}" + pp + ")"
        values["threshold"] = Length(thr) if is_length else f"{thr:+.3g}"
    return Measured(template, **values)


#: the change quantities in words (answers, the page, the report, the headline)
CHANGE_NAMES = {"1x_change": "1X vector change", "2x_change": "2X vector change", "dc_shift": "centreline shift",
                "orbit_ellipticity_change": "orbit ellipticity change", "orbit_2x_1x_change": "orbit 2X/1X change"}

_MEANING = {
    "1x_change": "1X vector change (amplitude and phase): unbalance, bow, rub, or the 1X part of misalignment",
    "2x_change": "2X vector change: misalignment preload (the classic signature), or a crack",
    "dc_shift": "shaft-centreline (journal position) shift: a changed static load — a stationary shaft-line offset "
                "moves the coupling bearings' journals",
    "orbit_ellipticity_change": "orbit flattening (negative) or rounding: a changed radial preload",
    "orbit_2x_1x_change": "2X/1X of the orbit axes changed: misalignment preload growing (positive)",
}


def compare(signature_now: dict[str, Any], baseline: dict[str, Any] | None, rule: ChangeRule,
            *, asset_hint: str = "") -> dict[str, Any]:
    """The ``baseline`` section of an answer: whether a baseline was used, when it was set, what changed.

    Parameters
    ----------
    signature_now : dict
        ``features.signature`` of the recording diagnosed.
    baseline : dict or None
        ``{"set_at", "speed_rpm", "model_version", "source", "signature"}`` (the stored baseline), or None.
    rule : ChangeRule
        Thresholds (the asset's, when edited).
    asset_hint : str
        What to tell the user when there is no baseline (how to set one).

    Returns
    -------
    dict
        ``used`` (a comparison was made), ``set_at``, ``speed_rpm``, ``model_version``, ``source``,
        ``compared``, ``message``, ``changed`` (None when not compared), ``exceeded``, ``quantities``,
        ``values`` (every change feature), ``speed_change_frac``, ``thresholds_basis``
        (:func:`thresholds_basis`; None without a baseline), ``notes`` (typed: the last one says whether the
        thresholds are the asset's own or the fleet-wide ones) and ``evidence`` (items in the evidence section's
        form, scope ``"change since baseline"``).
    """
    from rotordiag.features import change_features

    if baseline is None:
        return {"used": False, "compared": False, "changed": None, "exceeded": [], "quantities": {}, "values": {},
                "notes": [], "evidence": [], "set_at": None, "speed_rpm": None, "model_version": None,
                "source": None, "speed_change_frac": None, "thresholds_basis": None,
                "message": "no baseline for this asset: the verdict is the present state only" + asset_hint}
    res = change_features(baseline["signature"], signature_now)
    verdict = assess_change(res, rule)
    basis = thresholds_basis(baseline)
    head = {**{k: baseline.get(k) for k in ("set_at", "speed_rpm", "model_version", "source")},
            "thresholds_basis": basis}
    d = res.to_dict()
    if not res.comparable:
        msg = (f"not compared with the baseline of {readable_time(baseline.get('set_at'))}: {res.notes[0]}; record at the "
               "baseline's operating condition, or set a baseline at this one")
        return {**head, "used": False, "compared": False, "changed": None, "exceeded": [], "quantities": {},
                "values": {}, "notes": list(res.notes), "evidence": [], "message": msg,
                "speed_change_frac": d["speed_change_frac"]}
    evidence = []
    for q, info in verdict["quantities"].items():
        if info["value"] is None:
            continue
        value = _measured_change(info)
        meaning = ("CHANGED: " if info["exceeded"] else "within the re-recording spread: ") + _MEANING[q]
        evidence.append({"scope": "change since baseline", "name": CHANGE_NAMES.get(q, q), "value": value,
                         "meaning": meaning, "number": info["value"]})
    when = readable_time(baseline.get("set_at"))
    if verdict["changed"]:
        msg = (f"changed since the baseline of {when}: " + ", ".join(CHANGE_NAMES.get(q, q) for q in verdict["exceeded"])
               + " above the alarm thresholds")
    else:
        msg = f"no change beyond the alarm thresholds since the baseline of {when}"
    notes = [*d["notes"], basis_note(basis)]
    return {**head, "used": True, "compared": True, "changed": verdict["changed"], "exceeded": verdict["exceeded"],
            "quantities": verdict["quantities"], "values": d["values"], "notes": notes, "evidence": evidence,
            "message": msg, "speed_change_frac": d["speed_change_frac"]}


def load_baseline_file(path: str | Path) -> tuple[dict[str, Any], ChangeRule]:
    """A baseline saved as JSON (``rotordiag baseline show ASSET --json``, GET /assets/{id}/baseline, or just
    its ``baseline`` object) and the thresholds it carries (the shipped ones when it has none).

    Raises
    ------
    ValueError
        The file is not such a JSON, or has no baseline set.
    """
    from rotordiag.features.safe_io import loads_json_finite

    try:
        raw = loads_json_finite(Path(path).read_bytes())
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise ValueError(f"--baseline {path}: cannot be read as JSON ({exc})") from None
    if not isinstance(raw, dict):
        raise ValueError(f"--baseline {path}: must be a JSON object")
    base = raw.get("baseline", raw) if "signature" not in raw else raw
    if not isinstance(base, dict) or not isinstance(base.get("signature"), dict):
        raise ValueError(f"--baseline {path}: no baseline in it (an asset without a baseline, or not a baseline "
                         "file); write one with `rotordiag baseline show ASSET --json`")
    rule = shipped_rule().with_repeatability(base.get("repeatability"))
    edited = raw.get("edited_thresholds")
    if isinstance(edited, dict) and edited:
        rule = rule.with_overrides(edited)
    return base, rule


def format_change(section: dict[str, Any]) -> str:
    """The ``baseline`` section of an answer as text (CLI)."""
    lines = [f"baseline: {section['message']}"]
    for item in section.get("evidence") or []:
        lines.append(f"  {item['name']}: {item['value']} — {item['meaning']}")
    for note in section.get("notes") or []:
        lines.append(f"  note: {note}")
    return "\n".join(lines)
