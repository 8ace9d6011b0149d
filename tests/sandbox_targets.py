"""Functions run in the sandbox child by tests/test_features_sandbox.py (importable by name)."""
from __future__ import annotations

import os
import time


def add(a: int, b: int = 0) -> int:
    return a + b


def allocate_forever() -> None:
    hoard = []
    while True:
        hoard.append(bytearray(64 * 2**20))


def sleep_s(seconds: float) -> None:
    time.sleep(seconds)


def abort() -> None:
    os.abort()


def refuse(message: str) -> None:
    raise ValueError(message)


def key_error() -> None:
    raise KeyError("inner")
