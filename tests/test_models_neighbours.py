"""What the training machines nearest a recording show: the OOD scorer's reference rows as neighbours.

Two synthetic families that one OOD column tells apart: family A's journals sit where a plain short bearing puts
them and whirl forward at bearing 3; family B's sit 40° further round and whirl backward there (a four-pole train's
exciter journal between its split criticals). A recording is compared with its own family's training machines.
"""
from __future__ import annotations

import copy
from types import SimpleNamespace

import numpy as np
import pytest

from rotordiag.core.journal import short_bearing_attitude_deg
from rotordiag.models.checks.backward_whirl import MIN_BACKWARD, N_NEIGHBOURS, answer_reverse_whirl, backward_as_trained
from rotordiag.models.estimators import (
    ConformalIntervalRegressor,
    KNNDistanceOOD,
    MisalignmentModel,
    SeverityClassifier,
)
from rotordiag.models.status import DEFAULT_POLICY, _probe_frame_reasons
from tests.models_synthetic import FEATURE_NAMES, make_table

CENTRES = ("b1_centre_x_per_c", "b1_centre_y_per_c", "b1_centre_ecc_per_c",
           "b3_centre_x_per_c", "b3_centre_y_per_c", "b3_centre_ecc_per_c")
NAMES = (*FEATURE_NAMES, *CENTRES, "b3_1x_whirl_index")
FAMILY_B_TURN_DEG = 40.0


