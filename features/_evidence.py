"""Model-independent evidence for a verdict (issue 15, item 2): the measured signatures an
engineer reads, each with a one-line meaning.

Per coupling bearing (2 and 3, else whatever is present): 1X and 2X vectors of each probe
direction (µm pk-pk and phase lag), 2X/1X, orbit shape and the shaft-centreline position;
across the coupling: the 1X and 2X phase differences; between neighbouring journals: how the load is shared
(the centreline's positions compared, ``features._across``); first, when runout was compensated, the
slow-roll vectors subtracted at each bearing, and a 1X / 2X largely common to every probe (mains pickup).
Nothing here uses the ML model.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotordiag.core.notes import Length, Measured

from ._acquisitions import split_pairs
from ._common_mode import COMMON_MODE_NOTABLE_SHARE, common_mode
from ._config import ACROSS_PAIRS, CENTRELINE_MAX_ECC, PHASE_PAIRS
from ._sanity import common_mode_dominates

__all__ = ["EvidenceItem", "evidence"]

COUPLING = PHASE_PAIRS[0]                     # (2, 3): the bearings either side of the coupling


@dataclass(frozen=True)
class EvidenceItem:
    """One measured signature.

    Attributes
    ----------
    scope : str
        ``"bearing 2"``, ``"coupling 2–3"``.
    name : str
        What is measured (e.g. ``"1X x"``, ``"2X/1X"``).
    value : str
        The measurement, with units (``"42.1 µm pk-pk ∠ 137°"``; ``"not measurable: …"``).
    meaning : str
        What it usually means.
    number : float or None
        The main number (µm pk-pk, ratio, degrees, eccentricity ratio), for machines.
    """

    scope: str
    name: str
    value: str
    meaning: str
    number: float | None = None

    def to_dict(self) -> dict:
        return {"scope": self.scope, "name": self.name, "value": self.value, "meaning": self.meaning,
                "number": self.number}


def _num(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def _whole_degrees(angle_deg: float) -> float:
    """``angle_deg`` in [0, 360) such that printing it to whole degrees never shows 360° (−0.0009° is 0°)."""
    d = float(angle_deg) % 360.0
    return 0.0 if d >= 359.5 else d


def _vector(det, direction: str, order: int) -> tuple[str, float]:
    c = (det.x_coeffs_um if direction == "x" else det.y_coeffs_um)[order - 1]
    amp = 2.0 * abs(c)
    ph = det.phase_deg(direction, order)
    if not np.isfinite(ph):
        return Measured("{amp} pk-pk, phase not measurable (in the noise)", amp=Length(amp)), amp
    return Measured("{amp} pk-pk ∠ {phase_deg:.0f}°", amp=Length(amp), phase_deg=_whole_degrees(ph)), amp


def _ratio_meaning(r: float) -> str:
    if not np.isfinite(r):
        return "not measurable (no 1X)"
    if r >= 1.0:
        return "2X above 1X: strong misalignment signature (or a cracked shaft / loose part)"
    if r >= 0.5:
        return "2X over half of 1X: the usual rule-of-thumb threshold for misalignment"
    if r >= 0.25:
        return "noticeable 2X: mild misalignment or a preload, worth trending"
    return "1X-dominated: no misalignment signature in 2X (unbalance or normal running)"


def _shape_meaning(det) -> tuple[str, str]:
    f = det.features
    b = det.bearing
    ell = f.get(f"b{b}_orbit12_ellipticity", np.nan)
    conc = f.get(f"b{b}_orbit12_concavity", np.nan)
    turn = f.get(f"b{b}_orbit12_turning_number", np.nan)
    wi = f.get(f"b{b}_1x_whirl_index", np.nan)
    if not np.isfinite(ell):
        return "not determined", "no 1X/2X orbit to shape"
    direction = "forward" if np.isfinite(wi) and wi >= 0 else "reverse"
    if np.isfinite(turn) and abs(turn) != 1:
        return (f"loops (turning number {turn:.0f}, {direction})",
                "inner loop or figure-8: 2X strong relative to 1X — typical of severe misalignment (preload)")
    if np.isfinite(conc) and conc > 0.05:
        return (f"banana/kidney (concavity {conc:.2f}, {direction})",
                "a flattened, dented orbit: a radial preload such as misalignment is bending it")
    if ell < 0.3:
        return (f"flat ellipse (minor/major {ell:.2f}, {direction})",
                "a line-like orbit: strongly anisotropic support, or a preload pressing the journal")
    return (f"ellipse (minor/major {ell:.2f}, {direction})",
            "a plain 1X ellipse: unbalance-type response; no preload visible in the shape")


def _centreline(det) -> EvidenceItem:
    scope = f"bearing {det.bearing}"
    mx, my = det.mean_um
    r = float(np.hypot(mx, my))
    c = det.clearance_um
    if det.dc_removed:
        return EvidenceItem(scope, "shaft centreline", "not measured: the channels carry no DC position",
                            "AC-coupled acquisition or the means removed: a stationary shaft-line offset shows mainly "
                            "in the centreline and is not assessed; give DC readings referenced to the bearing "
                            "centre (or V with the gap voltage)", None)
    if not (np.isfinite(c) and c > 0):
        return EvidenceItem(scope, "shaft centreline", Measured("mean x {x}, y {y} (clearance unknown)", x=Length(mx, ".4g"), y=Length(my, ".4g")),
                            "a position relative to the bearing centre only if the gaps are referenced to it; "
                            "give clearance_um for the eccentricity ratio", None)
    ecc = r / c
    if ecc > CENTRELINE_MAX_ECC:
        return EvidenceItem(scope, "shaft centreline", Measured("mean {r} from zero = {ecc:.1f} c: a raw gap", r=Length(r, ".4g"), ecc=ecc),
                            "not a position inside the bearing: the DC part is the probes' gap; reference the "
                            "gaps to the bearing centre (cold gap) to read the centreline", None)
    # attitude angle: from the load line (gravity, −y) to the line of centres, in the rotation direction (+θ)
    attitude = _whole_degrees(np.degrees(np.arctan2(my, mx) - np.arctan2(-1.0, 0.0)))
    if ecc < 0.3:
        meaning = "journal lightly loaded (near the centre): an unloaded bearing, often the result of misalignment " \
                  "shifting the load to the neighbouring bearing"
    elif ecc > 0.8:
        meaning = "journal pushed to the bearing wall: heavily loaded — misalignment preload or a high static load"
    else:
        meaning = "normally loaded journal position"
    return EvidenceItem(scope, "shaft centreline",
                        f"eccentricity {ecc:.2f} c, attitude angle {attitude:.0f}° (from the load line, with rotation)",
                        meaning, ecc)


def _slow_roll_item(det) -> EvidenceItem | None:
    """What slow-roll (runout) compensation subtracted at this bearing, or None when none was asked for."""
    if det.slow_roll_um_pp is None:
        return None
    parts: list[str] = []
    lengths: dict[str, Length] = {}
    for angle, vec in zip(det.probe_angles_deg, det.slow_roll_um_pp):
        vec = vec or {}
        got = []
        for k in (1, 2):
            if k in vec:
                field_name = f"amp{len(lengths)}"
                lengths[field_name] = Length(vec[k][0])
                got.append(f"{k}X {{{field_name}}} pk-pk ∠ {vec[k][1]:.0f}°")
        left = [f"{k}X" for k in (1, 2) if k not in vec]
        parts.append(f"{angle:g}° probe: " + (", ".join(got) + " subtracted" if got else "nothing subtracted")
                     + (f" ({'/'.join(left)} not given or in the noise at slow roll)" if left else ""))
    return EvidenceItem(f"bearing {det.bearing}", "slow-roll compensation", Measured("; ".join(parts), **lengths),
                        "runout (mechanical/electrical, fixed to the shaft surface) measured at slow roll with the "
                        "keyphasor, subtracted as vectors: the 1X/2X vectors reported are the shaft's vibration "
                        "without it", None)


def _bearing_items(det) -> list[EvidenceItem]:
    b = det.bearing
    scope = f"bearing {b}"
    items = []
    for order in (1, 2):
        for d in ("x", "y"):
            text, amp = _vector(det, d, order)
            meaning = ("running-speed response: unbalance, bow, and the 1X part of misalignment" if order == 1 else
                       "twice-per-revolution: misalignment, shaft asymmetry (two-pole generator), or a crack")
            items.append(EvidenceItem(scope, f"{order}X {d}", text, meaning, _num(amp)))
    r = det.features.get(f"b{b}_2x_1x_major_ratio", np.nan)
    items.append(EvidenceItem(scope, "2X/1X", "not measurable" if not np.isfinite(r) else f"{r:.2f} (orbit major axes)",
                              _ratio_meaning(r), _num(r)))
    shape, meaning = _shape_meaning(det)
    items.append(EvidenceItem(scope, "orbit shape", shape, meaning,
                              _num(det.features.get(f"b{b}_orbit12_ellipticity", np.nan))))
    items.append(_centreline(det))
    return items


def _coupling_items(fr) -> list[EvidenceItem]:
    bi, bj = COUPLING
    scope = f"coupling {bi}–{bj}"
    if bi not in fr.bearings or bj not in fr.bearings:
        return [EvidenceItem(scope, "phase across the coupling", f"not measurable (needs bearings {bi} and {bj})",
                             "the phase difference across the coupling is the most direct misalignment signature",
                             None)]
    if split_pairs(getattr(fr, "acquisitions", ()), [COUPLING]):
        return [EvidenceItem(scope, "phase across the coupling",
                             f"not measured (bearings {bi} and {bj} recorded in separate acquisitions)",
                             "the phase difference across the coupling is the most direct misalignment signature; "
                             "between takes whose start times are not related it would be the delay between them — "
                             f"record bearings {bi} and {bj} together for it", None)]
    items = []
    for order in (1, 2):
        for d in ("x", "y"):
            v = fr[f"dphase_{order}x_b{bi}_b{bj}_{d}_deg"]
            if not np.isfinite(v):
                items.append(EvidenceItem(scope, f"{order}X phase difference {d}", "not measurable",
                                          f"the {order}X phase is in the noise at bearing {bi} or {bj}", None))
                continue
            a = abs(v)
            if a >= 135:
                meaning = ("near 180°: the shaft ends move against each other across the coupling — the classic "
                           "field signature of misalignment (also seen in a coupling-bending mode)")
            elif a <= 45:
                meaning = ("near 0°: the shaft ends move together (unbalance, or a stiff coupling carrying the "
                           "motion across); on its own this does not rule misalignment out")
            else:
                meaning = "in between: a mixed response; trend it"
            items.append(EvidenceItem(scope, f"{order}X phase difference {d}", f"{v:+.0f}°", meaning, float(v)))
    return items


def _load_sharing_items(fr) -> list[EvidenceItem]:
    """Per pair of :data:`ACROSS_PAIRS` whose static positions are both read: journal i's eccentricity against
    journal j's and where it sits relative to it (the load one bearing takes from the other)."""
    items = []
    for i, j in ACROSS_PAIRS:
        ratio = fr[f"centre_ecc_b{i}_b{j}_ratio"]
        dx, dy = fr[f"dcentre_x_b{i}_b{j}_per_c"], fr[f"dcentre_y_b{i}_b{j}_per_c"]
        if not (np.isfinite(ratio) and np.isfinite(dx) and np.isfinite(dy)):
            continue
        where = (f"{abs(dy):.2f} c {'lower' if dy < 0 else 'higher'}, {abs(dx):.2f} c towards "
                 f"{'+x' if dx >= 0 else '−x'}")
        items.append(EvidenceItem(
            f"journals {i} and {j}", "load sharing (centreline)",
            f"journal {i}'s eccentricity {ratio:.2f}× journal {j}'s; journal {i} sits {where} of journal {j}",
            "an offset coupling lifts one journal and presses its neighbour down: a ratio far from this machine's "
            "aligned baseline is the load transfer misalignment causes (the design sets the healthy ratio; trend it)",
            float(ratio)))
    return items


