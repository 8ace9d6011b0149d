"""Once-per-revolution (Poincaré) samples, their dispersion and the motion type."""
from __future__ import annotations

import numpy as np

from . import _config as cfg

__all__ = ["poincare_points", "dispersion", "classify"]


def poincare_points(sync_at_zero: np.ndarray, residual: np.ndarray, seg_times_s: np.ndarray,
                    rev_times_s: np.ndarray) -> np.ndarray:
    """Signal at θ = 2πm for each analysed revolution m.

    The synchronous part is the same at every θ = 2πm (``sync_at_zero``: constant plus
    Σ Re C_k); the non-synchronous residual is interpolated linearly at the revolution start
    times. ``residual`` has shape (m, n); returns shape (n_revs, m).
    """
    out = np.empty((rev_times_s.size, residual.shape[0]))
    for c in range(residual.shape[0]):
        out[:, c] = sync_at_zero[c] + np.interp(rev_times_s, seg_times_s, residual[c])
    return out


def dispersion(points: np.ndarray) -> float:
    """RMS distance of the points (n, d) from their centroid."""
    return float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=1))))


def classify(points: np.ndarray, orbit_size_um: float, point_noise_um: float):
    """Motion type from the Poincaré points of all bearings with the analysis package's classifier.

    The period tolerance is widened from the classifier's default (a fraction of the orbit
    size, meant for noise-free simulations) to ``POINCARE_NOISE_FACTOR`` × the RMS noise of a
    Poincaré point, so that measurement noise does not turn a period-1 orbit into
    "quasi-periodic". Returns ``(MotionType | None, note)``; None when the classifier is not
    importable.
    """
    try:
        from simulator.analysis import classify_motion
        from simulator.analysis.motion import PERIOD_RTOL
    except ImportError as exc:  # pragma: no cover - depends on the installation
        return None, f"motion type not determined: simulator.analysis.classify_motion unavailable ({exc})"
    rtol = PERIOD_RTOL
    if orbit_size_um > 0:
        rtol = max(rtol, cfg.POINCARE_NOISE_FACTOR * point_noise_um / orbit_size_um)
    return classify_motion(points, orbit_size=orbit_size_um, period_rtol=rtol), ""