def _centre(ecc: np.ndarray, turn_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """x, y per clearance of a journal at ``turn_deg`` beyond a plain short bearing's attitude (angles from the
    load line, −y, toward rotation, +x)."""
    phi = np.radians(short_bearing_attitude_deg(ecc) + turn_deg)
    return ecc * np.sin(phi), -ecc * np.cos(phi)


def _rows(n: int, family_b: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    ecc = rng.uniform(0.3, 0.6, size=(n, 2))
    turn = np.where(family_b, FAMILY_B_TURN_DEG, 0.0)
    x1, y1 = _centre(ecc[:, 0], turn)
    x3, y3 = _centre(ecc[:, 1], turn)
    whirl = np.where(family_b, rng.uniform(-0.7, -0.3, n), rng.uniform(0.3, 0.9, n))
    return np.column_stack([x1, y1, ecc[:, 0], x3, y3, ecc[:, 1], whirl])


@pytest.fixture(scope="module")
def two_families():
    t = make_table(n_plants=40, per_plant=10, seed=11)
    family_b = t.plant_id % 2 == 1
    X = np.column_stack([t.X, _rows(len(t.X), family_b, 1)])
    X[family_b, FEATURE_NAMES.index("noise_a")] += 12.0              # the column that tells the families apart
    model = MisalignmentModel(
        classifier=SeverityClassifier(max_iter=20),
        regressor=ConformalIntervalRegressor(max_iter=20, lower_bound=0.0),
        feature_names=NAMES,
        # the neighbours are found without the centreline (a turned probe frame must not move them)
        ood_features=("noise_a", "b2_x_2x_1x_ratio", "b3_1x_whirl_index"),
        ood=KNNDistanceOOD(max_reference=200),
    ).fit(X, t.misalignment, groups=t.plant_id)
    return model, X, family_b


def _query(family_b: bool, seed: int = 7) -> np.ndarray:
    t = make_table(n_plants=1, per_plant=1, seed=seed)
    row = np.concatenate([t.X[0], _rows(1, np.array([family_b]), seed)[0]])
    row[FEATURE_NAMES.index("noise_a")] += 12.0 if family_b else 0.0
    return row


def _turned(row: np.ndarray, deg: float) -> np.ndarray:
    """``row`` with the probes' frame turned by ``deg`` at bearings 1 and 3 (the centreline rotated)."""
    out = row.copy()
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    for b in (1, 3):
        jx, jy = NAMES.index(f"b{b}_centre_x_per_c"), NAMES.index(f"b{b}_centre_y_per_c")
        out[jx], out[jy] = c * row[jx] - s * row[jy], s * row[jx] + c * row[jy]
    return out


def test_reference_rows_are_the_fitted_rows_that_make_up_the_reference(two_families):
    model, X, _ = two_families
    ood = model.ood_
    assert ood.reference_rows_.shape == (ood.reference_.shape[0],) and ood.reference_.shape[0] <= 200
    np.testing.assert_allclose(ood.reference_, ood.preprocess_.transform(model.ood_input(X)[ood.reference_rows_]),
                               atol=1e-5)
    np.testing.assert_array_equal(model.reference_attitude_offset_deg_,
                                  model._attitude_offsets(X[ood.reference_rows_]).astype(np.float32))


def test_nearest_reference_ignores_missing_columns_and_the_one_asked_for():
    X = np.array([[0.0, 0.0], [1.0, 10.0], [2.0, 0.0], [3.0, 10.0]] * 5)
    ood = KNNDistanceOOD(max_reference=1000).fit(X)
    nearest = ood.nearest_reference(np.array([1.0, 0.0]), 5)
    assert set(X[ood.reference_rows_[nearest], 1]) == {0.0}               # column 1 decides: its 0 rows
    nearest = ood.nearest_reference(np.array([1.0, 0.0]), 5, ignore=1)    # column 1 left out: column 0 decides
    assert set(X[ood.reference_rows_[nearest], 0]) == {1.0}
    nearest = ood.nearest_reference(np.array([1.0, np.nan]), 5)           # a missing column does not count
    assert set(X[ood.reference_rows_[nearest], 0]) == {1.0}
    values = ood.neighbour_values(np.array([3.0, -99.0]), 1, 5)           # in X's units
    np.testing.assert_allclose(values, 10.0)
    with pytest.raises(ValueError, match="columns"):
        ood.nearest_reference(np.zeros(3), 5)


def test_the_attitude_reference_is_the_nearest_training_machines(two_families):
    model, _, _ = two_families
    overall = model.attitude_offset_reference_deg_
    near_a = model.attitude_reference_deg(_query(False))
    near_b = model.attitude_reference_deg(_query(True))
    np.testing.assert_allclose(near_a[[0, 2]], 0.0, atol=3.0)
    np.testing.assert_allclose(near_b[[0, 2]], FAMILY_B_TURN_DEG, atol=3.0)
    assert np.isnan(near_b[1]) and np.isnan(overall[1])                    # never instrumented: the overall NaN
    # the frame check: family B's journals are where its training machines' sat; turned 60° they are not
    checks = dict(policy=DEFAULT_POLICY)
    assert _probe_frame_reasons(NAMES, _query(True), reference_deg=near_b, **checks) == []
    assert _probe_frame_reasons(NAMES, _query(True), reference_deg=np.zeros(9), **checks) != []
    turned = _turned(_query(True), -60.0)
    assert model.attitude_reference_deg(turned)[0] == pytest.approx(near_b[0], abs=3.0)   # neighbours unmoved
    assert _probe_frame_reasons(NAMES, turned, reference_deg=model.attitude_reference_deg(turned), **checks) != []


def test_a_model_without_the_per_row_reference_gives_the_overall_one(two_families):
    model, _, _ = two_families
    old = copy.copy(model)                               # as a model saved before the per-row reference loads
    del old.reference_attitude_offset_deg_
    got = old.attitude_reference_deg(_query(True))
    np.testing.assert_array_equal(got, model.attitude_offset_reference_deg_)


def test_a_backward_whirl_the_nearest_training_machines_share_is_read(two_families):
    model, _, _ = two_families
    b = backward_as_trained(model, NAMES, _query(True), 3)
    assert b is not None and b.n_neighbours == N_NEIGHBOURS and b.n_backward >= MIN_BACKWARD and b.as_trained
    row_a = _query(False)
    row_a[-1] = -0.6                                     # family A's probes at bearing 3 inverted
    a = backward_as_trained(model, NAMES, row_a, 3)
    assert a is not None and a.n_backward == 0 and not a.as_trained
    assert backward_as_trained(model, NAMES, row_a, 2) is None     # no whirl column for bearing 2


def test_answer_reverse_whirl_drops_only_the_findings_training_shares(two_families):
    model, _, _ = two_families
    finding = SimpleNamespace(code="reverse_whirl", bearing=3)
    other = SimpleNamespace(code="spike", bearing=3)
    kept, notes = answer_reverse_whirl(model, NAMES, _query(True), (finding, other))
    assert kept == (other,)
    assert [n.code for n in notes] == ["reverse_whirl_as_trained"]
    assert "bearing 3: the 1X whirls backward, as in" in str(notes[0])
    row_a = _query(False)
    row_a[-1] = -0.6
    kept, notes = answer_reverse_whirl(model, NAMES, row_a, (finding, other))
    assert kept == (finding, other) and notes == []
