"""The catalogue of reason and sanity codes (rotordiag.core.reasons): every code produced is in it, it is the
schema's enum and the reason table of docs/pipeline.md."""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from rotordiag.core.reasons import CATALOGUE, FAIL, INCONCLUSIVE, SANITY, UNCERTAIN, WARN, markdown_table, require_code

ROOT = Path(__file__).resolve().parents[1]
CONSTRUCTORS = {"Reason", "SanityFinding"}


def _produced_codes() -> tuple[set[str], set[str]]:
    """Codes written as the first argument of a ``Reason(...)`` / ``SanityFinding(...)`` call in the packages: the
    literal ones, and the patterns of f-strings (``common_mode_{k}x`` → ``common_mode_.x``)."""
    literal, patterns = set(), set()
    for path in sorted(p for d in ("features", "models", "service", "rotordiag") for p in (ROOT / d).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in CONSTRUCTORS
                    and node.args):
                continue
            first = node.args[0]
            if isinstance(first, ast.Constant) and isinstance(first.value, str):
                literal.add(first.value)
            elif isinstance(first, ast.JoinedStr):
                patterns.add("".join(re.escape(v.value) if isinstance(v, ast.Constant) else ".+"
                                     for v in first.values))
    return literal, patterns


def test_every_code_written_in_the_packages_is_in_the_catalogue_and_every_entry_is_produced():
    literal, patterns = _produced_codes()
    assert len(literal) >= 30 and patterns           # the scan found the constructors (it can fail)
    assert literal - set(CATALOGUE) == set()
    for pat in patterns:
        assert any(re.fullmatch(pat, c) for c in CATALOGUE), pat
    produced = literal | {c for c in CATALOGUE for pat in patterns if re.fullmatch(pat, c)}
    # a sanity finding's code is passed on as a reason's (models.status), so all of them are produced
    assert set(CATALOGUE) - produced == set()


def test_a_code_or_status_the_catalogue_lacks_is_refused():
    from rotordiag.features import SanityFinding
    from rotordiag.models.status import Reason

    with pytest.raises(ValueError, match="not in the catalogue"):
        Reason("made_up_code", UNCERTAIN, "x")
    with pytest.raises(ValueError, match="not in the catalogue"):
        SanityFinding("made_up_code", WARN, "x")
    with pytest.raises(ValueError, match="allows"):
        Reason("low_probability", INCONCLUSIVE, "x")            # the catalogue: uncertain only
    with pytest.raises(ValueError, match="allows"):
        SanityFinding("zero_channel", WARN, "x")                # a channel of zeros always fails
    assert Reason("ood", INCONCLUSIVE, "x").code == "ood"
    # the answer carries the catalogue's "what to do" beside the recording's own message (the web page shows both)
    assert Reason("ood", INCONCLUSIVE, "x").to_dict() == {"code": "ood", "status": INCONCLUSIVE, "message": "x",
                                                          "action": CATALOGUE["ood"].action}
    require_code("no_sync_signal", FAIL)
    require_code("no_sync_signal", WARN)


def test_entries_are_complete():
    assert len(CATALOGUE) == 42     # the 38 codes of issue 43 + startup_changed (46) + family_untrained,
    #                                 signature_contradicts_call, attitude_outside_training (48)
    for code, e in CATALOGUE.items():
        assert re.fullmatch(r"[a-z0-9_]+", code)
        assert e.code == code and e.meaning and e.action
        assert e.statuses and set(e.statuses) <= {UNCERTAIN, INCONCLUSIVE}
    assert sum(e.kind == SANITY for e in CATALOGUE.values()) == 14


def test_the_schema_enum_is_the_catalogue_and_a_foreign_code_is_refused():
    from pydantic import ValidationError

    from rotordiag.service.schemas import DiagnoseResponse, ReasonOut

    schema = DiagnoseResponse.model_json_schema()
    assert schema["$defs"]["ReasonOut"]["properties"]["code"]["enum"] == list(CATALOGUE)
    assert ReasonOut(code="ood", status="uncertain", message="m").code == "ood"
    with pytest.raises(ValidationError):
        ReasonOut(code="made_up_code", status="uncertain", message="m")


def test_docs_pipeline_holds_the_generated_reason_table():
    page = (ROOT / "docs" / "pipeline.md").read_text(encoding="utf-8")
    assert markdown_table() in page, "regenerate the table: python -c 'from rotordiag.core.reasons import " \
                                     "markdown_table; print(markdown_table())'"
