"""The verdict's honesty: ``status`` = confident | uncertain | inconclusive, with reasons (issue 15, item 2).

- ``inconclusive``: a physics sanity check failed (``features.check_recording``), the
  recording is far outside the training data (OOD score above ``OOD_INCONCLUSIVE``), or
  the vibration at the coupling bearings is ``SCALE_INCONCLUSIVE`` times away from the
  training data's typical level, or — on a recording outside the training family (OOD score above 1, or a
  feature outside the training range) — the classic coupling 2X/1X reading (the rule of thumb's bands) lies
  ``SIGNATURE_BANDS_ABOVE_CALL`` or more bands above the model's call (``signature_above_call``: outside its
  family the model is not trusted against the physics; a misaligned machine of another design called
  "aligned"), or the probes' bearings hold none of the model's training probe sets, or only one it tells
  misalignment poorly from on held-out plants (``bearing_set_untrained``, ``bearing_set_uninformative``:
  :mod:`models.checks.bearing_sets`). No severity is given.
- ``uncertain``: a sanity warning, OOD score above 1, a feature outside the training range
  (``outside_training``: which feature, its value and the training range, in plain words;
  inconclusive when ``SCALE_INCONCLUSIVE`` times beyond it), vibration ``SCALE_UNCERTAIN`` times
  away from the training level, an ambiguous speed estimate, features the model always had
  missing here, no class above ``CONFIDENT_MIN_PROBABILITY``, a Δ regressor whose interval
  does not reach the classifier's band, "aligned" although misalignment is more likely than
  not (below the ordinal classifier's false-alarm threshold), more than
  ``CONFIDENT_MAX_FAR_PROBABILITY`` on the bands two or more from the call, a Δ regressor's interval
  that reaches a band two or more from the call (:func:`interval_far_bands`), or a misalignment severity
  without the coupling bearings' 2X (2X/1X below ``SIGNATURE_MIN_2X_1X``: nothing physical
  backs the model's call), or "aligned" without the coupling bearings' shaft-centreline position
  per clearance (no clearance given, or no DC reading referenced to the bearing centre): a stationary
  shaft-line offset shows mainly there, so "aligned" cannot rule it out; or a misalignment call that the
  classifier lowers (to "aligned" above all) when the two coupling-end journals are put at one static position
  (``static_offset_only``: the training simulator ties those journals together, a real train does not); or every
  journal of a four-bearing recording within ``NEAR_CENTRE_MAX_ECC`` of its bearing centre
  (``journals_near_centre``: numbers too small for the clearance, a units or sensitivity slip or a clearance stated
  too large); or every journal's attitude angle more than ``FRAME_OFFSET_DEG`` off a plain short bearing's, on one
  side (``centreline_frame_turned``: probes not at the angles given, or bearings unlike plain cylindrical ones);
  or a probe set the model tells misalignment from with more than 10 % false alarms
  (``bearing_set_weak``, :mod:`models.checks.bearing_sets`); or bearings 2 and 3 recorded in separate acquisitions
  (``separate_acquisitions``, :mod:`models.checks.acquisitions`: no phase across the coupling); or a misalignment call
  on a coupling 2X that whirls backward (``reverse_2x``, :mod:`models.checks.reverse_2x`).
- ``confident``: none of these.

Class and Δ are consistent by construction (:func:`consistent_estimate`): the severity is
the calibrated classifier's; the Δ point estimate is the interval regressor's, clipped into
that class's band (the unclipped estimate is kept in the verdict as ``misalignment_model``).
"""
from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from rotordiag.core.journal import ATTITUDE_MIN_ECC, attitude_angle_deg, attitude_offset_deg
from rotordiag.core.notes import Length, Measured
from rotordiag.core.reasons import DEFAULT_VARIANT, INCONCLUSIVE, UNCERTAIN, code_info, require_code
from rotordiag.features import across_bearings, speed_in_doubt

from ._patterns import name_index
from .baselines import DEFAULT_RULE_CUTS, RuleOfThumb

__all__ = ["Reason", "RecordingChecks", "ModelCall", "assess", "consistent_estimate", "CONFIDENT", "UNCERTAIN", "INCONCLUSIVE",
           "OOD_INCONCLUSIVE", "SCALE_UNCERTAIN", "SCALE_INCONCLUSIVE", "CONFIDENT_MIN_PROBABILITY", "NEAR_CENTRE_MAX_ECC",
           "FRAME_OFFSET_DEG",
           "CONFIDENT_MAX_FAR_PROBABILITY", "DecisionPolicy", "DEFAULT_POLICY", "policy_of",
           "SIGNATURE_MIN_2X_1X", "coupling_2x_1x", "coupling_centreline_known", "journals_at_one_position",
           "journals_apart_c", "SIGNATURE_BANDS_ABOVE_CALL", "signature_band",
           "CENTRELINE_FEATURES", "describe_feature", "far_band_probability",
           "interval_far_bands", "envelope_reasons"]

