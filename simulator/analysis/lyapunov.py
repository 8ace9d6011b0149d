"""Largest Lyapunov exponent of a flow map by Benettin's method.

A *flow map* is any callable that advances a state by one fixed interval: one
revolution of the rotor (the Poincaré map of the 2π-periodic system), one time
unit of the Lorenz flow, one iteration of a discrete map.  The largest Lyapunov
exponent (LLE) is the mean logarithmic growth rate per interval of an
infinitesimal perturbation.  Two ways to follow the perturbation are offered:

* ``method="neighbour"`` (default): a neighbouring trajectory at distance
  ``separation`` is advanced with the same flow map and pulled back to distance
  ``separation`` along the current separation direction after every interval
  (Benettin et al., Meccanica 15, 1980).  Works with any black-box flow map,
  including an adaptive ODE integrator, as long as ``separation`` is well above
  the integration error and well below the size of the attractor.
* ``method="variational"``: a ``tangent_map(state, vector) -> (state, vector)``
  advances the state and a tangent vector (the variational equations); the
  vector is renormalised to unit length after every interval.

The estimate after ``k`` intervals is ``sum(log(growth_i)) / k``; the full
running estimate is returned as the convergence history.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = ["LyapunovResult", "FlowMapError", "largest_lyapunov"]

#: number of batches for the batch-means standard error of the LLE estimate
N_BATCHES = 10


class FlowMapError(RuntimeError):
    """Raised by a flow map that cannot advance a state (e.g. journal contact, divergence)."""


@dataclass(frozen=True)
class LyapunovResult:
    """Largest Lyapunov exponent estimate and its diagnostics.

    Attributes
    ----------
    lle_per_interval : float
        LLE per flow-map interval (per revolution for the rotor's Poincaré map).
    lle_per_s : float
        ``lle_per_interval / interval_s`` (per time unit of the flow when
        ``interval_s`` is given in that unit).
    interval_s : float
        Duration of one interval.
    history_per_interval : ndarray, shape (n_intervals,)
        Running estimate after 1, 2, ... intervals (the convergence history).
    log_growth : ndarray, shape (n_intervals,)
        Logarithmic growth of the perturbation in each interval.
    stderr_per_interval : float
        Batch-means standard error of ``lle_per_interval`` (``N_BATCHES`` batches);
        NaN when fewer than ``N_BATCHES`` intervals were used.
    method : str
        ``"neighbour"`` or ``"variational"``.
    final_state : ndarray
        State of the reference trajectory after the last interval.
    """

    lle_per_interval: float
    lle_per_s: float
    interval_s: float
    history_per_interval: np.ndarray = field(repr=False)
    log_growth: np.ndarray = field(repr=False)
    stderr_per_interval: float
    method: str
    final_state: np.ndarray = field(repr=False)

    @property
    def n_intervals(self) -> int:
        """Number of intervals averaged."""
        return int(self.log_growth.size)


def _batch_stderr(values: np.ndarray, n_batches: int = N_BATCHES) -> float:
    if values.size < n_batches:
        return float("nan")
    usable = values.size - values.size % n_batches
    means = values[values.size - usable:].reshape(n_batches, -1).mean(axis=1)
    return float(means.std(ddof=1) / np.sqrt(n_batches))


def _as_state(x: object, name: str) -> np.ndarray:
    arr = np.array(x, dtype=float, copy=True)
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D state vector, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise FlowMapError(f"{name} contains non-finite values")
    return arr


def largest_lyapunov(
    flow_map: Callable[[np.ndarray], np.ndarray] | None,
    state0: np.ndarray,
    *,
    n_intervals: int,
    interval_s: float = 1.0,
    transient_intervals: int = 0,
    method: str = "neighbour",
    separation: float = 1e-8,
    norm_weights: np.ndarray | None = None,
    tangent_map: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None,
    seed: int = 0,
    progress: Callable[[int], None] | None = None,
) -> LyapunovResult:
    """Estimate the largest Lyapunov exponent of a flow map (Benettin's method).

    Parameters
    ----------
    flow_map : callable ``state -> state``
        Advances a 1-D state by one interval; may raise :class:`FlowMapError`.
        For a periodically forced system the interval must be a whole number of
        forcing periods (a stroboscopic / Poincaré map).  Not used (may be None)
        with ``method="variational"``.
    state0 : array_like, shape (n_state,)
        Starting state.
    n_intervals : int
        Number of intervals averaged (after the transient), ≥ 1.
    interval_s : float
        Duration of one interval, for the per-second exponent (e.g. ``60/rpm``
        for one revolution).  Must be > 0.
    transient_intervals : int
        Intervals to advance before measuring (reference trajectory only), ≥ 0.
    method : {"neighbour", "variational"}
        Renormalised neighbouring trajectory, or variational equations through
        ``tangent_map``.
    separation : float
        Neighbour distance (weighted Euclidean norm), ``method="neighbour"`` only.
        Choose it ≫ the flow map's numerical error and ≪ the attractor size.
    norm_weights : array_like, shape (n_state,), optional
        Positive weights of the norm ``sqrt(sum((w*d)**2))``; default all ones.
        The exponent does not depend on the norm, but the linear regime does.
    tangent_map : callable ``(state, vector) -> (state, vector)``, optional
        Advances state and tangent vector by one interval (``method="variational"``).
    seed : int
        Seed of the random initial perturbation direction.
    progress : callable ``int -> None``, optional
        Called with 1 after each measured interval (e.g. ``tqdm.update``).

    Returns
    -------
    LyapunovResult

    Raises
    ------
    ValueError
        Bad arguments (the message names the parameter).
    FlowMapError
        The flow map failed or produced a non-finite state.
    """
    if method not in ("neighbour", "variational"):
        raise ValueError(f"method must be 'neighbour' or 'variational', got {method!r}")
    if isinstance(n_intervals, bool) or not isinstance(n_intervals, (int, np.integer)) or n_intervals < 1:
        raise ValueError(f"n_intervals must be an integer >= 1, got {n_intervals!r}")
    if isinstance(transient_intervals, bool) or not isinstance(transient_intervals, (int, np.integer)) \
            or transient_intervals < 0:
        raise ValueError(f"transient_intervals must be an integer >= 0, got {transient_intervals!r}")
    if not (np.isfinite(interval_s) and interval_s > 0):
        raise ValueError(f"interval_s must be a finite positive duration, got {interval_s!r}")
    if not (np.isfinite(separation) and separation > 0):
        raise ValueError(f"separation must be a finite positive distance, got {separation!r}")
    if method == "neighbour" and not callable(flow_map):
        raise ValueError("flow_map must be a callable state -> state for method='neighbour'")
    if method == "variational" and not callable(tangent_map):
        raise ValueError("tangent_map must be a callable (state, vector) -> (state, vector) "
                         "for method='variational'")

    x = _as_state(state0, "state0")
    n = x.size
    if norm_weights is None:
        w = np.ones(n)
    else:
        w = np.asarray(norm_weights, dtype=float)
        if w.shape != (n,) or not np.all(np.isfinite(w)) or np.any(w <= 0):
            raise ValueError(f"norm_weights must be {n} finite positive numbers, got shape {w.shape}")

    def norm(d: np.ndarray) -> float:
        return float(np.sqrt(np.sum((w * d) ** 2)))

    def step(state: np.ndarray) -> np.ndarray:
        if flow_map is not None:
            return _as_state(flow_map(state), "flow_map(state)")
        assert tangent_map is not None  # checked above
        return _as_state(tangent_map(state, np.zeros_like(state))[0], "tangent_map(state)[0]")

    for _ in range(int(transient_intervals)):
        x = step(x)

    rng = np.random.default_rng(seed)
    direction = rng.standard_normal(n) / w
    direction /= norm(direction)

    log_growth = np.empty(int(n_intervals))
    if method == "neighbour":
        assert flow_map is not None  # checked above
        y = x + separation * direction
        for k in range(int(n_intervals)):
            x_next = step(x)
            y_next = _as_state(flow_map(y), "flow_map(neighbour)")
            d = y_next - x_next
            dist = norm(d)
            if not (dist > 0 and np.isfinite(dist)):
                raise FlowMapError(
                    f"neighbour separation became {dist!r} in interval {k}: choose a larger "
                    "separation (it is below the flow map's resolution)")
            log_growth[k] = np.log(dist / separation)
            x = x_next
            y = x + d * (separation / dist)
            if progress is not None:
                progress(1)
    else:
        v = direction
        assert tangent_map is not None  # checked above
        for k in range(int(n_intervals)):
            x_next, v_next = tangent_map(x, v)
            x_next = _as_state(x_next, "tangent_map(state)[0]")
            v_next = _as_state(v_next, "tangent_map(state)[1]")
            length = norm(v_next)
            if not (length > 0 and np.isfinite(length)):
                raise FlowMapError(f"tangent vector length became {length!r} in interval {k}")
            log_growth[k] = np.log(length)
            x = x_next
            v = v_next / length
            if progress is not None:
                progress(1)

    history = np.cumsum(log_growth) / np.arange(1, log_growth.size + 1)
    lle = float(history[-1])
    return LyapunovResult(
        lle_per_interval=lle,
        lle_per_s=lle / float(interval_s),
        interval_s=float(interval_s),
        history_per_interval=history,
        log_growth=log_growth,
        stderr_per_interval=_batch_stderr(log_growth),
        method=method,
        final_state=x,
    )
