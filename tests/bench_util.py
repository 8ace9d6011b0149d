"""The benchmark scripts as modules for the tests (``benchmarks/`` is a folder of scripts, not a package)."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

from rotordiag.simulator.train import Train

#: the checkout's benchmarks/ folder
BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def load_benchmark(name: str) -> ModuleType:
    """``benchmarks/<name>.py`` as the module ``name``, executed once per process.

    The module is registered in ``sys.modules`` before it runs: its dataclasses look their module up
    there, and every later call (any test file) gets the same module object instead of a second copy."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, BENCH / f"{name}.py")
    if spec is None or spec.loader is None:
        raise ImportError(f"no benchmark script {BENCH / f'{name}.py'}")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    try:
        spec.loader.exec_module(mod)
    except BaseException:
        del sys.modules[name]
        raise
    return mod


def ross_reference() -> ModuleType:
    """``benchmarks/train_ross_reference.py``: the 40-node generator–exciter train shared with ROSS."""
    return load_benchmark("train_ross_reference")


def bench_machine() -> Train:
    """The bench machine of ``benchmarks/bench_train.py``: the reference train on four plain oil films, with
    gravity and a two-pole generator body (``plain_train``)."""
    return load_benchmark("bench_train").plain_train(ross_reference())