CONFIDENT = "confident"

#: OOD score (distance to training data over its usual distance) beyond which no severity is given
OOD_INCONCLUSIVE = 3.0
#: every journal of a recording with the four bearings' centrelines within this many clearances of its bearing
#: centre → uncertain (``journals_near_centre``: a units or sensitivity slip that shrinks the numbers and left
#: verdicts confident and two bands off; measured in docs/models-history.md, "Numbers too small for the clearance")
NEAR_CENTRE_MAX_ECC = 0.15
#: the journals' attitude angles all this many degrees beyond (or short of) a plain short bearing's → uncertain
#: (``centreline_frame_turned``: probes declared at 0°/90° that sit at 45°/135° left verdicts confident and two bands
#: off; measured in docs/models-history.md, "Probe angles not the ones given")
FRAME_OFFSET_DEG = 30.0
#: coupling-bearing 1X orbit major axis this many times above / below the training median → uncertain …
SCALE_UNCERTAIN = 20.0
#: … and this many times → inconclusive (trees cannot extrapolate: a tree model is blind there)
SCALE_INCONCLUSIVE = 100.0
#: the predicted class needs at least this calibrated probability for a confident verdict
CONFIDENT_MIN_PROBABILITY = 0.6
#: ... and at most this calibrated probability on the bands two or more away from it (a gross error: a moderate
#: misalignment called aligned, an aligned machine called moderate)
CONFIDENT_MAX_FAR_PROBABILITY = 0.1
#: the bearings either side of the coupling whose 1X level is compared with the training data
COUPLING_BEARINGS = (2, 3)
#: a misalignment verdict needs the classic signature to be confident: the largest 2X/1X amplitude ratio of the
#: coupling bearings' probes at least this (what the confident calls below it were: docs/models.md, "How it
#: decides")
SIGNATURE_MIN_2X_1X = 0.05
#: outside its training family (OOD score above 1 or a feature outside the training range) the model's call is not
#: trusted against the classic 2X/1X reading (the rule of thumb's bands, models.baselines.DEFAULT_RULE_CUTS) when that
#: reads this many bands or more above the call: the verdict is then inconclusive (``signature_above_call``)
SIGNATURE_BANDS_ABOVE_CALL = 2


@dataclass(frozen=True)
class DecisionPolicy:
    """The thresholds that turn a model's call into a verdict's status, in one object outside the estimators.

    Stored with a model (its card's ``decision_policy``, written by ``models.train``); a card without one (the
    shipped model's, made before it existed) gets :data:`DEFAULT_POLICY`, whose values are the module constants
    above. The ordinal classifier's false-alarm thresholds stay with the classifier that was fitted with them (the
    model file); :attr:`ModelCall.alarm` carries them to the status.
    """

    ood_inconclusive: float = OOD_INCONCLUSIVE
    near_centre_max_ecc: float = NEAR_CENTRE_MAX_ECC
    frame_offset_deg: float = FRAME_OFFSET_DEG
    scale_uncertain: float = SCALE_UNCERTAIN
    scale_inconclusive: float = SCALE_INCONCLUSIVE
    confident_min_probability: float = CONFIDENT_MIN_PROBABILITY
    confident_max_far_probability: float = CONFIDENT_MAX_FAR_PROBABILITY
    signature_min_2x_1x: float = SIGNATURE_MIN_2X_1X
    signature_bands_above_call: int = SIGNATURE_BANDS_ABOVE_CALL

    def to_dict(self) -> dict[str, float]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> DecisionPolicy:
        """The policy of a card's ``decision_policy`` (None or empty: :data:`DEFAULT_POLICY`).

        Raises
        ------
        ValueError
            An unknown name, or a value that is not a finite positive number.
        """
        if not d:
            return DEFAULT_POLICY
        known = {f.name: f for f in fields(cls)}
        unknown = sorted(set(d) - set(known))
        if unknown:
            raise ValueError(f"decision_policy: unknown threshold(s) {unknown}; known: {sorted(known)}")
        values: dict[str, Any] = {}
        for k, v in d.items():
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (np.isfinite(v) and v > 0):
                raise ValueError(f"decision_policy.{k}: must be a finite positive number, got {v!r}")
            values[k] = int(v) if k == "signature_bands_above_call" else float(v)
        return cls(**values)


#: the policy of every model whose card has none
DEFAULT_POLICY = DecisionPolicy()


def policy_of(card: Mapping[str, Any] | None) -> DecisionPolicy:
    """The decision policy stored with a model (its card's ``decision_policy``), else :data:`DEFAULT_POLICY`."""
    return DecisionPolicy.from_dict((card or {}).get("decision_policy"))