def _common_mode_items(fr) -> list[EvidenceItem]:
    """The 1X / 2X common to every probe, where it is a notable share of the order (``features._common_mode``)."""
    items = []
    for order in (1, 2):
        cm = common_mode(fr, order)
        if cm is None or not cm.share >= COMMON_MODE_NOTABLE_SHARE:
            continue
        dominant = common_mode_dominates(cm)
        meaning = (f"the {order}X is one signal at every probe: electrical pickup (mains on a grid-synchronous "
                   "generator) or the probe mountings vibrating together, not shaft motion" if dominant else
                   f"a large part of the {order}X is one signal at every probe, which no shaft orbit is: pickup or "
                   "mounting vibration is likely; check the probe cabling and grounding")
        items.append(EvidenceItem(
            "all probes", f"{order}X common to every probe",
            Measured(f"{100 * cm.share:.0f} % of the {order}X power: {{amp}} pk-pk ∠ "
                     f"{_whole_degrees(cm.phase_lag_deg):.0f}° at all {cm.n_probes} probes", amp=Length(cm.amp_um_pp)),
            meaning, float(cm.share)))
    return items


def evidence(fr) -> list[EvidenceItem]:
    """The model-independent evidence of a feature result (coupling bearings first).

    Parameters
    ----------
    fr : features.FeatureResult

    Returns
    -------
    list of EvidenceItem
        The slow-roll vectors subtracted at each bearing (when runout was compensated), a 1X / 2X
        largely common to every probe (pickup: when its share reaches ``COMMON_MODE_NOTABLE_SHARE``), the
        across-the-coupling phase differences, then each coupling bearing present (2, 3); when
        neither coupling bearing is present, every bearing present.
    """
    present = sorted(fr.bearings)
    chosen = [b for b in present if b in COUPLING] or present
    items = [it for b in present if (it := _slow_roll_item(fr.bearings[b])) is not None]
    items += _common_mode_items(fr)
    items += _coupling_items(fr)
    items += _load_sharing_items(fr)
    for b in chosen:
        items += _bearing_items(fr.bearings[b])
    return items
