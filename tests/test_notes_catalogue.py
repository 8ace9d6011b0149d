"""The catalogue of warnings (rotordiag.core.notes): every warning produced is a typed note of a catalogue code,
its text is rendered from the template with typed values (lengths in µm or mil), and docs/pipeline.md holds its
generated table."""
from __future__ import annotations

import ast
import copy
import pickle
import re
from pathlib import Path

import numpy as np
import pytest

from rotordiag.core.notes import NOTES, Length, Note, notes_markdown_table, speed_in_doubt
from rotordiag.core.units import UM_PER_MIL

ROOT = Path(__file__).resolve().parents[1]


def _written_codes() -> set[str]:
    """Codes written as the first argument of a ``Note(...)`` call in the packages (they must be literals)."""
    codes = set()
    for path in sorted(p for d in ("features", "models", "service", "rotordiag") for p in (ROOT / d).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "Note" \
                    and node.args and path.name != "notes.py":
                first = node.args[0]
                assert isinstance(first, ast.Constant) and isinstance(first.value, str), \
                    f"{path}:{node.lineno}: a warning's code must be a literal of the catalogue"
                codes.add(first.value)
    return codes


def test_every_warning_code_written_is_in_the_catalogue_and_every_entry_is_written():
    written = _written_codes()
    assert len(written) >= 20                                    # the scan found the constructors (it can fail)
    assert written - set(NOTES) == set()
    assert set(NOTES) - written == set()


def test_entries_are_complete_and_templates_name_their_fields():
    for code, e in NOTES.items():
        assert re.fullmatch(r"[a-z0-9_]+", code) and e.code == code
        assert e.meaning and e.action and e.template and e.severity in {"doubt", "caution", "info"}
        assert e.fields, code                                    # every message carries a value of its recording


def test_a_foreign_code_or_wrong_values_are_refused():
    with pytest.raises(ValueError, match="not in the catalogue"):
        Note("made_up_warning", detail="x")
    with pytest.raises(ValueError, match="template's fields"):
        Note("speed_varies", variation_pct=1.0, extra=2)
    with pytest.raises(ValueError, match="template's fields"):
        Note("speed_varies")


def test_a_note_is_its_text_and_keeps_code_and_values_through_pickle_and_copy():
    n = Note("speed_not_converged", speed_rpm=1234.567)
    assert n == "speed refinement did not converge; using the spectral peak 1234.57 r/min"
    for other in (pickle.loads(pickle.dumps(n)), copy.deepcopy(n)):
        assert isinstance(other, Note) and other == n and other.code == n.code and other.values == n.values
    assert n.severity == "doubt" and speed_in_doubt(n)


def test_a_length_is_rendered_in_the_units_asked_for():
    """25.4 µm is exactly 1 mil (the inch's definition); the same number, two units, no text parsed."""
    n = Note("motion_not_classified", orbit=Length(2.54e-300))
    assert "2.54e-300 µm" in n and n.render("um") == str(n)
    assert f"{2.54e-300 / UM_PER_MIL:.3g} mil" in n.render("mil") and "µm" not in n.render("mil")
    assert Length(25.4).render("mil") == "1 mil" and Length(25.4).render("um") == "25.4 µm"


def test_every_warning_of_a_produced_verdict_is_a_catalogue_note():
    """Recordings that make the feature extractor and the model side warn (few revolutions, no DC position, a
    stated speed off the signal, too few bearings for the model): every warning of the verdict is a Note of a
    catalogue code — a plain string, or a code the catalogue lacks, fails here."""
    from rotordiag.features import ProbeChannel, Recording, extract_features
    from rotordiag.models.pipeline import diagnose
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.registry import shipped_registry_dir
    from rotordiag.simulator import Plant, simulate

    res = simulate(Plant.default(), 1800.0, 0.2, 0.05, mechanism="rigid", transient_revs=100, record_revs=40,
                   sample_rate_hz=4096.0)
    d = res.journal_displacements_m * 1e6
    rows = [(b, a, d[:, b - 1, 0] * np.cos(np.deg2rad(a)) + d[:, b - 1, 1] * np.sin(np.deg2rad(a)))
            for b in range(1, 5) for a in (45.0, 135.0)]

    def rec(speed_rpm, n, centred=False, bearings=(1, 2, 3, 4)):
        return Recording(sample_rate_hz=4096.0, speed_rpm=speed_rpm, channels=[
            ProbeChannel(bearing=b, angle_deg=a, units="um", data=(x[:n] - x[:n].mean()) if centred else x[:n])
            for b, a, x in rows if b in bearings])

    model = load_bundle(shipped_registry_dir())
    seen = set()
    for r in (rec(1800.0, 2048), rec(1800.0, 8192, centred=True), rec(1807.2, 8192), rec(1800.0, 8192, bearings=(1, 2))):
        v = diagnose(model, extract_features(r))
        for w in v.warnings:
            assert isinstance(w, Note) and w.code in NOTES, w
            assert str(w) == NOTES[w.code].template.format(**{k: (x.render() if isinstance(x, Length) else x)
                                                               for k, x in w.values.items()})
            seen.add(w.code)
    assert {"few_revolutions_subharmonic", "no_dc_position", "speed_off_signal"} <= seen, seen


def test_docs_pipeline_holds_the_generated_warnings_table():
    page = (ROOT / "docs" / "pipeline.md").read_text(encoding="utf-8")
    assert notes_markdown_table() in page, "regenerate the table: python -c 'from rotordiag.core.notes import " \
                                           "notes_markdown_table; print(notes_markdown_table())'"


def test_mil_output_is_rendered_from_typed_values_not_parsed():
    """A fresh verdict's evidence texts carry their lengths as numbers (Measured): the mil answer is rendered from
    them — the sentence parser (the fallback for untyped texts) is never called — and every µm amount becomes the
    same length / 25.4 in mil (1 mil = 25.4 µm exactly)."""
    import rotordiag.models.output_units as ou
    from rotordiag.core.notes import Measured
    from rotordiag.features import ProbeChannel, Recording, extract_features
    from rotordiag.models.pipeline import diagnose
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.registry import shipped_registry_dir
    from rotordiag.simulator import Plant, simulate

    res = simulate(Plant.default(), 1800.0, 0.2, 0.05, mechanism="rigid", transient_revs=100, record_revs=40,
                   sample_rate_hz=4096.0)
    d = res.journal_displacements_m * 1e6
    rec = Recording(sample_rate_hz=4096.0, speed_rpm=1800.0, channels=[
        ProbeChannel(bearing=b, angle_deg=a, units="um",
                     data=d[:, b - 1, 0] * np.cos(np.deg2rad(a)) + d[:, b - 1, 1] * np.sin(np.deg2rad(a)))
        for b in range(1, 5) for a in (45.0, 135.0)])
    v = diagnose(load_bundle(shipped_registry_dir()), extract_features(rec)).to_dict()

    import inspect

    assert "import re" not in inspect.getsource(ou), "nothing is parsed out of a sentence: no regular expressions"
    out = ou.verdict_in_units(v, "mil")
    typed = [(e, o) for e, o in zip(v["evidence"], out["evidence"]) if isinstance(e["value"], Measured)]
    assert len(typed) >= 8                                   # 1X and 2X at x and y of the coupling bearings
    for e, o in typed:
        assert "µm" not in o["value"] and "mil" in o["value"], o
        for value in e["value"].values.values():
            if isinstance(value, Length):
                assert f"{value.value_um / UM_PER_MIL:{value.fmt}} mil" in o["value"]
        if e["name"] in ("1X x", "2X y"):
            assert o["number"] == pytest.approx(e["number"] / UM_PER_MIL, rel=1e-12)
            assert o["value"].startswith(f"{e['number'] / UM_PER_MIL:.3g} mil pk-pk")


def test_the_schema_names_every_warning_code():
    from rotordiag.service.schemas import DiagnoseResponse

    text = DiagnoseResponse.model_json_schema()["properties"]["warnings"]["description"]
    assert all(f"`{code}`" in text for code in NOTES)