@dataclass(frozen=True)
class Reason:
    """Why a verdict is not confident: a catalogue code with its typed values, its message rendered from the
    catalogue's template.

    Attributes
    ----------
    code : str
        Stable identifier, one of the catalogue's (:mod:`rotordiag.core.reasons`; any other is refused, as is a
        status the catalogue does not allow the code).
    status : str
        ``uncertain`` or ``inconclusive``: what this reason alone makes of the verdict.
    values : mapping
        The template's fields, exactly (a length as :class:`~rotordiag.core.notes.Length`); others are refused.
    variant : str
        Which of the code's templates (``"default"`` unless the code has named cases).
    """

    code: str
    status: str
    values: Mapping[str, Any] = field(default_factory=dict, hash=False)
    variant: str = DEFAULT_VARIANT

    def __post_init__(self) -> None:
        require_code(self.code, self.status)
        object.__setattr__(self, "_message", code_info(self.code).message(self.variant, self.values))

    @property
    def message(self) -> Measured:
        """What was found, in words (µm; ``.render("mil")`` for mils)."""
        return self._message  # type: ignore[attr-defined]

    def to_dict(self) -> dict:
        """The reason as the answer carries it, with the catalogue's ``action`` (what to do, for every recording
        with this code)."""
        return {"code": self.code, "status": self.status, "message": self.message, "action": code_info(self.code).action}


def consistent_estimate(band_index: int, edges: Sequence[float], point: float,
                        interval: tuple[float, float]) -> tuple[float, tuple[float, float], bool]:
    """Δ point and interval consistent with the class ``band_index``.

    Returns
    -------
    point, interval, agrees
        The point clipped into the band ``[edges[i-1], edges[i])`` (the upper edge exclusive,
        as ``SeverityBands.index``), the interval widened to contain it, and whether the
        regressor's own interval reached the band at all.
    """
    lo_edge = float(edges[band_index - 1]) if band_index > 0 else 0.0
    hi_edge = float(edges[band_index]) if band_index < len(edges) else np.inf
    top = float(np.nextafter(hi_edge, -np.inf)) if np.isfinite(hi_edge) else np.inf
    p = float(min(max(point, lo_edge), top))
    lo, hi = float(interval[0]), float(interval[1])
    agrees = not (hi < lo_edge or lo >= hi_edge)
    return p, (min(lo, p), max(hi, p)), agrees


def _near_centre_reasons(names: Sequence[str], row: np.ndarray, policy: DecisionPolicy = DEFAULT_POLICY
                          ) -> list[Reason]:
    """``journals_near_centre`` when all four bearings' centrelines are read and every journal sits within
    :data:`NEAR_CENTRE_MAX_ECC` of its bearing centre."""
    index = name_index(names)
    cols = [index.get(f"b{b}_centre_ecc_per_c") for b in (1, 2, 3, 4)]
    if any(j is None for j in cols):
        return []
    ecc = np.array([row[j] for j in cols if j is not None], dtype=float)       # all four found (above)
    if not np.isfinite(ecc).all() or ecc.max() >= policy.near_centre_max_ecc:
        return []
    e1, e2, e3, e4 = (float(e) for e in ecc)
    return [Reason("journals_near_centre", UNCERTAIN, {"max_ecc_c": float(ecc.max()), "ecc1_c": e1, "ecc2_c": e2,
                                                       "ecc3_c": e3, "ecc4_c": e4,
                                                       "limit_c": policy.near_centre_max_ecc})]


