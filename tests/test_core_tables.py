"""rotordiag.core.tables.deep_merge: overrides lay over defaults table by table, and touch neither."""
from __future__ import annotations

from rotordiag.core.tables import deep_merge


def test_tables_merge_and_other_values_replace():
    base = {"seed": 0, "classifier": {"max_iter": 150, "min_samples_leaf": 20},
            "features": {"monotonic_increasing": ["a", "b"]}, "augment": {"bearing_sets": [{"bearings": [1, 2]}]}}
    got = deep_merge(base, {"classifier": {"max_iter": 30}, "features": {"monotonic_increasing": []},
                            "augment": {"bearing_sets": [{"bearings": [2]}]}, "bands": {"edges": [0.1]}})
    assert got == {"seed": 0, "classifier": {"max_iter": 30, "min_samples_leaf": 20},
                   "features": {"monotonic_increasing": []}, "augment": {"bearing_sets": [{"bearings": [2]}]},
                   "bands": {"edges": [0.1]}}


def test_a_whole_table_replaces_and_nothing_is_shared():
    base = {"operating": {"mechanism": {"pin": 1.0, "rigid": 1.0}, "speed_rpm": {"min": 1200, "max": 2200}}}
    over = {"operating": {"mechanism": {"offset": 1.0}, "speed_rpm": {"max": 3000}}}
    got = deep_merge(base, over, whole=("mechanism",))
    assert got["operating"] == {"mechanism": {"offset": 1.0}, "speed_rpm": {"min": 1200, "max": 3000}}
    got["operating"]["speed_rpm"]["min"] = 0
    got["operating"]["mechanism"]["offset"] = 0.0
    assert base["operating"]["speed_rpm"]["min"] == 1200 and over["operating"]["mechanism"] == {"offset": 1.0}
