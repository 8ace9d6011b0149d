"""Sampling design: spec → one operating point and one plant per sample, and per-sample seeds.

Seeds
-----
Everything derives from ``design.seed`` (the master seed) through
:class:`numpy.random.SeedSequence` with fixed spawn keys:

* the design's scrambling / permutation: ``SeedSequence(seed, spawn_key=(0,))``;
* sample ``i``'s measurement draws (noise, runout, start angle, speed
  fluctuation phase): ``default_rng(sample_seed(seed, i))`` with
  ``sample_seed(seed, i) = SeedSequence(seed, spawn_key=(1, i)).generate_state(1, uint64)[0]``,
  a 64-bit integer stored with the sample, so one sample can be reproduced
  alone and does not depend on the number of samples or on execution order.

Designs
-------
``grid``  full factorial over every list / ``{min, max, n}`` range (first
          variable varies slowest, in the order of :data:`VARIABLES`; then
          ``mechanism``, then the base plant of a machine family).
``sobol`` scrambled Sobol points (``scipy.stats.qmc.Sobol``; powers of two keep
          its balance properties).
``lhs``   Latin hypercube (``scipy.stats.qmc.LatinHypercube``).
For the random designs each non-constant quantity is one dimension of the unit
hypercube: a range maps linearly onto ``[min, max]``, a list onto equally
likely levels, mechanism weights onto a weighted choice, and each perturbed
plant value (each bearing separately for per-bearing values) onto
``value × (1 + u)`` with ``u`` uniform in ``[−r, r]``.

Machine families (``plant.presets`` / ``plant.shaftlines``) add, after those,
one dimension for the base plant (a weighted choice; a level on a grid) and one
per ``plant.scale`` field (``value × f``, ``log f`` uniform in
``[log min, log max]``, all bearings together). A spec without them has the
same dimensions, hence the same samples, as before they existed. Each sample
records its base plant's label (:attr:`SampleParams.plant_source`) and its full
plant values.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from .spec import Range, ResolvedSpec, SpecError

__all__ = ["VARIABLES", "Design", "SampleParams", "build_design", "sample_seed"]

#: Operating quantities of a sample, in design order.
VARIABLES: tuple[str, ...] = (
    "speed_rpm", "misalignment", "unbalance", "unbalance_phase_rad", "exciter_unbalance",
    "exciter_unbalance_phase_rad", "offset_angle_rad", "coupling_phase_rad",
    # appended last: a spec that leaves it constant keeps its design (no new dimension before the others)
    "angular_misalignment_mrad",
)


def sample_seed(master_seed: int, index: int) -> int:
    """64-bit seed of sample ``index`` (see the module docstring)."""
    ss = np.random.SeedSequence(int(master_seed), spawn_key=(1, int(index)))
    return int(ss.generate_state(1, np.uint64)[0])


@dataclass(frozen=True)
class SampleParams:
    """Everything that defines one sample's physics (the design's output)."""

    index: int
    plant: dict[str, Any]
    speed_rpm: float
    misalignment: float
    unbalance: float
    unbalance_phase_rad: float
    exciter_unbalance: float
    exciter_unbalance_phase_rad: float
    offset_angle_rad: float
    mechanism: str
    sample_seed: int
    coupling_phase_rad: float = 0.0
    plant_source: str = "default"     # label of the base plant (ResolvedSpec.sources)
    angular_misalignment_mrad: float = 0.0  # applied to offset/flexible samples only (worker)


class Design:
    """The design of a resolved spec: ``len(design)`` samples, ``design[i]`` → :class:`SampleParams`."""

    def __init__(self, resolved: ResolvedSpec):
        self.resolved = resolved
        spec = resolved.spec
        self.master_seed = spec.design.seed
        self.method = spec.design.method
        self._bases = {label: p.to_dict() for label, p in resolved.sources.items()}
        self._base = next(iter(self._bases.values()))
        self._source_weights = resolved.source_weights
        self._scale = [(name, r.min, r.max) for name, r in spec.plant.scale.items()]
        op = spec.operating
        self._values = {name: getattr(op, name) for name in VARIABLES}
        if spec.transient is not None:  # a run-up's speed is its profile's; the sample carries the top speed
            self._values["speed_rpm"] = spec.speed_bounds_rpm[1]
        self._mechanism: str | list[str] | dict[str, float] = op.mechanism
        # perturbation dimensions: (field, element index or None, half-width)
        self._perturb: list[tuple[str, int | None, float]] = []
        for name in spec.plant.perturbable:
            r = spec.plant.perturb.get(name, 0.0)
            if r <= 0:
                continue
            base = self._base[name]
            if isinstance(base, list):
                self._perturb.extend((name, k, r) for k in range(len(base)))
            else:
                self._perturb.append((name, None, r))
        if self.method == "grid":
            self._levels: list[list[Any]] = [list(self._grid_levels(self._values[n])) for n in VARIABLES]
            mech = self._mechanism
            self._levels.append([mech] if isinstance(mech, str) else list(mech))
            self._levels.append(list(self._bases))
            self._shape = tuple(len(v) for v in self._levels)
            n = math.prod(self._shape)          # exact: np.prod wraps around in int64 on a huge grid
            if spec.design.n_samples is not None and spec.design.n_samples != n:
                raise SpecError(f"invalid dataset spec:\n  design.n_samples = {spec.design.n_samples} but the grid "
                                f"has {n} points ({' × '.join(map(str, self._shape))}); remove n_samples or fix it")
            self.n_samples = n
            self._u: np.ndarray | None = None
        else:
            assert spec.design.n_samples is not None  # required for sampled designs (validated)
            self.n_samples = int(spec.design.n_samples)
            self._dims = [n for n in VARIABLES if self._is_variable(self._values[n])]
            self._mech_dim = not isinstance(self._mechanism, str) and len(self._mechanism) > 1
            self._source_dim = len(self._bases) > 1
            d = len(self._dims) + int(self._mech_dim) + len(self._perturb) + int(self._source_dim) + len(self._scale)
            self._u = self._unit_points(d)

    # ------------------------------------------------------------------ helpers
    @staticmethod
    def _is_variable(v: Any) -> bool:
        if isinstance(v, Range):
            return v.max > v.min
        return isinstance(v, list) and len(v) > 1

    @staticmethod
    def _grid_levels(v: Any) -> list[float]:
        if isinstance(v, Range):
            if v.max == v.min or v.n in (None, 1):
                return [v.min] if v.max == v.min else [0.5 * (v.min + v.max)]
            return list(np.linspace(v.min, v.max, v.n))
        if isinstance(v, list):
            return list(v)
        return [float(v)]

    def _unit_points(self, d: int) -> np.ndarray:
        from scipy.stats import qmc

        n = self.n_samples
        if d == 0:
            return np.zeros((n, 0))
        rng = np.random.default_rng(np.random.SeedSequence(self.master_seed, spawn_key=(0,)))
        if self.method == "sobol":
            engine = qmc.Sobol(d, scramble=True, rng=rng)
            with warnings.catch_warnings():  # not a power of two: documented, still a valid design
                warnings.simplefilter("ignore", UserWarning)
                return engine.random(n)
        return qmc.LatinHypercube(d, rng=rng).random(n)

    @staticmethod
    def _map(v: Any, u: float) -> float:
        if isinstance(v, Range):
            return float(v.min + float(u) * (v.max - v.min))
        k = min(int(math.floor(u * len(v))), len(v) - 1)
        return float(v[k])

    def _pick_mechanism(self, u: float) -> str:
        m = self._mechanism
        if isinstance(m, list):
            return m[min(int(math.floor(u * len(m))), len(m) - 1)]
        if isinstance(m, str):
            return m
        return self._pick_weighted(m, u, sort=True)  # fixed order: names sorted

    @staticmethod
    def _pick_weighted(weights: dict[str, float], u: float, *, sort: bool) -> str:
        """The member whose share of [0, 1) (in name order, or the given order) holds ``u``."""
        names = sorted(weights) if sort else list(weights)
        w = np.array([float(weights[k]) for k in names], dtype=float)
        edges = np.cumsum(w / w.sum())
        return names[min(int(np.searchsorted(edges, u, side="right")), len(names) - 1)]

    @staticmethod
    def _constant(v: Any) -> float:
        if isinstance(v, Range):
            return float(v.min)
        if isinstance(v, list):
            return float(v[0])
        return float(v)

    # ------------------------------------------------------------------ access
    def __len__(self) -> int:
        return self.n_samples

    def __getitem__(self, index: int) -> SampleParams:
        i = int(index)
        if not 0 <= i < self.n_samples:
            raise IndexError(f"sample index {i} out of range [0, {self.n_samples})")
        source = next(iter(self._bases))
        if self.method == "grid":
            pos = np.unravel_index(i, self._shape)
            vals = {n: float(self._levels[k][pos[k]]) for k, n in enumerate(VARIABLES)}
            mechanism = self._levels[-2][pos[-2]]
            source = self._levels[-1][pos[-1]]
            plant = dict(self._bases[source])
        else:
            assert self._u is not None
            u = self._u[i]
            vals = {}
            j = 0
            for n in VARIABLES:
                v = self._values[n]
                if n in self._dims:
                    vals[n] = self._map(v, u[j])
                    j += 1
                else:
                    vals[n] = self._constant(v)
            if self._mech_dim:
                mechanism = self._pick_mechanism(u[j])
                j += 1
            else:
                m = self._mechanism
                mechanism = m if isinstance(m, str) else (m[0] if isinstance(m, list) else next(iter(m)))
            u_perturb = u[j:j + len(self._perturb)]
            j += len(self._perturb)
            if self._source_dim:
                source = self._pick_weighted(self._source_weights, u[j], sort=False)
                j += 1
            plant = dict(self._bases[source])
            for (name, k, r), uk in zip(self._perturb, u_perturb):
                factor = 1.0 + r * (2.0 * float(uk) - 1.0)
                if k is None:
                    plant[name] = float(plant[name]) * factor
                else:
                    seq = list(plant[name])
                    seq[k] = float(seq[k]) * factor
                    plant[name] = seq
            for name, lo, hi in self._scale:
                factor = float(math.exp(math.log(lo) + float(u[j]) * (math.log(hi) - math.log(lo))))
                j += 1
                v = plant[name]
                plant[name] = [float(x) * factor for x in v] if isinstance(v, list) else float(v) * factor
        return SampleParams(index=i, plant=plant, mechanism=mechanism,
                            sample_seed=sample_seed(self.master_seed, i), plant_source=source, **vals)


def build_design(resolved: ResolvedSpec) -> Design:
    """The :class:`Design` of a resolved spec (raises :class:`SpecError` for an inconsistent grid)."""
    return Design(resolved)