def _probe_frame_reasons(names: Sequence[str], row: np.ndarray, policy: DecisionPolicy = DEFAULT_POLICY,
                         reference_deg: np.ndarray | None = None) -> list[Reason]:
    """``centreline_frame_turned`` when at two or more bearings the journal sits off the load line (attitude angle)
    by more than :data:`FRAME_OFFSET_DEG` beyond where the model's training journals sat, every one on the same
    side: the probes' frame as given is turned (wrong ``angle_deg``), or the bearings are unlike the training's
    (the ROSS set's linear bearings, tilting pads: the journal near the load line).

    ``reference_deg`` (``MisalignmentModel.attitude_reference_deg``, bearing n at n − 1): the median offset from a
    plain short journal bearing's attitude of the training recordings nearest this one (of all training, for a
    model saved before the per-row reference); where it is missing (a model saved before either, a bearing never
    instrumented in training) the reference is the plain bearing's (0°). A model trained on trains whose bearings
    hold their journals elsewhere than a plain bearing's (a four-pole train's +35°, linear or tilting-pad bearings
    on the load line) thus takes those trains' journals as its own, and still sees a turned frame."""
    index = name_index(names)
    bearings, xye = [], []
    for b in range(1, 10):
        cols = [index.get(f"b{b}_centre_{k}_per_c") for k in ("x", "y", "ecc")]
        if all(j is not None for j in cols):
            v = np.array([row[j] for j in cols if j is not None], dtype=float)
            if np.isfinite(v).all() and v[2] >= ATTITUDE_MIN_ECC:
                bearings.append(b)
                xye.append(v)
    if len(bearings) < 2:
        return []
    x, y, e = np.array(xye).T
    phis = attitude_angle_deg(x, y)
    ref = np.zeros(len(bearings))
    if reference_deg is not None:
        trained = np.asarray(reference_deg, dtype=float)
        ref = np.array([trained[b - 1] if b <= trained.size and np.isfinite(trained[b - 1]) else 0.0
                        for b in bearings])
    offsets = (attitude_offset_deg(x, y, e) - ref + 180.0) % 360.0 - 180.0
    found = list(zip(bearings, phis.tolist(), offsets.tolist()))
    if not (np.all(offsets < -policy.frame_offset_deg) or np.all(offsets > policy.frame_offset_deg)):
        return []
    where = ", ".join(f"bearing {b} {phi:.0f}° ({off:+.0f}°)" for b, phi, off in found)
    held = ("a plain oil-film journal bearing's" if not np.any(ref) else
            "that of the training machines nearest this recording (" + ", ".join(f"bearing {b} {r:+.0f}° from a plain bearing's"
                                                          for b, r in zip(bearings, ref.tolist())) + ")")
    return [Reason("centreline_frame_turned", UNCERTAIN,
                   {"mean_offset_deg": float(np.mean(offsets)), "bearings": where, "reference": held})]


def _scale_reasons(names: Sequence[str], row: np.ndarray, median: np.ndarray,
                   policy: DecisionPolicy = DEFAULT_POLICY) -> list[Reason]:
    index = name_index(names)
    ratios = []
    for b in COUPLING_BEARINGS:
        j = index.get(f"b{b}_1x_major_um_pp")
        if j is None or not (np.isfinite(row[j]) and np.isfinite(median[j]) and median[j] > 0):
            continue
        ratios.append((b, float(row[j]), float(median[j])))
    if not ratios:
        return []
    b, v, m = max(ratios, key=lambda t: abs(np.log(max(t[1], 1e-300) / t[2])))
    if v <= 0:                       # no 1X vibration at all (all-zero or flat probes): as far below as can be
        return [Reason("scale", INCONCLUSIVE, {"bearing": b, "amp": Length(0.0), "typical": Length(m)},
                       variant="none")]
    factor = m / v if v < m else v / m
    if factor < policy.scale_uncertain:
        return []
    status = INCONCLUSIVE if factor >= policy.scale_inconclusive else UNCERTAIN
    side = "below" if v < m else "above"
    return [Reason("scale", status, {"bearing": b, "amp": Length(v), "factor": factor, "typical": Length(m)},
                   variant=side)]


_ORDER_AMP = re.compile(r"b(\d+)_(\d)x_major_(um_pp|pp_per_c)")
_BEARING_FEATURE = re.compile(r"b(\d+)_(.+)")
#: plain words and unit of the envelope's per-bearing features (``b{n}_`` + key)
_PLAIN = {
    "2x_1x_major_ratio": ("2X/1X amplitude ratio (orbit major axes)", ""),
    "3x_1x_major_ratio": ("3X/1X amplitude ratio (orbit major axes)", ""),
    "centre_ecc_per_c": ("shaft centreline eccentricity", "× clearance"),
    "orbit12_pp_per_c": ("orbit size (1X + 2X, peak-to-peak)", "× clearance"),
    "poincare_rms_per_c": ("cycle-to-cycle scatter of the once-per-turn orbit points (rms)", "× clearance"),
    "nonsync_frac": ("share of the vibration not at running-speed orders", ""),
    "subsync_frac": ("share of sub-synchronous vibration (below 1X)", ""),
    "1x_ellipticity": ("1X orbit ellipticity (minor/major axis)", ""),
    "1x_whirl_index": ("1X whirl index (+1 forward, −1 reverse)", ""),
    "attitude_deg": ("shaft centreline attitude angle (from the load line, with rotation)", "°"),
    "attitude_offset_deg": ("shaft centreline attitude angle relative to a plain oil-film journal bearing's at "
                            "the same eccentricity (short-bearing theory)", "°"),
}


def describe_feature(name: str) -> tuple[str, str]:
    """Plain words and unit of a feature name (the name itself and "" when not known)."""
    if name == "speed_rpm":
        return "running speed", "r/min"
    m = _ORDER_AMP.fullmatch(name)
    if m:
        b, k, kind = m.groups()
        return f"{k}X vibration (orbit major axis) at bearing {b}", "µm pk-pk" if kind == "um_pp" else "× clearance pk-pk"
    m = _BEARING_FEATURE.fullmatch(name)
    if m and m.group(2) in _PLAIN:
        words, unit = _PLAIN[m.group(2)]
        return f"{words} at bearing {m.group(1)}", unit
    return name, ""


