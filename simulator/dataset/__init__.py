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
h5py, scipy and Dask are imported inside the functions that need them.
"""
from __future__ import annotations

# explicit imports (not lazy): the function names ``generate`` and ``merge`` are also
# submodule names, and an eager ``from .x import x`` keeps the package attribute the function
from .design import build_design
from .generate import GenerateSummary, generate
from .info import summarize
from .merge import merge
from .read import DatasetReader
from .spec import SpecError, load_spec, parse_spec
from .store import StoreError, open_dataset, repair_file

__all__ = ["load_spec", "parse_spec", "SpecError", "build_design", "generate", "GenerateSummary",
           "DatasetReader", "summarize", "merge", "repair_file", "open_dataset", "StoreError"]
