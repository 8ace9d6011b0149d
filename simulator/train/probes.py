"""A train's time response in the recording layout the features read: proximity-probe waveforms in µm.

Each probe reads its journal's displacement relative to the bearing housing along the probe's axis, DC
included (``rotordiag.core.conventions.project_on_probe``: d = x cos α + y sin α, α from +x toward +y); the
keyphasor is the once-per-revolution mark t·Ω ≡ 0 mod 2π (the unbalance angles' reference), given on the
record's clock (first sample at t = 0). Channels are ``(bearing number, angle_deg)`` with bearings numbered
1, 2, … along the train, as ``features.ProbeChannel`` numbers them; any number of instrumented bearings.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rotordiag.core.conventions import project_on_probe

from .dynamics import TrainRun
from .model import TrainError

DEFAULT_PROBE_ANGLES_DEG = (45.0, 135.0)


@dataclass(frozen=True)
class TrainProbes:
    """Probe waveforms of one run: ``waveforms_um`` (n_channels, n_points), ``channels`` [(bearing, angle_deg)],
    ``sample_rate_hz``, ``keyphasor_times_s`` (record clock), ``speed_rpm``, ``clearance_um`` {bearing: µm},
    ``bearing_names`` {bearing: name}."""

    waveforms_um: np.ndarray
    channels: tuple[tuple[int, float], ...]
    sample_rate_hz: float
    keyphasor_times_s: np.ndarray
    speed_rpm: float
    clearance_um: dict[int, float]
    bearing_names: dict[int, str]


def train_probes(run: TrainRun, channels: Sequence[tuple[int, float]] | None = None) -> TrainProbes:
    """The probes of ``run`` (default: a 45°/135° pair at every bearing).

    Raises ``TrainError`` for a bearing number outside 1…n_bearings or a non-finite angle, and for a run
    that did not finish (``status`` other than ``ok``: its record is incomplete).
    """
    n_b = run.journal_m.shape[1]
    if channels is None:
        channels = [(b + 1, a) for b in range(n_b) for a in DEFAULT_PROBE_ANGLES_DEG]
    chans = []
    for ch in channels:
        try:
            b, a = int(ch[0]), float(ch[1])
        except (TypeError, ValueError, IndexError):
            raise TrainError(f"a probe channel is (bearing number, angle_deg), got {ch!r}") from None
        if not 1 <= b <= n_b:
            raise TrainError(f"probe bearing {b} does not exist: this train has bearings 1…{n_b}")
        if not math.isfinite(a):
            raise TrainError(f"probe angle of bearing {b} must be finite (got {a!r})")
        chans.append((b, a))
    if not chans:
        raise TrainError("at least one probe channel is needed")
    if run.status != "ok":
        raise TrainError(f"the run ended as {run.status!r}: its record is incomplete, no probe waveforms")
    xy_um = run.journal_m * 1e6
    wave = np.stack([project_on_probe(xy_um[:, b - 1, 0], xy_um[:, b - 1, 1], a) for b, a in chans])
    t0 = float(run.time_s[0])
    fs = 1.0 / float(run.time_s[1] - run.time_s[0])
    return TrainProbes(waveforms_um=wave, channels=tuple(chans), sample_rate_hz=fs,
                       keyphasor_times_s=np.asarray(run.keyphasor_s, dtype=float) - t0, speed_rpm=run.speed_rpm,
                       clearance_um={b + 1: float(c) * 1e6 for b, c in enumerate(run.clearance_m)},
                       bearing_names={b + 1: str(n) for b, n in enumerate(run.bearing_names)})