def _num(v: float, unit: str = "") -> tuple[str | Length, ...]:
    """A value with its unit as pieces of a :meth:`Measured.of` text (a length in µm kept typed)."""
    if unit.startswith("µm"):
        return (Length(v), unit[2:])
    text = f"{round(v) + 0:+d}" if unit == "°" else f"{v:.3g}"
    return (f"{text}{unit}" if unit == "°" else (f"{text} {unit}" if unit else text),)


def envelope_reasons(findings: Sequence[dict], *, max_reasons: int = 3,
                     policy: DecisionPolicy | None = None) -> list[Reason]:
    """``outside_training`` reasons from ``MisalignmentModel.envelope_findings`` (largest excess first).

    Uncertain; inconclusive when a value is :data:`SCALE_INCONCLUSIVE` (``policy.scale_inconclusive``) times beyond
    the training range (a tree model is blind there).
    """
    policy = DEFAULT_POLICY if policy is None else policy
    out = []
    for k, f in enumerate(list(findings)[:max_reasons]):
        words, unit = describe_feature(str(f["feature"]))
        side, factor = f["side"], f.get("factor")
        bound = f["train_min"] if side == "below" else f["train_max"]
        how = f"{factor:.0f}× " if factor is not None and factor >= 2 else ""
        name = str(f["feature"])
        value: str | Length
        low: str | Length
        high: str | Length
        shown: str | Length
        if unit.startswith("µm"):                   # a length: typed, its unit's tail (" pk-pk") after each number
            value, low, high, shown = Length(f["value"]), Length(f["train_min"]), Length(f["train_max"]), Length(bound)
            tail = unit[2:]
        else:
            (value,), (shown,), (high,) = _num(f["value"], unit), _num(bound, unit), _num(f["train_max"], unit)
            (low,) = _num(f["train_min"], "°" if unit == "°" else "")
            tail = ""
        if "_attitude_" in name:
            variant = "attitude"
        elif "um_pp" in name and side == "above":
            variant = "amplitude_above"
        elif "per_c" in name:
            variant = "per_clearance"
        else:
            variant = DEFAULT_VARIANT
        more = (f" (and {len(findings) - max_reasons} more feature(s) outside the training range)"
                if k == max_reasons - 1 and len(findings) > max_reasons else "")
        status = INCONCLUSIVE if factor is not None and factor >= policy.scale_inconclusive else UNCERTAIN
        out.append(Reason("outside_training", status,
                          {"feature": words, "value": value, "unit": tail, "how": how, "side": side,
                           "bound_name": "min" if side == "below" else "max", "bound": shown, "train_min": low,
                           "train_max": high, "more": more}, variant=variant))
    return out


def coupling_2x_1x(names: Sequence[str], row: np.ndarray) -> float:
    """The largest 2X/1X amplitude ratio of the coupling bearings' probes (NaN when none is measured)."""
    index = name_index(names)
    cols = [index[n] for b in COUPLING_BEARINGS for n in (f"b{b}_x_2x_1x_ratio", f"b{b}_y_2x_1x_ratio") if n in index]
    vals = [v for v in (float(row[j]) for j in cols) if np.isfinite(v)]
    return max(vals) if vals else float("nan")


def signature_band(ratio: float, n_bands: int) -> int | None:
    """The band the classic 2X/1X rule of thumb reads from the coupling bearings' largest 2X/1X (``ratio``): the
    number of :data:`models.baselines.DEFAULT_RULE_CUTS` (0.5 / 1 / 2) at or below it. None when the ratio is not
    measured or the model's bands are not the rule's four."""
    if not np.isfinite(ratio) or n_bands != len(DEFAULT_RULE_CUTS) + 1:
        return None
    return int(RuleOfThumb([str(k) for k in range(n_bands)]).predict(np.array([ratio]))[0])


def coupling_centreline_known(names: Sequence[str], row: np.ndarray) -> bool:
    """Whether the shaft-centreline eccentricity per clearance is measured at a coupling bearing.

    It needs the bearing clearance and DC probe readings referenced to the bearing centre
    (``b{n}_centre_ecc_per_c`` is NaN without the clearance, or when the mean is a raw gap,
    > 1.5 c from the probes' zero); a model without the feature never knows it."""
    wanted = {f"b{b}_centre_ecc_per_c" for b in COUPLING_BEARINGS}
    return any(n in wanted and np.isfinite(row[i]) for i, n in enumerate(names))


