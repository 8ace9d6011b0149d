"""Dataset loader and the CLI (train, models, diagnose) on a small synthetic dataset file.

The file follows docs/dataset-format.md but its waveforms are exact sinusoids, so the
features the loader extracts have known values (no simulator run needed).
"""
from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
from threadpoolctl import threadpool_limits
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.models.dataset import load_feature_table

FS = 2560.0
N_POINTS = 2048
CHANNELS = [(b, a) for b in (1, 2, 3, 4) for a in (45.0, 135.0)]


@pytest.fixture(autouse=True)
def _one_openmp_thread():
    with threadpool_limits(1):
        yield


def _waveforms(delta: float, speed_rpm: float, rng) -> tuple[np.ndarray, float]:
    """x = A1 cos θ + A2 cos(2θ − q), y = A1 sin θ + ... per bearing; A2 grows with Δ at b2/b3."""
    t = np.arange(N_POINTS) / FS
    theta = 2 * np.pi * speed_rpm / 60 * t + rng.uniform(0, 2 * np.pi)
    out = np.empty((8, N_POINTS), dtype=np.float32)
    a1 = 40.0
    for c, (b, ang) in enumerate(CHANNELS):
        a2 = (4.0 + 60.0 * delta) if b in (2, 3) else 4.0
        x = a1 * np.cos(theta) + a2 * np.cos(2 * theta - 0.3)
        y = a1 * np.sin(theta) + a2 * np.sin(2 * theta - 0.3)
        out[c] = x * np.cos(np.radians(ang)) + y * np.sin(np.radians(ang)) + rng.normal(0, 0.05, N_POINTS)
    return out, a2_ratio(delta)


def a2_ratio(delta: float) -> float:
    return (4.0 + 60.0 * delta) / 40.0


def make_dataset(path, n=64, seed=0):
    rng = np.random.default_rng(seed)
    delta = np.where(np.arange(n) % 4 == 0, 0.0, rng.uniform(0, 0.6, n))
    speed = rng.uniform(1200, 2400, n)
    status = np.zeros(n, np.int8)
    status[5] = 1                                    # contact
    done = np.ones(n, np.uint8)
    done[7] = 0                                      # unfinished
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "rotordiag-dataset"
        f.attrs["format_version"] = 1
        f.attrs["sample_rate_hz"] = FS
        f.attrs["waveform_units"] = "um"
        f.attrs["spec_hash"] = "test"
        f.attrs["spec_json"] = json.dumps({"plant": {"perturb": {}}})
        ch = np.array(CHANNELS, dtype=[("bearing", "i1"), ("angle_deg", "f8")])
        f["channels"] = ch
        wf = np.zeros((n, 8, N_POINTS), np.float32)
        for i in range(n):
            wf[i], _ = _waveforms(delta[i], speed[i], rng)
        f["waveforms"] = wf
        f["done"] = done
        f["parameters/speed_rpm"] = speed
        f["parameters/misalignment"] = delta
        f["labels/misalignment"] = delta
        mech = np.where(delta == 0, 2, np.arange(n) % 2).astype(np.int8)
        f["parameters/simulated_mechanism"] = mech
        f["parameters/simulated_mechanism"].attrs["codes_json"] = json.dumps({"pin": 0, "rigid": 1, "aligned": 2})
        f["labels/status"] = status
        f["labels/status"].attrs["codes_json"] = json.dumps({"ok": 0, "contact": 1, "diverged": 2, "error": 3})
        f["parameters/plant_id"] = np.array([f"plant{i:04d}".encode() for i in range(n)], dtype="S16")
        f["parameters/plant/clearance_m"] = np.full(n, 350e-6)
    return delta, speed


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    p = tmp_path_factory.mktemp("data") / "d.h5"
    delta, speed = make_dataset(p)
    return p, delta, speed


def test_loader_skips_bad_samples_and_extracts_known_features(dataset):
    path, delta, _ = dataset
    tab = load_feature_table(path)
    assert tab.meta["skipped"] == {"not finished": 1, "status contact": 1}
    assert len(tab) == 62 and 5 not in tab.sample_index and 7 not in tab.sample_index
    j = tab.feature_names.index("b2_x_2x_1x_ratio")
    expected = np.array([a2_ratio(d) for d in delta[tab.sample_index]])
    np.testing.assert_allclose(tab.X[:, j], expected, rtol=2e-3)
    assert set(tab.mechanism.tolist()) == {"aligned", "pin", "rigid"}
    k = tab.feature_names.index("b2_x_1x_amp_pp_per_c")
    np.testing.assert_allclose(tab.X[:, k], 80.0 / 350.0, rtol=2e-3)   # 40 µm 0-pk = 80 pk-pk
    assert tab.meta["feature_cache"]["hit"] is False
    again = load_feature_table(path)
    assert again.meta["feature_cache"]["hit"] is True
    np.testing.assert_array_equal(again.X, tab.X)
    assert again.meta["dataset_hash"] == tab.meta["dataset_hash"]


