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
        Reason("made_up_code", UNCERTAIN)
    with pytest.raises(ValueError, match="not in the catalogue"):
        SanityFinding("made_up_code", WARN)
    with pytest.raises(ValueError, match="allows"):
        Reason("low_probability", INCONCLUSIVE, {"p_max": 0.5, "min_probability": 0.6})   # the catalogue: uncertain only
    with pytest.raises(ValueError, match="allows"):
        SanityFinding("zero_channel", WARN, {"bearing": 1, "angle_deg": 45.0})         # a channel of zeros always fails
    ood = Reason("ood", INCONCLUSIVE, {"ood_score": 3.5, "ood_inconclusive": 3.0})
    assert ood.code == "ood" and ood.variant == "default" and ood.values == {"ood_score": 3.5, "ood_inconclusive": 3.0}
    # the answer carries the catalogue's "what to do" beside the recording's own message (the web page shows both)
    assert ood.to_dict() == {"code": "ood", "status": INCONCLUSIVE, "message": ood.message,
                             "action": CATALOGUE["ood"].action}
    require_code("no_sync_signal", FAIL)
    require_code("no_sync_signal", WARN)


class _Field:
    """A stand-in for any typed value: formats as its field's name, whatever the format spec or conversion."""

    def __init__(self, name: str) -> None:
        self.name = name

    def __format__(self, spec: str) -> str:
        return f"<{self.name}>"

    def __repr__(self) -> str:
        return f"<{self.name}>"


def test_every_template_of_every_code_renders_from_its_fields():
    """Each variant's message is made from its fields alone: every field appears, nothing else is a field, and no
    brace is left over (a template with a typo, or text with a stray brace, fails here)."""
    from rotordiag.models.status import Reason

    for code, e in CATALOGUE.items():
        assert e.templates and all(re.fullmatch(r"[a-z_]+", v) for v in e.templates)
        for variant, template in e.templates.items():
            assert template.strip() and "`" not in template and "|" not in template, (code, variant)   # the table
            fields = e.fields(variant)
            text = e.message(variant, {f: _Field(f) for f in fields})
            assert "{" not in text and "}" not in text, (code, variant, text)
            assert all(f"<{f}>" in text for f in fields), (code, variant)
            if e.kind != SANITY:
                status = e.statuses[0]
                assert Reason(code, status, {f: _Field(f) for f in fields}, variant).message == text


def test_values_that_are_not_the_templates_fields_are_refused():
    from rotordiag.features import SanityFinding
    from rotordiag.models.status import Reason

    with pytest.raises(ValueError, match="not the template's fields"):
        Reason("ood", UNCERTAIN, {"ood_score": 1.5})                                        # one missing
    with pytest.raises(ValueError, match="not the template's fields"):
        Reason("ood", UNCERTAIN, {"ood_score": 1.5, "ood_inconclusive": 3.0, "speed_rpm": 1500.0})   # one extra
    with pytest.raises(ValueError, match="no message variant 'sideways'"):
        Reason("scale", UNCERTAIN, {"bearing": 2, "amp": 1.0, "factor": 30.0, "typical": 2.0}, "sideways")
    with pytest.raises(ValueError, match="not the template's fields"):
        SanityFinding("reverse_whirl", WARN, {"bearings": "2"}, 2)                          # the _all variant's field
    with pytest.raises(TypeError, match="mapping"):
        Reason("ood", UNCERTAIN, "the recording is unlike the training data")               # free text: refused


def _literal_value_calls() -> list[tuple[str, str, str, frozenset[str]]]:
    """(where, code, variant, value names) of every ``Reason(...)`` / ``SanityFinding(...)`` call in the packages whose
    code, values (a dict display with string keys, no ``**``) and variant (absent or a string) are written out."""
    found = []
    for path in sorted(p for d in ("features", "models", "service", "rotordiag") for p in (ROOT / d).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in CONSTRUCTORS
                    and node.args and isinstance(node.args[0], ast.Constant)):
                continue
            values = node.args[2] if len(node.args) > 2 else next(
                (k.value for k in node.keywords if k.arg == "values"), None)
            variant = node.args[-1] if len(node.args) > 3 + (node.func.id == "SanityFinding") else next(
                (k.value for k in node.keywords if k.arg == "variant"), ast.Constant("default"))
            if values is None:
                values = ast.Dict(keys=[], values=[])
            if not (isinstance(values, ast.Dict) and all(isinstance(k, ast.Constant) for k in values.keys)
                    and isinstance(variant, ast.Constant)):
                continue
            found.append((f"{path.relative_to(ROOT)}:{node.lineno}", node.args[0].value, variant.value,
                          frozenset(k.value for k in values.keys if isinstance(k, ast.Constant))))
    return found


def test_the_values_written_at_each_call_are_its_templates_fields():
    """Where a reason's values are written out at the call, they are its template's fields: a template changed
    without its call (or a call without its template) fails here, not only when that recording comes."""
    calls = _literal_value_calls()
    assert len(calls) >= 15                                    # the scan finds the calls (it can fail)
    for where, code, variant, names in calls:
        assert names == CATALOGUE[code].fields(variant), (where, code, variant)


def test_a_length_is_written_in_um_or_mil_from_its_value():
    """A deliberate test of a template's rendered wording: a length carried as a number in µm is written in mil
    (÷ 25.4) only when the message is rendered in mil."""
    from rotordiag.core.notes import Length
    from rotordiag.models.status import Reason

    r = Reason("scale", UNCERTAIN, {"bearing": 3, "amp": Length(254.0), "factor": 25.0, "typical": Length(10.16)},
               "above")
    assert r.values["amp"] == Length(254.0) and r.variant == "above"
    assert r.message.startswith("1X vibration at bearing 3 is 254 µm pk-pk, 25× above the training data's typical "
                                "10.2 µm: ")
    assert r.message.render("mil").startswith("1X vibration at bearing 3 is 10 mil pk-pk, 25× above the training "
                                              "data's typical 0.4 mil: ")
    assert r.message.render("mil").endswith("check the units (µm vs mils ×25.4) and the probe sensitivity")


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


def test_the_reason_table_shows_every_template():
    table = markdown_table()
    for e in CATALOGUE.values():
        row = next(r for r in table.splitlines() if r.startswith(f"| `{e.code}` |"))
        assert row.count(" | ") == 5 and all(f"`{t}`" in row for t in e.templates.values()), e.code
        assert all(f"*{v}*: " in row for v in e.templates) if len(e.templates) > 1 else "*default*" not in row


def test_docs_pipeline_holds_the_generated_reason_table():
    page = (ROOT / "docs" / "pipeline.md").read_text(encoding="utf-8")
    assert markdown_table() in page, "regenerate the table: python -c 'from rotordiag.core.reasons import " \
                                     "markdown_table; print(markdown_table())'"