#: the static-position features of a bearing that :func:`journals_at_one_position` copies across the coupling
CENTRELINE_FEATURES = ("centre_x_per_c", "centre_y_per_c", "centre_ecc_per_c")


def journals_apart_c(names: Sequence[str], row: np.ndarray) -> tuple[float, float] | None:
    """Bearing 3's static journal position minus bearing 2's (x, y), in clearances; None when either is not
    measured."""
    index = name_index(names)
    cols = [index.get(f"b{b}_centre_{d}_per_c") for b in COUPLING_BEARINGS[::-1] for d in "xy"]
    if any(j is None or not np.isfinite(row[j]) for j in cols):
        return None
    x3, y3, x2, y2 = (float(row[j]) for j in cols if j is not None)
    return x3 - x2, y3 - y2


def journals_at_one_position(names: Sequence[str], row: np.ndarray) -> np.ndarray | None:
    """The recording with the coupling-end journals at one static position: two rows, bearing 3's centreline
    features replaced by bearing 2's, and bearing 2's by bearing 3's (everything else unchanged).

    The simulator that trained the model ties the two coupling-end journals together (MODEL.md: r3 = r4 on an
    aligned train), so to the model any static offset between them is a shaft-line offset; on a real train each
    journal sits by its own load, and a DC gap referenced to the wrong zero reads the same. The model's call on
    these rows says whether the call rests on that offset (docs/robustness.md, transfer check); the columns across
    bearings (``dcentre_*_b2_b3_per_c`` …) are built again from the moved journals, or they would keep the offset.
    None when either coupling bearing's centreline is not measured (no clearance, raw gaps, bearing absent)."""
    index = name_index(names)
    found = {b: [index.get(f"b{b}_{q}") for q in CENTRELINE_FEATURES] for b in COUPLING_BEARINGS}
    if any(j is None or not np.isfinite(row[j]) for js in found.values() for j in js):
        return None
    cols = {b: np.array(js, dtype=np.intp) for b, js in found.items()}
    (b2, b3) = COUPLING_BEARINGS
    out = np.repeat(np.asarray(row, dtype=float)[None, :], 2, axis=0)
    out[0, cols[b3]] = row[cols[b2]]
    out[1, cols[b2]] = row[cols[b3]]
    across_bearings(out, names)     # the columns across bearings read the journals as moved (features._across)
    return out


def _far_bands(n_bands: int, call_index) -> np.ndarray:
    """Mask, shape (..., n_bands), of the bands two or more from the called one (``call_index``, shape (...))."""
    return np.abs(np.arange(n_bands) - np.asarray(call_index)[..., None]) >= 2


def far_band_probability(probabilities: Sequence[float] | np.ndarray, call_index: int | np.ndarray) -> np.ndarray:
    """Probability on the bands two or more from the called one.

    ``probabilities``: shape (..., n_bands), columns in band order; ``call_index``: the called band, shape (...).
    Returns an array of shape (...) (a 0-d array for one verdict)."""
    p = np.asarray(probabilities, dtype=float)
    return np.sum(np.where(_far_bands(p.shape[-1], call_index), p, 0.0), axis=-1)


def interval_far_bands(interval: Sequence[float] | np.ndarray, call_index: int | np.ndarray,
                       edges: Sequence[float]) -> np.ndarray:
    """Whether a Δ interval reaches a band two or more from the called one.

    ``interval``: shape (..., 2), (low, high) Δ; ``call_index``: the called band, shape (...); ``edges``: the
    bands' inner edges (``SeverityBands.edges``; a band's upper edge is exclusive, as ``SeverityBands.index``).
    Returns a bool array of shape (...) (0-d for one verdict)."""
    return np.any(_interval_far_mask(interval, call_index, edges), axis=-1)


def _interval_far_mask(interval: Sequence[float] | np.ndarray, call_index: int | np.ndarray,
                       edges: Sequence[float]) -> np.ndarray:
    """Mask, shape (..., n_bands), of the bands the interval reaches that are two or more from the call."""
    iv = np.asarray(interval, dtype=float)
    e = np.asarray(edges, dtype=float)
    bands = np.arange(e.size + 1)
    lo_band = np.searchsorted(e, iv[..., 0], side="right")[..., None]
    hi_band = np.searchsorted(e, iv[..., 1], side="right")[..., None]
    return (bands >= lo_band) & (bands <= hi_band) & _far_bands(e.size + 1, call_index)


