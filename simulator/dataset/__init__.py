"""Labelled datasets: TOML sweep spec → simulator on Dask → one HDF5 file (issue 4).

Public API
----------
load_spec(path) / parse_spec(text) -> ResolvedSpec
    Validate a spec (:mod:`simulator.dataset.spec`); ``SpecError`` names the key to fix.
build_design(resolved) -> Design
    Grid / Sobol / LHS design; ``design[i]`` is sample i's operating point and plant.
generate(spec, out, *, n_workers=None, scheduler_address=None, client=None, ...) -> GenerateSummary
    Run (or resume) a dataset into HDF5; crash-safe.
DatasetReader(path)
    Read labels and waveforms of a dataset file.
summarize(path), merge(inputs, out), repair_file(path)
    What ``rotordiag dataset info | merge | repair`` do.

The file layout is documented in ``docs/dataset-format.md``; the user guide is ``docs/datasets.md``.
Heavy modules are imported lazily, so ``import simulator.dataset`` stays cheap.
"""
from __future__ import annotations

from typing import Any

__all__ = ["load_spec", "parse_spec", "SpecError", "build_design", "generate", "GenerateSummary",
           "DatasetReader", "summarize", "merge", "repair_file", "open_dataset", "StoreError"]

_WHERE = {
    "load_spec": "spec", "parse_spec": "spec", "SpecError": "spec", "build_design": "design",
    "generate": "generate", "GenerateSummary": "generate", "DatasetReader": "read", "summarize": "info",
    "merge": "merge", "repair_file": "store", "open_dataset": "store", "StoreError": "store",
}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        import importlib

        return getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
