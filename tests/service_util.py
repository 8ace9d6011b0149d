"""Helpers shared by the service tests (not a test module)."""
from __future__ import annotations

from pathlib import Path

API_KEY = "test-key-0123456789"


def make_settings(tmp_path: Path, **overrides):
    """Settings for an isolated app: its own data dir, database and registry under ``tmp_path``."""
    from service.core.config import Settings

    values = dict(data_dir=tmp_path / "data", api_key=API_KEY, environment="development",
                  dask_local_workers=1, _env_file=None)
    values.update(overrides)
    return Settings(**values)


def auth() -> dict[str, str]:
    return {"X-API-Key": API_KEY}


def probe_signals_um(journal_displacements_m, angles_deg=(45.0, 135.0), bearings=(1, 2, 3, 4)):
    """Probe readings (µm) of the simulated journals: p = x cos θ + y sin θ for each bearing and probe angle.

    Returns ``(bearing, angle_deg, data)`` triples, bearing-major.
    """
    import numpy as np

    d = np.asarray(journal_displacements_m) * 1e6
    out = []
    for b in bearings:
        for a in angles_deg:
            t = np.deg2rad(a)
            out.append((b, a, d[:, b - 1, 0] * np.cos(t) + d[:, b - 1, 1] * np.sin(t)))
    return out


_SIM_CACHE: dict = {}


def simulated_channels(misalignment=0.2, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=24,
                       mechanism="rigid"):
    """A simulated recording of the default plant as ``(sample_rate_hz, [(bearing, angle_deg, data_um), ...])``."""
    key = (misalignment, speed_rpm, sample_rate_hz, record_revs, mechanism)
    if key not in _SIM_CACHE:
        from simulator import Plant, simulate

        res = simulate(Plant.default(), speed_rpm, misalignment, 0.05, mechanism=mechanism,
                       transient_revs=200, record_revs=record_revs, sample_rate_hz=sample_rate_hz)
        assert res.status == "ok", res.status
        _SIM_CACHE[key] = (sample_rate_hz, probe_signals_um(res.journal_displacements_m))
    return _SIM_CACHE[key]


def diagnose_json(sample_rate_hz, channels, **extra):
    """JSON body of POST /diagnose."""
    body = {"sample_rate_hz": sample_rate_hz,
            "channels": [{"bearing": b, "angle_deg": a, "units": "um", "data": [float(v) for v in d]}
                         for b, a, d in channels]}
    body.update(extra)
    return body