@dataclass(frozen=True)
class RecordingChecks:
    """What a recording says before the models' call: its physics checks and how it sits against training.

    Attributes
    ----------
    names, row, feature_median
        The model's feature names, this recording's vector and the training medians.
    sanity : iterable of features.SanityFinding
    ood_score : float
        Distance to the training data over its usual distance (NaN: not scored).
    never_missing : sequence of str
        Features missing here that training always had.
    speed_source : str or None
        ``"keyphasor"``, ``"given"`` or ``"estimated"``.
    warnings : iterable of str
        The feature extractor's warnings (an ambiguous speed estimate is one).
    envelope : sequence of dict
        ``MisalignmentModel.envelope_findings`` of this row: features outside the training range.
    extra : sequence of Reason
        Reasons found outside this module: ``models.checks.bearing_sets`` (a probe set the model was not trained on, or
        one it tells little from) and ``models.checks.numbering`` (bearings numbered from the other end).
    attitude_reference_deg : ndarray or None
        The model's ``attitude_offset_reference_deg_`` (None: a model saved before it; a plain bearing's).
    """

    names: Sequence[str]
    row: np.ndarray
    feature_median: np.ndarray
    sanity: Iterable
    ood_score: float
    never_missing: Sequence[str]
    speed_source: str | None
    warnings: Iterable[str]
    envelope: Sequence[dict] = ()
    extra: Sequence[Reason] = ()
    attitude_reference_deg: np.ndarray | None = None


@dataclass(frozen=True)
class ModelCall:
    """The two models' call on a recording: the classifier's band and the Δ regressor's interval.

    Attributes
    ----------
    probabilities : sequence of float
        Calibrated class probabilities.
    class_delta_agree : bool
        From :func:`consistent_estimate`.
    call_index : int, optional
        The called band's index into ``probabilities`` (ordered bands): a confident verdict needs at most
        :data:`CONFIDENT_MAX_FAR_PROBABILITY` on the bands two or more away from it.
    band_names : sequence of str
        The bands' names, for the reasons' messages.
    misaligned_call : bool
        The class is a misalignment severity (not the aligned band): it then needs the coupling
        bearings' 2X (:data:`SIGNATURE_MIN_2X_1X`) to be confident; an aligned call needs their
        shaft-centreline position per clearance (:func:`coupling_centreline_known`).
    alarm : (probability, threshold), optional
        For a verdict of "aligned" from an ordinal classifier: P(misaligned, any band) and the
        threshold it must reach to be reported (false-alarm control). Between 0.5 and the
        threshold the verdict is uncertain, and says so.
    delta_interval : (float, float), optional
        The Δ regressor's own interval (before it is widened to the class's band). With ``call_index`` and
        ``band_edges``: a confident verdict needs it within one band of the call (:func:`interval_far_bands`):
        the regressor is the second model of the verdict, and an interval that reaches two bands away does
        not rule out the gross error the far-band probability limit guards against.
    band_edges : sequence of float
        The bands' inner edges.
    interval_level : float
        The interval's coverage, for that reason's message.
    static_offset : sequence of Reason
        ``static_offset_only`` of a misalignment call that falls to a lower band with the coupling-end journals at
        one static position (``models.checks.one_position``), listed after the call's 2X reason.
    """

    probabilities: Sequence[float] | np.ndarray
    class_delta_agree: bool
    call_index: int | None = None
    band_names: Sequence[str] = ()
    misaligned_call: bool = False
    alarm: tuple[float, float] | None = None
    delta_interval: tuple[float, float] | None = None
    band_edges: Sequence[float] = ()
    interval_level: float = 0.9
    static_offset: Sequence[Reason] = ()


def assess(checks: RecordingChecks, call: ModelCall, policy: DecisionPolicy | None = None
           ) -> tuple[str, list[Reason]]:
    """The verdict's status and its reasons (worst first): the recording's (:func:`_recording_reasons`), then
    the call's (:func:`_call_reasons`); ``inconclusive`` when any reason is, ``uncertain`` when there is one,
    else ``confident``."""
    policy = DEFAULT_POLICY if policy is None else policy
    reasons = _recording_reasons(checks, policy) + _call_reasons(call, checks, policy)
    if any(r.status == INCONCLUSIVE for r in reasons):
        status = INCONCLUSIVE
    elif reasons:
        status = UNCERTAIN
    else:
        status = CONFIDENT
    reasons.sort(key=lambda r: r.status != INCONCLUSIVE)
    return status, reasons


