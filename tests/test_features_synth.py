"""Synthetic probe signals with exactly known content, for the features tests.

``make_recording`` builds x/y journal displacements from order components given as
zero-to-peak amplitude and phase lag (``a·cos(kθ − φ)``, θ = 2π·f1·t unless a shaft-angle
function is given), projects them onto the probes (``p = x cos α + y sin α``) and converts
to the requested units — the same convention the extractor documents, written out here
independently of ``features``.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording

UM_PER_UNIT = {"um": 1.0, "mm": 1000.0, "m": 1e6, "mil": 25.4}

# default components: bearing -> list of (order, ax_0p, phx_deg, ay_0p, phy_deg)
DEFAULT_COMPONENTS = {
    1: [(1, 40.0, 30.0, 32.0, 120.0), (2, 12.0, 75.0, 9.0, 160.0), (3, 3.0, 10.0, 2.0, 300.0)],
    2: [(1, 55.0, 50.0, 45.0, 145.0), (2, 20.0, 200.0, 14.0, 290.0), (3, 4.0, 100.0, 5.0, 20.0)],
    3: [(1, 25.0, 210.0, 22.0, 305.0), (2, 18.0, 20.0, 15.0, 110.0), (3, 2.5, 45.0, 1.5, 135.0)],
    4: [(1, 15.0, 250.0, 14.0, 340.0), (2, 6.0, 330.0, 4.0, 60.0), (3, 1.0, 80.0, 1.0, 170.0)],
}


def xy_signals(theta: np.ndarray, comps) -> tuple[np.ndarray, np.ndarray]:
    x = np.zeros_like(theta)
    y = np.zeros_like(theta)
    for k, ax, phx, ay, phy in comps:
        x += ax * np.cos(k * theta - np.deg2rad(phx))
        y += ay * np.cos(k * theta - np.deg2rad(phy))
    return x, y


def make_recording(
    *,
    fs: float = 5120.0,
    n: int = 16384,
    rpm: float = 1953.7,
    components: dict | None = None,
    angles: tuple[float, float] = (45.0, 135.0),
    units: str = "um",
    noise_um: float = 0.0,
    seed: int = 0,
    theta_fn: Callable[[np.ndarray], np.ndarray] | None = None,
    extra: Callable[[np.ndarray, int], tuple[np.ndarray, np.ndarray]] | None = None,
    offset_um: tuple[float, float] = (0.0, 0.0),
    **recording_kw,
) -> Recording:
    """A recording of the given components; ``extra(t, bearing) -> (x, y)`` adds more (µm)."""
    comps = DEFAULT_COMPONENTS if components is None else components
    t = np.arange(n) / fs
    theta = 2 * np.pi * rpm / 60.0 * t if theta_fn is None else theta_fn(t)
    rng = np.random.default_rng(seed)
    chans = []
    for b in sorted(comps):
        x, y = xy_signals(theta, comps[b])
        x = x + offset_um[0]
        y = y + offset_um[1]
        if extra is not None:
            ex, ey = extra(t, b)
            x, y = x + ex, y + ey
        for a in angles:
            r = np.deg2rad(a)
            p = x * np.cos(r) + y * np.sin(r)
            if noise_um:
                p = p + rng.normal(0.0, noise_um, n)
            chans.append(ProbeChannel(bearing=b, angle_deg=a, units=units, data=p / UM_PER_UNIT[units]))
    return Recording(sample_rate_hz=fs, channels=chans, **recording_kw)


def keyphasor_times(rpm: float, duration_s: float, t0: float = 0.0) -> np.ndarray:
    return np.arange(t0, duration_s, 60.0 / rpm)


def test_probe_projection_convention():
    """A probe at 90° reads y, at 0° reads x, at 45° reads (x + y)/√2."""
    comps = {1: [(1, 10.0, 0.0, 5.0, 90.0)]}
    rec = make_recording(components=comps, angles=(0.0, 90.0), n=4096)
    t = np.arange(4096) / 5120.0
    th = 2 * np.pi * 1953.7 / 60 * t
    np.testing.assert_allclose(rec.channels[0].data, 10 * np.cos(th), atol=1e-12)
    np.testing.assert_allclose(rec.channels[1].data, 5 * np.sin(th), atol=1e-12)


@pytest.mark.parametrize("units", ["mm", "mil", "m"])
def test_units_scaling(units):
    a = make_recording(n=2048, components={1: [(1, 25.4, 0.0, 25.4, 0.0)]})
    b = make_recording(n=2048, components={1: [(1, 25.4, 0.0, 25.4, 0.0)]}, units=units)
    np.testing.assert_allclose(b.channels[0].data * UM_PER_UNIT[units], a.channels[0].data, rtol=1e-12)
