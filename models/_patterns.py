"""Feature names against the glob patterns of train.toml's feature lists (``b?_[xy]_2x_1x_ratio``), and the index of a
model's feature names."""
from __future__ import annotations

import fnmatch
import re
from collections.abc import Mapping, Sequence
from functools import lru_cache

import numpy as np

__all__ = ["name_mask", "pattern_value", "require_matches", "bearing_feature", "name_index"]

_PER_BEARING = re.compile(r"^b(\d+)_(.+)$")
_BEARING_PAIR = re.compile(r"^(.+)_b(\d+)_b(\d+)_(.+)$")


def _matches(name: str, patterns: Sequence[str]) -> bool:
    return any(fnmatch.fnmatchcase(name, p) for p in patterns)


def name_mask(names: Sequence[str], patterns: Sequence[str]) -> np.ndarray:
    """Boolean mask over ``names``: True where a name matches any of the glob ``patterns`` (case-sensitive)."""
    return np.array([_matches(n, patterns) for n in names], dtype=bool)


def pattern_value(name: str, table: Mapping[str, float], default: float) -> float:
    """The value of the first pattern of ``table`` (in its order) that ``name`` matches, else ``default``."""
    return next((float(v) for p, v in table.items() if fnmatch.fnmatchcase(name, p)), default)


def require_matches(key: str, patterns: Sequence[str], names: Sequence[str], hint: str = "") -> None:
    """Raise ``ValueError`` naming ``key`` when one of ``patterns`` matches none of ``names``."""
    unmatched = [p for p in patterns if not any(fnmatch.fnmatchcase(n, p) for n in names)]
    if unmatched:
        raise ValueError(f"{key}: pattern(s) {unmatched} match no feature name{hint}")


def bearing_feature(name: str) -> tuple[str, tuple[int, ...], str] | None:
    """The bearings a feature reads, with the name around them: ``("", (2,), "1x_major_um_pp")`` for
    ``b2_1x_major_um_pp``, ``("dphase_1x", (2, 3), "x_deg")`` for ``dphase_1x_b2_b3_x_deg`` (a phase difference
    between two bearings); None for a feature of no bearing (the speed, the motion type)."""
    if m := _PER_BEARING.match(name):
        return "", (int(m.group(1)),), m.group(2)
    if m := _BEARING_PAIR.match(name):
        return m.group(1), (int(m.group(2)), int(m.group(3))), m.group(4)
    return None


def name_index(names: Sequence[str]) -> Mapping[str, int]:
    """``{name: column}`` of a model's feature names, made once per tuple of names (a verdict looks columns up in
    several places; the dict of 292 names cost 0.1–0.3 ms each time). Read it, never change it."""
    return _name_index(names if isinstance(names, tuple) else tuple(names))


@lru_cache(maxsize=16)
def _name_index(names: tuple[str, ...]) -> dict[str, int]:
    return {n: i for i, n in enumerate(names)}