def _recording_reasons(c: RecordingChecks, policy: DecisionPolicy = DEFAULT_POLICY) -> list[Reason]:
    """The probe set's reasons (``extra``), sanity findings, OOD score, features outside the training range,
    vibration scale, every journal near its bearing centre, an ambiguous speed estimate, features the model
    always had."""
    reasons: list[Reason] = list(c.extra)
    for f in c.sanity:
        reasons.append(Reason(f.code, INCONCLUSIVE if f.level == "fail" else UNCERTAIN, f.values, f.variant))
    if np.isfinite(c.ood_score) and c.ood_score > 1.0:
        status = INCONCLUSIVE if c.ood_score > policy.ood_inconclusive else UNCERTAIN
        reasons.append(Reason("ood", status, {"ood_score": c.ood_score, "ood_inconclusive": policy.ood_inconclusive}))
    reasons += envelope_reasons(c.envelope, policy=policy)
    reasons += _scale_reasons(c.names, c.row, c.feature_median, policy)
    reasons += _near_centre_reasons(c.names, c.row, policy)
    reasons += _probe_frame_reasons(c.names, c.row, policy, c.attitude_reference_deg)
    if c.speed_source == "estimated":
        for w in c.warnings:
            if speed_in_doubt(w):
                reasons.append(Reason("speed_ambiguous", UNCERTAIN, {"warning": w}))
    if c.never_missing:
        reasons.append(Reason("features_missing", UNCERTAIN,
                              {"n_missing": len(c.never_missing), "examples": ", ".join(list(c.never_missing)[:3])},
                              "motion" if any(n.startswith("motion_") for n in c.never_missing) else DEFAULT_VARIANT))
    return reasons


def _call_reasons(m: ModelCall, c: RecordingChecks, policy: DecisionPolicy = DEFAULT_POLICY) -> list[Reason]:
    """Low probability, probability or Δ interval on bands two or more from the call, below the alarm
    threshold, a severity without the coupling 2X or "aligned" without the coupling centreline (these two
    read the recording's features), a severity resting on the static offset between the coupling journals
    (``static_offset``, from ``models.checks.one_position``), class and Δ disagreeing."""
    reasons: list[Reason] = []
    probabilities, call_index, band_names = m.probabilities, m.call_index, m.band_names
    pmax = float(np.max(probabilities)) if len(probabilities) else np.nan
    if not pmax >= policy.confident_min_probability:
        reasons.append(Reason("low_probability", UNCERTAIN,
                              {"p_max": pmax, "min_probability": policy.confident_min_probability}))
    if call_index is not None and len(probabilities):
        far = np.flatnonzero(_far_bands(len(probabilities), call_index))
        p_far = float(far_band_probability(probabilities, call_index))
        if p_far > policy.confident_max_far_probability:
            which = " or ".join(str(band_names[int(k)]) for k in far) if len(band_names) == len(probabilities) else \
                "bands two or more away"
            reasons.append(Reason("far_band_probability", UNCERTAIN,
                                  {"p_far": p_far, "bands": which,
                                   "max_far_probability": policy.confident_max_far_probability}))
    reached: list[int] = []
    if call_index is not None and m.delta_interval is not None and len(m.band_edges):
        lo, hi = float(m.delta_interval[0]), float(m.delta_interval[1])
        reached = [int(k) for k in np.flatnonzero(_interval_far_mask((lo, hi), call_index, m.band_edges))]
    if reached:
        which = " or ".join(str(band_names[k]) if len(band_names) > k else f"band {k}" for k in reached)
        reasons.append(Reason("far_band_interval", UNCERTAIN,
                              {"level": m.interval_level, "low": lo, "high": hi, "bands": which}))
    if m.alarm is not None and m.alarm[0] >= 0.5:
        reasons.append(Reason("below_alarm_threshold", UNCERTAIN,
                              {"p_misaligned": m.alarm[0], "threshold": m.alarm[1]}))
    ratio = coupling_2x_1x(c.names, c.row)
    outside = (np.isfinite(c.ood_score) and c.ood_score > 1.0) or bool(c.envelope)
    rule = signature_band(ratio, len(probabilities))
    if outside and call_index is not None and rule is not None and rule - call_index >= policy.signature_bands_above_call:
        called = str(band_names[call_index]) if len(band_names) > call_index else f"band {call_index}"
        read = str(band_names[rule]) if len(band_names) > rule else f"band {rule}"
        reasons.append(Reason("signature_above_call", INCONCLUSIVE,
                              {"called": called, "ratio_2x_1x": ratio, "read": read,
                               "rule_cut": DEFAULT_RULE_CUTS[rule - 1]}))
    if m.misaligned_call:
        if not ratio >= policy.signature_min_2x_1x:
            if np.isfinite(ratio):
                reasons.append(Reason("no_2x_signature", UNCERTAIN,
                                      {"ratio_2x_1x": ratio, "min_2x_1x": policy.signature_min_2x_1x}))
            else:
                reasons.append(Reason("no_2x_signature", UNCERTAIN, {"min_2x_1x": policy.signature_min_2x_1x},
                                      "not_measured"))
        reasons += list(m.static_offset)          # models.checks.one_position: listed here, after the 2X
    elif not coupling_centreline_known(c.names, c.row):
        reasons.append(Reason("offset_not_assessed", UNCERTAIN))
    if not m.class_delta_agree:
        reasons.append(Reason("class_delta_disagree", UNCERTAIN))
    return reasons
