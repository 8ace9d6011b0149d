"""rotordiag: coupling-misalignment diagnosis for generator-exciter rotors.

Sub-packages, lowest layer first: :mod:`rotordiag.core` (shared conventions),
:mod:`rotordiag.simulator`, :mod:`rotordiag.features`, :mod:`rotordiag.models`,
:mod:`rotordiag.service`; :mod:`rotordiag.cli` is the command line. In the source
repository the four layers live in the top-level folders ``simulator/``,
``features/``, ``models/`` and ``service/`` (mapped by ``pyproject.toml``).
"""
from __future__ import annotations

from rotordiag.core.version import __version__, code_version

__all__ = ["__version__", "code_version"]
