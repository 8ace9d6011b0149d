"""Severity bands: how a misalignment Δ = δ/c maps to a severity class.

The defaults follow issue 5 and MODEL.md section 11::

    aligned   Δ < 0.05
    slight    0.05 ≤ Δ < 0.15
    moderate  0.15 ≤ Δ < 0.35
    severe    Δ ≥ 0.35

Edges are lower-inclusive: Δ exactly on an edge belongs to the band above it.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

DEFAULT_EDGES: tuple[float, ...] = (0.05, 0.15, 0.35)
DEFAULT_NAMES: tuple[str, ...] = ("aligned", "slight", "moderate", "severe")


@dataclass(frozen=True)
class SeverityBands:
    """Ordered misalignment bands.

    Parameters
    ----------
    edges : tuple of float
        Strictly increasing interior edges in Δ = δ/c (non-dimensional), all > 0.
    names : tuple of str
        One unique name per band, ``len(edges) + 1`` of them, from the smallest Δ up.
        The first band is the "no fault" band used for binary detection metrics.
    """

    edges: tuple[float, ...] = DEFAULT_EDGES
    names: tuple[str, ...] = DEFAULT_NAMES

    def __post_init__(self) -> None:
        edges = tuple(float(e) for e in self.edges)
        names = tuple(str(n) for n in self.names)
        object.__setattr__(self, "edges", edges)
        object.__setattr__(self, "names", names)
        if len(edges) < 1:
            raise ValueError("bands.edges: need at least one edge (two bands)")
        if not all(np.isfinite(edges)) or edges[0] <= 0:
            raise ValueError(f"bands.edges: must be finite and > 0, got {list(edges)}")
        if any(b <= a for a, b in zip(edges, edges[1:])):
            raise ValueError(f"bands.edges: must be strictly increasing, got {list(edges)}")
        if len(names) != len(edges) + 1:
            raise ValueError(
                f"bands.names: need len(edges) + 1 = {len(edges) + 1} names, got {len(names)}"
            )
        if len(set(names)) != len(names) or any(not n for n in names):
            raise ValueError(f"bands.names: must be unique and non-empty, got {list(names)}")

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> SeverityBands:
        """Build from ``{"edges": [...], "names": [...]}`` (missing keys take the defaults)."""
        if not d:
            return cls()
        unknown = set(d) - {"edges", "names"}
        if unknown:
            raise ValueError(f"bands: unknown keys {sorted(unknown)}; allowed: edges, names")
        return cls(edges=tuple(d.get("edges", DEFAULT_EDGES)), names=tuple(d.get("names", DEFAULT_NAMES)))

    def to_dict(self) -> dict[str, list]:
        """JSON-able form, the inverse of :meth:`from_dict`."""
        return {"edges": list(self.edges), "names": list(self.names)}

    @property
    def n_bands(self) -> int:
        return len(self.names)

    def index(self, misalignment: Sequence[float] | np.ndarray) -> np.ndarray:
        """Band index (0 = first band) of each Δ.

        Raises
        ------
        ValueError
            If any Δ is negative or not finite.
        """
        delta = np.asarray(misalignment, dtype=float)
        if not np.all(np.isfinite(delta)) or np.any(delta < 0):
            raise ValueError("misalignment: every Δ must be finite and ≥ 0")
        return np.searchsorted(np.asarray(self.edges), delta, side="right").astype(np.int64)

    def label(self, misalignment: Sequence[float] | np.ndarray) -> np.ndarray:
        """Band name of each Δ (array of str)."""
        return np.asarray(self.names, dtype=object)[self.index(misalignment)]

    def representative(self, upper: float | None = None) -> np.ndarray:
        """One Δ per band, used to turn a class into a Δ estimate (baselines).

        Interior bands give their mid-point; the first band gives half its upper edge;
        the open last band gives the mid-point between its edge and ``upper``
        (default: 1.5 × the last edge).
        """
        e = np.asarray(self.edges)
        top = float(upper) if upper is not None and upper > e[-1] else 1.5 * e[-1]
        lows = np.concatenate([[0.0], e])
        highs = np.concatenate([e, [top]])
        return 0.5 * (lows + highs)