def test_loader_rejects_non_datasets(tmp_path):
    p = tmp_path / "x.h5"
    with h5py.File(p, "w") as f:
        f["a"] = 1
    with pytest.raises(ValueError, match="not a rotordiag dataset"):
        load_feature_table(p)
    with pytest.raises(ValueError, match="does not exist"):
        load_feature_table(tmp_path / "missing.h5")


@pytest.fixture(scope="module")
def trained(dataset, tmp_path_factory):
    path, _, _ = dataset
    root = tmp_path_factory.mktemp("reg")
    cfg = root / "train.toml"
    cfg.write_text('[classifier]\nmax_iter = 20\ncv = 3\n[regressor]\nmax_iter = 20\n'
                   '[evaluation]\nn_splits = 3\n')
    reg = root / "registry"
    with threadpool_limits(1):
        res = CliRunner().invoke(app, ["train", str(path), "--config", str(cfg), "--registry", str(reg)])
    assert res.exit_code == 0, res.output
    return reg, res.output


def test_train_registers_and_lists(trained):
    reg, out = trained
    assert "registered v0001" in out and "target pin" in out
    card = json.loads((reg / "v0001" / "card.json").read_text())
    assert card["training_data"]["skipped"] == {"not finished": 1, "status contact": 1}
    assert not any(n.endswith("_1x_phase_deg") and n.startswith("b") for n in card["feature_names"])
    res = CliRunner().invoke(app, ["models", "list", "--registry", str(reg)])
    assert res.exit_code == 0 and "* v0001" in res.output
    res = CliRunner().invoke(app, ["models", "rollback", "--registry", str(reg)])
    assert res.exit_code == 2 and "nothing to roll back" in res.output and "Traceback" not in res.output
    res = CliRunner().invoke(app, ["models", "activate", "v0042", "--registry", str(reg)])
    assert res.exit_code == 2 and "v0042 is not in registry" in res.output


def test_diagnose_npy_csv_and_dataset_row(trained, dataset, tmp_path):
    reg, _ = trained
    rng = np.random.default_rng(5)
    wf, _ = _waveforms(0.5, 1800.0, rng)
    npy = tmp_path / "rec.npy"
    np.save(npy, wf)
    (tmp_path / "rec.json").write_text(json.dumps({
        "sample_rate_hz": FS, "units": "um",
        "channels": [{"bearing": b, "angle_deg": a} for b, a in CHANNELS]}))
    res = CliRunner().invoke(app, ["diagnose", str(npy), "--registry", str(reg), "--clearance-um", "350", "--json"])
    assert res.exit_code == 0, res.output
    v = json.loads(res.output)
    assert v["severity"] == "severe" and v["offset_um"] == pytest.approx(350 * v["misalignment"])
    assert abs(v["speed_rpm"] - 1800.0) < 0.5                  # estimated from the signal
    # CSV with BEARING@ANGLE headers (points × channels), mils, speed flag.
    csv = tmp_path / "rec.csv"
    header = ",".join(f"b{b}@{a:g}" for b, a in CHANNELS)
    np.savetxt(csv, wf.T / 25.4, delimiter=",", header=header, comments="")
    res = CliRunner().invoke(app, ["diagnose", str(csv), "--registry", str(reg), "--units", "mil",
                                   "--sample-rate-hz", str(FS), "--speed-rpm", "1800"])
    assert res.exit_code == 0, res.output
    assert "severity: severe" in res.output and "offset δ: unknown" in res.output
    path, delta, _ = dataset
    res = CliRunner().invoke(app, ["diagnose", str(path), "--sample", "0", "--registry", str(reg)])
    assert res.exit_code == 0, res.output
    assert "dataset truth: Δ = 0.000" in res.output


@pytest.mark.parametrize(
    "args,msg",
    [
        (["--channels", "1@45,1@135"], "layout names 2 channels"),
        (["--channels", "9@45"], "--channels"),
        (["--sidecar", "nope.json"], "--sidecar"),
        (["--speed-range-rpm", "3100,2900"], "--speed-range-rpm: the minimum (3100) must be below the maximum"),
        (["--speed-range-rpm", "-5,3000"], "--speed-range-rpm must lie between 1 and 100000 r/min"),
        (["--speed-range-rpm", "3000"], "--speed-range-rpm must be two numbers"),
        (["--speed-range-rpm", "2900,3100", "--speed-rpm", "1500"], "speed_rpm 1500 lies outside speed_range_rpm"),
    ],
)
def test_diagnose_errors_are_clean(trained, tmp_path, args, msg):
    reg, _ = trained
    npy = tmp_path / "r.npy"
    np.save(npy, np.zeros((8, 4096)))
    res = CliRunner().invoke(app, ["diagnose", str(npy), "--registry", str(reg), "--sample-rate-hz", "2560", *args])
    assert res.exit_code == 2
    assert msg in res.output and "Traceback" not in res.output


