"""Bad input for shaft trains through the Python and CLI doors (issue 42 item 3; the HTTP door:
tests/test_service_train_simulate.py): an offset that presses a journal on its bearing metal names the bearing, by how
much, and the largest offset the train takes; a bad shaft line is exit 2 with what to fix, nothing written."""
from __future__ import annotations

import pytest
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.simulator.train import (
    Coupling,
    Rotor,
    Support,
    Train,
    TrainError,
    misaligned,
    static_state,
    uniform_elements,
)
from rotordiag.simulator.train.recording import train_recording
from rotordiag.simulator.train.shaftline import shaftline_of, train_from_shaftline
from rotordiag.simulator.train.static import MAX_FILM_ECCENTRICITY, ClearanceError, film_eccentricity

runner = CliRunner()


def _said(output: str) -> str:
    """The CLI's message as one line (the error panel's borders and line breaks removed)."""
    return " ".join(output.replace("│", " ").split())


@pytest.fixture(scope="module")
def gen200():
    return train_from_shaftline(shaftline_of("gen200_2pole")[0])


def test_a_5mm_sideways_offset_is_refused_and_the_offset_it_names_is_the_limit(gen200):
    with pytest.raises(ClearanceError) as info:
        train_recording(gen200, 3000.0, offset_um=5000.0, direction_deg=0.0, transient_revs=10, record_revs=2)
    exc = info.value
    assert exc.bearing == "B3" and exc.film_eccentricity > MAX_FILM_ECCENTRICITY
    msg = str(exc)
    assert "bearing B3" in msg and "film eccentricity" in msg and "kN on the bearing" in msg
    most_um = float(msg.split("at most about an offset of ")[1].split(" µm")[0])
    assert 300.0 < most_um < 5000.0
    # the offset it names is where the limit lies: just inside it the journal keeps its film, 10 % beyond it not
    st = static_state(misaligned(gen200, offset_m=most_um * 1e-6, direction_rad=0.0), 3000.0)
    ecc = max(film_eccentricity(b, *st.journal_m[k]) for k, b in enumerate(st.assembly.bearings))
    assert 0.85 < ecc <= MAX_FILM_ECCENTRICITY
    with pytest.raises(ClearanceError):
        static_state(misaligned(gen200, offset_m=1.1 * most_um * 1e-6, direction_rad=0.0), 3000.0)


def test_offsets_within_half_a_clearance_are_not_refused(gen200):
    """The limit does not catch the offsets of the misalignment study (0.5 c = 175 µm, both directions)."""
    for deg in (-90.0, 0.0):
        st = static_state(misaligned(gen200, offset_m=175e-6, direction_rad=deg * 3.141592653589793 / 180), 3000.0)
        assert max(film_eccentricity(b, *st.journal_m[k]) for k, b in enumerate(st.assembly.bearings)) < 0.8


def test_cli_refuses_the_offset_with_exit_2_and_writes_nothing(tmp_path):
    out = tmp_path / "x.csv"
    r = runner.invoke(app, ["simulate", "--train", "gen200_2pole", "--speed-rpm", "3000", "--offset-um", "5000",
                            "--probes-out", str(out)])
    assert r.exit_code == 2, r.output
    text = _said(r.output)
    assert "B3" in text and "film eccentricity" in text and "Along -90°" in text   # vertical by default
    assert "Traceback" not in r.output and list(tmp_path.iterdir()) == []


def test_cli_help_states_the_offset_direction_convention():
    r = runner.invoke(app, ["simulate", "--help"], env={"COLUMNS": "200"})
    text = _said(r.output)
    assert "default -90 (a vertical offset" in text and "0 = sideways" in text


@pytest.mark.parametrize("toml, says", [
    ("[generator]\nsegments = [[-1.0, 0.5]]\n[exciter]\nsegments = [[1.0, 0.3]]\n", "length"),
    ("[generator]\nsegments = [[1.0, 0.5]]\n[exciter]\nsegments = [[1.0, 0.3]]\n"
     "[bearings]\ntype = ['plain', 'plain', 'none', 'plain']\n", "only bearing 4"),
    ("[generator]\nsegments = [[1.0, 0.5]]\ndisks = [[3.0, 10, 1, 1]]\n[exciter]\nsegments = [[1.0, 0.3]]\n",
     "outside the span"),
    ("[generator]\nsegments = [[20.0, 0.6]]\nbody_masses = [" + ", ".join(f"[{0.1 * k + 0.05:.2f}, 10.0]"
                                                                         for k in range(190))
     + "]\n[exciter]\nsegments = [[2.0, 0.3]]\n", "max_element_m"),
])
def test_cli_refuses_bad_shaft_lines_with_what_to_fix(tmp_path, toml, says):
    line = tmp_path / "line.toml"
    line.write_text(toml)
    out = tmp_path / "x.csv"
    r = runner.invoke(app, ["simulate", "--shaftline", str(line), "--speed-rpm", "3000", "--probes-out", str(out)])
    assert r.exit_code == 2, r.output
    assert says in _said(r.output) and "Traceback" not in r.output
    assert not out.exists()


def test_a_train_too_large_to_reduce_is_refused_before_anything_is_assembled():
    """Three rotors of 150 elements (453 stations, 1812 DOFs) is beyond the limit of 400 stations; 3 × 100 is not."""
    from rotordiag.simulator.train.model import MAX_TRAIN_STATIONS
    from tests.train_support import iso

    def rotors(n):
        return tuple(Rotor(f"r{k}", uniform_elements(2.0, 0.3, n), supports=(Support(0, iso(1e9)), Support(n, iso(1e9))))
                     for k in range(3))

    with pytest.raises(TrainError, match=f"453 stations, more than {MAX_TRAIN_STATIONS}.*longer elements"):
        Train(rotors(150), (Coupling("rigid"), Coupling("rigid")))
    assert sum(r.n_stations for r in Train(rotors(100), (Coupling("rigid"), Coupling("rigid"))).rotors) == 303
