"""Bearings recorded in separate acquisitions: which phase differences between bearings are measured.

A recording's channels are taken to be sampled together: the phase difference of an order between two bearings
(``dphase_*``) is then a property of the shaft. A plant engineer with a four-channel analyser records an
eight-probe train in two takes, or takes bearings 3 and 4 from another monitoring system; the takes' start times
are not related, and a phase difference between bearings of different takes is the delay between the takes
(k·360°·f·τ at order k), not the shaft's. ``Recording.acquisitions`` says which bearings were sampled together;
the phase differences across acquisitions are then missing, not numbers, and the evidence says why (the
measurement behind it: docs/features.md, "Measurements behind the acquisition and keyphasor checks").
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rotordiag.core.input_bounds import KEYPHASOR_MAX_TIME_S, KEYPHASOR_MIN_INTERVAL_S

from ._config import PROBE_BEARINGS

__all__ = ["parse_acquisitions", "acquisitions_in_order", "format_acquisitions", "split_pairs", "parse_keyphasor_takes"]

_HINT = ("give the groups of bearings sampled together, e.g. \"1,2;3,4\" (bearings 1 and 2 in one take, 3 and 4 in "
         "another), or [[1, 2], [3, 4]]")


def _bearing(value: object, name: str) -> int:
    if isinstance(value, str):
        value = value.strip()
    try:
        b = int(value)  # type: ignore[call-overload]
    except (TypeError, ValueError):
        raise ValueError(f"{name}: {value!r} is not a bearing number 1–{PROBE_BEARINGS[-1]}; {_HINT}") from None
    if isinstance(value, bool) or b not in PROBE_BEARINGS or (not isinstance(value, str) and b != value):
        raise ValueError(f"{name}: {value!r} is not a bearing number 1–{PROBE_BEARINGS[-1]}; {_HINT}")
    return b


def acquisitions_in_order(value: object, name: str = "acquisitions") -> tuple[tuple[int, ...], ...]:
    """Groups of bearings sampled together, each sorted, in the order given (:func:`parse_acquisitions` orders them).

    Raises
    ------
    ValueError
        As :func:`parse_acquisitions`.
    """
    if isinstance(value, str):
        value = [g.split(",") for g in value.split(";") if g.strip()]
    if isinstance(value, (bytes, Mapping)) or not isinstance(value, (Sequence, np.ndarray)):
        raise ValueError(f"{name} must be groups of bearing numbers, got {value!r}; {_HINT}")
    groups: list[tuple[int, ...]] = []
    seen: set[int] = set()
    for i, g in enumerate(value):
        if isinstance(g, (str, bytes, Mapping)) or not isinstance(g, (Sequence, np.ndarray)):
            raise ValueError(f"{name}[{i}] must be a group of bearing numbers, got {g!r}; {_HINT}")
        group = [_bearing(b, f"{name}[{i}]") for b in g if not (isinstance(b, str) and not b.strip())]
        if not group:
            raise ValueError(f"{name}[{i}] is empty; {_HINT}")
        twice = sorted(seen.intersection(group) | {b for b in group if group.count(b) > 1})
        if twice:
            raise ValueError(f"{name}: bearing {twice[0]} is in more than one acquisition; {_HINT}")
        seen.update(group)
        groups.append(tuple(sorted(group)))
    if not groups:
        raise ValueError(f"{name} is empty; {_HINT}")
    return tuple(groups)


def parse_acquisitions(value: object, name: str = "acquisitions") -> tuple[tuple[int, ...], ...]:
    """Groups of bearings sampled together, from ``"1,2;3,4"`` or ``[[1, 2], [3, 4]]``: each group sorted, the
    groups ordered by their first bearing.

    Raises
    ------
    ValueError
        Naming ``name``: not groups of bearing numbers, an empty group, or a bearing in two groups.
    """
    return tuple(sorted(acquisitions_in_order(value, name)))


def _pulse_train(value: object, name: str) -> np.ndarray:
    try:
        kp = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a 1-D array of pulse times in s") from None
    if kp.ndim != 1 or kp.size < 2:
        raise ValueError(f"{name} must be a 1-D array of at least 2 pulse times (s), got shape {kp.shape}")
    if not np.all(np.isfinite(kp)):
        raise ValueError(f"{name} contains NaN/inf; give pulse times in s")
    if np.any(np.diff(kp) <= 0):
        raise ValueError(f"{name} must be strictly increasing (one pulse per revolution)")
    if np.max(np.abs(kp)) > KEYPHASOR_MAX_TIME_S or np.min(np.diff(kp)) < KEYPHASOR_MIN_INTERVAL_S:
        raise ValueError(f"{name}: pulse times must lie within ±{KEYPHASOR_MAX_TIME_S:g} s of the first sample and "
                         f"at least {KEYPHASOR_MIN_INTERVAL_S:g} s apart: check the units (seconds)")
    return kp


def parse_keyphasor_takes(value: object, name: str = "keyphasor_times_s") -> np.ndarray | tuple[np.ndarray, ...]:
    """Keyphasor pulse times: one train (a 1-D array, or ``"t0,t1,…"``), or one train per acquisition (a sequence
    of 1-D sequences, or ``"t0,t1,…;t0,t1,…"``), each on its own take's clock (first sample at t = 0) and in the
    order the acquisitions are listed.

    Raises
    ------
    ValueError
        Naming ``name`` (and the take): not numbers, fewer than 2 pulses, NaN/inf, not strictly increasing.
    """
    if isinstance(value, str):
        parts = [p for p in value.split(";") if p.strip()]
        try:
            trains: list[object] = [[float(t) for t in p.split(",") if t.strip()] for p in parts]
        except ValueError:
            raise ValueError(f"{name} must be pulse times in s separated by commas, one acquisition's from the "
                             "next by semicolons") from None
        value = trains[0] if len(trains) == 1 else trains
    if isinstance(value, np.ndarray) and value.ndim == 2:
        value = list(value)
    if isinstance(value, (Sequence, np.ndarray)) and not isinstance(value, (str, bytes)) and len(value) > 0 \
            and all(isinstance(v, (Sequence, np.ndarray)) and not isinstance(v, (str, bytes)) for v in value):
        return tuple(_pulse_train(v, f"{name}[{i}]") for i, v in enumerate(value))
    return _pulse_train(value, name)


def format_acquisitions(acquisitions: Sequence[Sequence[int]] | None) -> str:
    """The groups as a user types them (``"1,2;3,4"``); ``""`` for None (every channel sampled together)."""
    return ";".join(",".join(str(b) for b in g) for g in acquisitions or ())


def split_pairs(acquisitions: Sequence[Sequence[int]] | None,
                pairs: Sequence[tuple[int, int]]) -> tuple[tuple[int, int], ...]:
    """The bearing pairs of ``pairs`` whose bearings were recorded in different acquisitions (none when
    ``acquisitions`` is None or empty: all sampled together)."""
    if not acquisitions:
        return ()
    take = {b: i for i, g in enumerate(acquisitions) for b in g}
    return tuple((i, j) for i, j in pairs if i in take and j in take and take[i] != take[j])
