"""rotordiag.simulator's lazily exported functions stay functions when their same-named submodules are
imported first (a fresh interpreter each, since the import order is the point)."""
from __future__ import annotations

import subprocess
import sys

import pytest


@pytest.mark.parametrize("name", ["simulate", "modal"])
def test_importing_the_submodule_first_keeps_the_function(name):
    code = (f"import rotordiag.simulator.{name}\n"
            "import rotordiag.simulator as s, sys, types\n"
            f"assert callable(s.{name}) and not isinstance(s.{name}, types.ModuleType), type(s.{name})\n"
            f"assert isinstance(sys.modules['rotordiag.simulator.{name}'], types.ModuleType)\n"
            f"from rotordiag.simulator.{name} import {name} as f\n"
            f"assert f is s.{name}\n")
    subprocess.run([sys.executable, "-c", code], check=True)
