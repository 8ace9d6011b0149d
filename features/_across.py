"""Columns across bearings: how two bearings' static positions and 1X / 2X orbit sizes compare (``ACROSS_PAIRS``).

An offset coupling moves load from one bearing of a rotor to another and raises the coupling-end orbits against the
outboard ones; a ratio or a difference of the pair's columns divides out what the pair shares (speed, oil, the
plant's size). Built from the per-bearing columns, so it holds for a recording read in one take or in several (a
static position and an orbit's size do not depend on the phase reference), and is built again from them wherever
a row's per-bearing columns are changed (another clearance, another numbering, bearings left out).
"""
from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from . import _config as cfg
from ._names import FEATURE_NAMES, across_specs

__all__ = ["ACROSS_FEATURES", "across_bearings"]

#: the names of the columns across bearings, in the schema's order
ACROSS_FEATURES: tuple[str, ...] = tuple(s.name for s in across_specs(cfg.ACROSS_PAIRS))


@lru_cache(maxsize=16)
def _plan(names: tuple[str, ...]) -> tuple[tuple[int, str, int, int, float], ...]:
    """Per column across bearings present in ``names``: (its column, "ratio" or "difference", the two source
    columns — −1 where the source is not in ``names`` — and the ratio's floor)."""
    index = {n: i for i, n in enumerate(names)}
    out = []

    def add(name: str, kind: str, a: str, b: str, floor: float = 0.0) -> None:
        if name in index:
            out.append((index[name], kind, index.get(a, -1), index.get(b, -1), floor))

    for i, j in cfg.ACROSS_PAIRS:
        add(f"centre_ecc_b{i}_b{j}_ratio", "ratio", f"b{i}_centre_ecc_per_c", f"b{j}_centre_ecc_per_c",
            cfg.ACROSS_ECC_FLOOR)
        for d in ("x", "y"):
            add(f"dcentre_{d}_b{i}_b{j}_per_c", "difference", f"b{i}_centre_{d}_per_c", f"b{j}_centre_{d}_per_c")
        for k in (1, 2):
            add(f"{k}x_major_b{i}_b{j}_ratio", "ratio", f"b{i}_{k}x_major_um_pp", f"b{j}_{k}x_major_um_pp",
                cfg.ACROSS_MAJOR_FLOOR_UM)
    return tuple(out)


def across_bearings(values: np.ndarray, names: Sequence[str] = FEATURE_NAMES) -> None:
    """Write the columns across bearings of ``values`` (one row, or rows along the first axis, in the order of
    ``names``) from its per-bearing columns, in place; NaN where a column they need is NaN or not in ``names``.
    The ratio's denominator is floored (a journal at the bearing's centre, an orbit in the noise)."""
    with np.errstate(invalid="ignore"):
        for col, kind, a, b, floor in _plan(tuple(names)):
            if a < 0 or b < 0:
                values[..., col] = np.nan
            elif kind == "ratio":
                values[..., col] = values[..., a] / np.maximum(values[..., b], floor)    # NaN stays NaN
            else:
                values[..., col] = values[..., a] - values[..., b]
