"""Small dataset specs and file comparison for the dataset tests (tests/test_dataset_*.py)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

#: A tiny spec: short transient, few revolutions, 8 samples of the default plant family.
SMALL_SPEC = """\
# tiny spec for tests
[design]
method = "sobol"
n_samples = {n_samples}
seed = {seed}

[operating]
speed_rpm = {{min = 1500, max = 2100}}
misalignment = {{min = 0.0, max = 0.5}}
unbalance = {{min = 0.03, max = 0.08}}
unbalance_phase_rad = {{min = 0.0, max = 6.283185307179586}}
offset_angle_rad = {{min = 0.0, max = 6.283185307179586}}
mechanism = {{pin = 1, rigid = 1}}

[plant.perturb]
generator_mass_kg = 0.1
bearing_length_m = 0.05
asymmetry = 0.3

[measurement]
sample_rate_hz = {sample_rate_hz}
duration_revs = 4
snr_db = {{min = 25, max = 40}}
runout_1x_um = {{min = 0, max = 2}}
runout_2x_um = {{min = 0, max = 1}}
speed_fluctuation = 0.002

[simulation]
transient_revs = {transient_revs}
record_revs_min = 6
"""


def write_spec(path: Path, *, n_samples: int = 8, seed: int = 7, sample_rate_hz: float = 1024.0,
               transient_revs: int = 30) -> Path:
    path.write_text(SMALL_SPEC.format(n_samples=n_samples, seed=seed, sample_rate_hz=sample_rate_hz,
                                      transient_revs=transient_revs))
    return path


#: Datasets whose values legitimately differ between two runs of one spec (timing, resume history).
NOT_REPRODUCIBLE = {"diagnostics/wall_time_s", "resume_log"}


def differing_datasets(path_a: Path, path_b: Path) -> list[str]:
    """Names of datasets whose values differ (NaN == NaN), plus datasets present in only one file."""
    import h5py

    from rotordiag.simulator.dataset.store import open_dataset

    out: list[str] = []
    with open_dataset(path_a) as a, open_dataset(path_b) as b:
        names_a, names_b = [], []
        a.visititems(lambda n, o: names_a.append(n) if isinstance(o, h5py.Dataset) else None)
        b.visititems(lambda n, o: names_b.append(n) if isinstance(o, h5py.Dataset) else None)
        out += sorted(set(names_a) ^ set(names_b))
        for name in sorted(set(names_a) & set(names_b)):
            if name in NOT_REPRODUCIBLE:
                continue
            x, y = a[name][...], b[name][...]
            same = x.shape == y.shape and (
                np.array_equal(x, y, equal_nan=True) if x.dtype.kind == "f" else np.array_equal(x, y))
            if not same:
                out.append(name)
    return out
