"""The robustness conditions on held-out shaft-train recordings (issue 48, item 5: the measurement rows on trains).

The train recordings (``benchmarks/train_verdict.py``'s judged trains: finite-element trains of plants the training
never saw, stored as measured) already carry what their dataset drew (runout, noise, speed fluctuation). The
conditions that act on a recording as measured — what the user states, which probes are sent and how they are
numbered, probe gains, the DC part, faults and pickup, a second take — are applied to them as to the simulated base
set (:func:`rotordiag.models.robustness.apply_faults`, same order of draws). The rows that change the measurement
model itself (runout, SNR), the simulated set (presets, far plants), the record length or the keyphasor stay the
base set's (:func:`applies_to_recordings`).
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .robustness import (
    CONDITIONS,
    REVS,
    Condition,
    Outcome,
    apply_faults,
    diagnose_waveforms,
    measurement_rng,
    sent_bearings,
    told_extra,
)

__all__ = ["applies_to_recordings", "train_conditions", "run_condition_on_recordings", "family_rows"]


def applies_to_recordings(cond: Condition) -> bool:
    """Whether ``cond`` acts on a recording as measured (so it can be applied to stored train recordings)."""
    return (cond.sim_set == "base" and cond.revs == REVS and cond.snr_db == 45.0
            and cond.runout_1x_um == (0.0, 0.0) and cond.runout_2x_um == (0.0, 0.0)
            and not cond.keyphasor_fault and not cond.keyphasor_per_take)


def train_conditions() -> tuple[Condition, ...]:
    """The conditions of :data:`~rotordiag.models.robustness.CONDITIONS` that apply to stored recordings, in order."""
    return tuple(c for c in CONDITIONS if applies_to_recordings(c))


def run_condition_on_recordings(bundle, cond: Condition, samples: Sequence[dict], seed: int) -> list[Outcome]:
    """One outcome per stored recording under ``cond``.

    Each sample is a dict as ``benchmarks/train_verdict.read_samples`` gives it: ``waveforms_um`` (two channels per
    bearing of ``bearings``, at :data:`~rotordiag.models.robustness.ANGLES_DEG`), ``fs_hz``, ``speed_rpm``,
    ``clearance_um``, ``delta``, ``mechanism``, ``family`` and, optionally, ``offset_angle_rad``. The probes sent
    are the recording's bearings among ``cond.bearings``; the gains, faults and stated values are drawn from
    :func:`~rotordiag.models.robustness.measurement_rng` (``seed``, the condition, the sample's index).

    Raises
    ------
    ValueError
        A condition that does not apply to stored recordings (:func:`applies_to_recordings`).
    """
    if not applies_to_recordings(cond):
        raise ValueError(f"condition {cond.name!r} changes the simulation or the measurement model: it applies to "
                         "the simulated sets only")
    outs = []
    for i, s in enumerate(samples):
        o = Outcome(float(s["delta"]), str(s["mechanism"]), machine=str(s["family"]), speed_rpm=float(s["speed_rpm"]),
                    true_angle_rad=float(s.get("offset_angle_rad", math.nan)))
        rng = measurement_rng(cond, seed, i)
        recorded = tuple(int(b) for b in s["bearings"])
        bearings = tuple(b for b in recorded if b in cond.bearings)
        rows = [2 * k + j for k, b in enumerate(recorded) if b in cond.bearings for j in (0, 1)]
        w = np.array(s["waveforms_um"], dtype=np.float64)[rows]
        if cond.gain_mismatch > 0:
            w *= rng.uniform(1.0 - cond.gain_mismatch, 1.0 + cond.gain_mismatch, size=(w.shape[0], 1))
        w, _ = apply_faults(w, cond, bearings, float(s["clearance_um"]), float(s["speed_rpm"]), float(s["fs_hz"]), rng)
        stated = float(s["speed_rpm"]) * (1.0 + cond.speed_stated_error) if cond.speed_given else None
        told = told_extra(cond, float(s["speed_rpm"]), stated, None, rng)
        outs.append(diagnose_waveforms(bundle, w, sent_bearings(cond, bearings), float(s["fs_hz"]), stated,
                                       float(s["clearance_um"]) if cond.clearance_given else None, o, **told))
    return outs


def family_rows(outs: Sequence[Outcome], names: Sequence[str], edges: Sequence[float]) -> list[dict]:
    """Per machine family (``Outcome.machine``) of one condition's outcomes: n, false alarms (healthy trains given
    any class but the first, any status) of the healthy ones, Δ ≥ the second edge given the second band or worse,
    the confident share, and of the confident answers those in the true band and two or more bands off."""
    out = []
    for fam in sorted({o.machine for o in outs}):
        sel = [o for o in outs if o.machine == fam and o.status not in ("sim failed", "refused")]
        shown = np.array([list(names).index(o.model_class) if o.model_class in names else -1 for o in sel])
        true = np.searchsorted(np.asarray(edges, dtype=float), [o.delta for o in sel], side="right")
        conf = np.array([o.status == "confident" for o in sel], dtype=bool)
        healthy = np.array([o.delta == 0.0 for o in sel], dtype=bool)
        moderate = np.array([o.delta >= edges[1] for o in sel], dtype=bool)
        out.append({"family": fam, "n": len(sel), "healthy": int(healthy.sum()),
                    "false_alarms": int((healthy & (shown > 0)).sum()), "moderate": int(moderate.sum()),
                    "detected": int((moderate & (shown >= 1)).sum()), "confident": int(conf.sum()),
                    "right": int((conf & (shown == true)).sum()), "off2": int((conf & (np.abs(shown - true) >= 2)).sum())})
    return out