def test_diagnose_speed_range_hint(trained, tmp_path):
    """--speed-range-rpm reaches the speed estimate: inside the range it is found, a range without
    the machine's line is refused naming the option's field."""
    reg, _ = trained
    wf, _ = _waveforms(0.5, 1800.0, np.random.default_rng(5))
    npy = tmp_path / "rec.npy"
    np.save(npy, wf)
    base = ["diagnose", str(npy), "--registry", str(reg), "--sample-rate-hz", str(FS),
            "--channels", ",".join(f"{b}@{a:g}" for b, a in CHANNELS)]
    res = CliRunner().invoke(app, [*base, "--speed-range-rpm", "1700,1900", "--json"])
    assert res.exit_code == 0, res.output
    assert abs(json.loads(res.output)["speed_rpm"] - 1800.0) < 0.5
    res = CliRunner().invoke(app, [*base, "--speed-range-rpm", "2500,2600"])
    assert res.exit_code == 2 and "speed_range_rpm 2500–2600" in res.output


def test_diagnose_without_sample_rate_or_model(tmp_path):
    npy = tmp_path / "r.npy"
    np.save(npy, np.zeros((8, 4096)))
    res = CliRunner().invoke(app, ["diagnose", str(npy), "--registry", str(tmp_path)])
    assert res.exit_code == 2 and "sample rate unknown" in res.output
    res = CliRunner().invoke(app, ["diagnose", str(npy), "--registry", str(tmp_path / "empty"),
                                   "--sample-rate-hz", "2560",
                                   "--channels", ",".join(f"{b}@{a:g}" for b, a in CHANNELS)])
    assert res.exit_code == 2 and "no active model" in res.output


def test_augmented_table_adds_gain_mismatch_missing_bearings_and_unknown_speed(dataset):
    from rotordiag.models.augment import Augmentation

    path, delta, _ = dataset
    aug = Augmentation.from_dict({"copies": 2, "gain_mismatch": 0.1, "speed_unknown": 0.5, "seed": 3,
                                  "bearing_sets": [{"bearings": [2, 3], "weight": 1},
                                                   {"bearings": [1, 2, 3, 4], "weight": 1}]})
    plain = load_feature_table(path)
    tab = load_feature_table(path, augment=aug)
    n = len(plain)
    off = tab.meta["augment"]["speed_estimate_off"]
    assert len(tab) == 3 * n - off and tab.meta["augment"]["rows"] == 2 * n - off and off <= n // 4
    np.testing.assert_array_equal(tab.X[:n], plain.X)                  # originals unchanged, first
    assert set(tab.sample_index[n:]) <= set(plain.sample_index)
    if off == 0:
        np.testing.assert_array_equal(tab.sample_index[n:], np.repeat(plain.sample_index, 2))
        np.testing.assert_array_equal(tab.plant_id[n:], np.repeat(plain.plant_id, 2))   # same plant: same group
    # speed-unknown copies whose estimate missed the simulated speed by > 2 % are left out
    est = tab.X[n:, tab.feature_names.index("speed_rpm")]
    assert np.all(np.abs(est / tab.speed_rpm[n:] - 1) <= 0.02)
    aug_rows = tab.X[n:]
    b1 = tab.feature_names.index("b1_x_1x_amp_um_pp")
    b2 = tab.feature_names.index("b2_x_1x_amp_um_pp")
    missing_b1 = np.isnan(aug_rows[:, b1])
    assert 0.25 < missing_b1.mean() < 0.75 and not np.isnan(aug_rows[:, b2]).any()
    # Gains: every channel within ±10 % of the original, and not all equal to it.
    orig = plain.X[np.searchsorted(plain.sample_index, tab.sample_index[n:]), b2]
    ratio = aug_rows[:, b2] / orig
    assert np.all(np.abs(ratio - 1) <= 0.1 + 1e-3) and np.std(ratio) > 0.02
    # Deterministic, and cached under the augmentation's own key.
    again = load_feature_table(path, augment=aug)
    np.testing.assert_array_equal(again.X, tab.X)
    other = load_feature_table(path, augment=Augmentation.from_dict({"copies": 1, "seed": 4}))
    assert len(other) == 2 * n - other.meta["augment"]["speed_estimate_off"]
    with pytest.raises(ValueError, match="bearing_sets"):
        Augmentation.from_dict({"bearing_sets": [{"bearings": [5]}]})
    with pytest.raises(ValueError, match="unknown key"):
        Augmentation.from_dict({"copise": 2})


def test_speed_unknown_copies_with_a_wrong_speed_estimate_are_left_out():
    """A copy's estimated speed 1/5 of the simulated one (period-5 motion) is not a training row."""
    from rotordiag.models.dataset import SPEED_COPY_MAX_ERROR, _speed_estimate_off

    names = ["a", "speed_rpm"]
    X = np.array([[1.0, 1500.0], [1.0, 300.0], [1.0, np.nan], [1.0, 1500.0 * (1 + SPEED_COPY_MAX_ERROR / 2)],
                  [1.0, 1500.0 * (1 + 2 * SPEED_COPY_MAX_ERROR)]])
    off = _speed_estimate_off(X, names, np.full(5, 1500.0))
    assert off.tolist() == [False, True, False, False, True]
