"""Nested configuration tables (TOML / JSON objects): overriding some keys of a default."""
from __future__ import annotations

import copy
from collections.abc import Collection, Mapping
from typing import Any

__all__ = ["deep_merge"]


def deep_merge(base: Mapping[str, Any], override: Mapping[str, Any], *,
               whole: Collection[str] = ()) -> dict[str, Any]:
    """``base`` with ``override`` laid over it, table by table.

    A key whose value is a table in both is merged recursively; any other value of ``override``
    (a number, a string, a list — lists of tables too — or a table under a key named in ``whole``)
    replaces the one of ``base``. Neither argument is modified; the result shares nothing with them.

    Examples
    --------
    >>> deep_merge({"classifier": {"max_iter": 150, "min_samples_leaf": 20}, "seed": 0},
    ...            {"classifier": {"max_iter": 30}})
    {'classifier': {'max_iter': 30, 'min_samples_leaf': 20}, 'seed': 0}
    """
    out = copy.deepcopy(dict(base))
    for key, value in override.items():
        if isinstance(value, Mapping) and isinstance(out.get(key), Mapping) and key not in whole:
            out[key] = deep_merge(out[key], value, whole=whole)
        else:
            out[key] = copy.deepcopy(value)
    return out
