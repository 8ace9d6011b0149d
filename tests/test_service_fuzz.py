"""Property-based fuzz pass over the OpenAPI schema (schemathesis): no request produces a 5xx, every
answer has a documented status code and matches its documented schema.

Every operation is called with schema-conforming and schema-violating inputs (bodies in each documented
content type, query and path parameters), with a valid API key so the write endpoints' validation is
reached too. Jobs that the fuzzer manages to create are recorded but not run (the fuzz checks the HTTP
layer; jobs are covered by tests/test_service_jobs.py).

    .venv/bin/pytest tests/test_service_fuzz.py -q                       # default: 15 examples per operation
    ROTORDIAG_FUZZ_EXAMPLES=500 .venv/bin/pytest tests/test_service_fuzz.py -q   # a deeper pass
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest

schemathesis = pytest.importorskip("schemathesis")
from hypothesis import HealthCheck, settings  # noqa: E402
from schemathesis.checks import not_a_server_error, response_schema_conformance, status_code_conformance  # noqa: E402,E501

from rotordiag.service.main import create_app  # noqa: E402
from tests.service_util import API_KEY, make_settings, shipped_or_tiny_registry  # noqa: E402

_TMP = Path(tempfile.mkdtemp(prefix="rotordiag-fuzz-"))
N_EXAMPLES = int(os.environ.get("ROTORDIAG_FUZZ_EXAMPLES", "15"))
APP = create_app(make_settings(_TMP, max_body_bytes=4 * 1024 * 1024, shipped_registry_dir=shipped_or_tiny_registry()))
CREATED_JOBS: list[str] = []


def _record_only(manager) -> None:
    """Job kinds that record the job instead of simulating (schemathesis runs the app's lifespan itself,
    so the stand-ins are installed where the job manager looks its work functions up)."""
    for kind in ("dataset", "retrain"):
        manager.register(kind, lambda params, ctx, _k=kind: CREATED_JOBS.append(_k) or {})


@pytest.fixture(scope="module", autouse=True)
def _no_real_jobs():
    mp = pytest.MonkeyPatch()
    mp.setattr("rotordiag.service.work.register_all", _record_only)
    yield
    mp.undo()


schema = schemathesis.openapi.from_asgi("/openapi.json", APP)


# One explicit parametrization so that every operation's test has its own node id: pytest 9.2 builds a
# node id from the function's name and its callspec only, and schemathesis's per-operation items (named
# "test_no_server_errors[POST /diagnose]") carry no callspec of their own, so without this all 15 items
# share one id, and pytest-xdist (keyed by node id) runs one of them. test_every_operation_has_its_own_id.
@schema.parametrize()
@pytest.mark.parametrize("headers", [{"X-API-Key": API_KEY}], ids=["with key"])
@settings(max_examples=N_EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large,
                                 HealthCheck.function_scoped_fixture])
def test_no_server_errors(case, headers):
    # a generous read timeout (schemathesis's default is 10 s): a train simulation on a loaded 2-core machine
    # takes longer, and a slow answer is not what this test is about
    case.call_and_validate(headers=headers, timeout=180, checks=[not_a_server_error, response_schema_conformance,
                                                                 status_code_conformance])


def test_every_operation_has_its_own_id(request):
    """One fuzz item per operation, each with its own node id (pytest-xdist schedules by node id)."""
    fuzz = [item for item in request.session.items if item.name.startswith("test_no_server_errors[")]
    if not fuzz:
        pytest.skip("the fuzz items were not collected in this run (-k or a node id selected this test)")
    ids = sorted(item.nodeid for item in fuzz)
    assert len(set(ids)) == len(fuzz) == sum(1 for _ in schema.get_all_operations()), ids
