"""Pieces every layer shares, with no dependency on any other part of rotordiag.

- :mod:`rotordiag.core.bands` — severity bands (Δ = δ/c → aligned/slight/moderate/severe)
- :mod:`rotordiag.core.units` — displacement units and their conversion to µm
- :mod:`rotordiag.core.conventions` — bearing numbering and probe projection
- :mod:`rotordiag.core.numerics` — numba options and default integration tolerances
- :mod:`rotordiag.core.version` — the code version recorded in datasets and model cards

Layers (enforced by ``tests/test_architecture.py``): core < simulator < features <
models < service < cli.
"""
