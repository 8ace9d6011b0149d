"""``rotordiag.features.sandbox``: memory, time and crash containment of untrusted-file parsers."""
from __future__ import annotations

import time

import pytest

from rotordiag.features.sandbox import SandboxError, call_isolated

from . import sandbox_targets as t

LIMITS = dict(memory_bytes=256 * 2**20, timeout_s=20.0, what="the test file")


def test_result_and_keyword_arguments_come_back():
    assert call_isolated(t.add, 2, kwargs={"b": 3}, **LIMITS) == 5


def test_runaway_allocation_is_stopped_by_the_memory_limit():
    t0 = time.monotonic()
    with pytest.raises(SandboxError, match="more than 256 MiB"):
        call_isolated(t.allocate_forever, **LIMITS)
    assert time.monotonic() - t0 < 15


def test_stall_is_stopped_by_the_time_limit():
    t0 = time.monotonic()
    with pytest.raises(SandboxError, match="longer than 0.5 s"):
        call_isolated(t.sleep_s, 60, memory_bytes=2**28, timeout_s=0.5, what="x")
    assert time.monotonic() - t0 < 10


def test_a_crash_in_native_code_is_an_error_not_a_dead_caller():
    with pytest.raises(SandboxError, match="crashed"):
        call_isolated(t.abort, **LIMITS)


def test_the_parsers_own_value_error_passes_unchanged_and_others_are_wrapped():
    with pytest.raises(ValueError, match="^say what to fix$") as info:
        call_isolated(t.refuse, "say what to fix", **LIMITS)
    assert not isinstance(info.value, SandboxError)
    with pytest.raises(SandboxError, match="KeyError"):
        call_isolated(t.key_error, **LIMITS)


def test_bad_limits_are_refused():
    with pytest.raises(ValueError, match="positive"):
        call_isolated(t.add, 1, memory_bytes=0, timeout_s=1.0, what="x")
