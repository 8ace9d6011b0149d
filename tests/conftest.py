"""Test-session guards.

The four layers are imported as ``rotordiag.simulator``, ``rotordiag.features``,
``rotordiag.models`` and ``rotordiag.service``. pytest runs in ``importlib`` mode (no
``sys.path`` insertion), and this finder makes a stale bare import such as
``import models`` fail loudly instead of silently importing a second copy of the
package from the checkout's top-level folder. The checkout root is appended (last) to
``sys.path`` only so that worker processes (Dask, multiprocessing spawn) can import test
helpers as ``tests.<module>``; static bare imports anywhere in the tree are refused by
``tests/test_architecture.py``.
"""
from __future__ import annotations

import sys
from importlib.abc import MetaPathFinder
from pathlib import Path

_BARE_NAMES = frozenset({"simulator", "features", "models", "service"})


class _BareImportBlocker(MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):  # noqa: ANN001 - importlib protocol
        if fullname.split(".", 1)[0] in _BARE_NAMES:
            raise ImportError(
                f"bare import {fullname!r}: import it as 'rotordiag.{fullname}' "
                "(the top-level folders are installed under the rotordiag package)"
            )
        return None


_ROOT = str(Path(__file__).resolve().parents[1])
if _ROOT not in sys.path:
    sys.path.append(_ROOT)
if not any(isinstance(f, _BareImportBlocker) for f in sys.meta_path):
    sys.meta_path.insert(0, _BareImportBlocker())
