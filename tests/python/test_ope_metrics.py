"""SR0.5, SR0.75, AO and normalised precision beside success AUC and P@20,
under the three conventions (otb, got10k, got10k_otb = got10k's
ExperimentOTB.report), on boxes whose overlaps are worked out by hand."""

import math

import numpy as np
import pytest

from sim4cv import ope

BOX = [0, 0, 10, 10]
# frame 1 is replaced by the truth; then IoU 1, 8*10 / (200 - 80) = 2/3, 5*10 / (200 - 50) = 1/3;
# centre errors 0, 0, 2, 5 px; in units of the truth's size 0, 0, 0.2, 0.5
RESULT = [[50, 50, 4, 4], BOX, [2, 0, 10, 10], [5, 0, 10, 10]]


def _score(truth, convention):
    return ope.evaluate_sequence(np.array(RESULT, float), np.array(truth, float), convention)


@pytest.mark.parametrize("convention", ope.CONVENTIONS)
def test_every_frame_valid_all_conventions_agree(convention):
    s = _score([BOX] * 4, convention)
    assert s["sr_50"] == pytest.approx(3 / 4)  # IoU > 0.5: 1, 1, 2/3
    assert s["sr_75"] == pytest.approx(2 / 4)  # IoU > 0.75: 1, 1
    assert s["ao"] == pytest.approx((1 + 1 + 2 / 3 + 1 / 3) / 4)
    assert s["norm_precision_20"] == pytest.approx(3 / 4)  # 0, 0, 0.2 <= 0.2
    assert s["precision_20"] == 1.0 and s["frames"] == 4


def test_a_frame_without_truth_under_each_convention():
    truth = [BOX, BOX, [math.nan] * 4, BOX]
    otb, got10k, experiment_otb = (_score(truth, c) for c in ("otb", "got10k", "got10k_otb"))
    # otb: the frame stays, overlap -1 (a miss), centre errors -1 (a hit)
    assert (otb["sr_50"], otb["ao"], otb["precision_20"], otb["norm_precision_20"]) == pytest.approx(
        (2 / 4, (1 + 1 + 0 + 1 / 3) / 4, 1.0, 3 / 4))
    # got10k (uav123.py/lasot.py): the frame is left out
    assert (got10k["sr_50"], got10k["ao"], got10k["precision_20"], got10k["frames"]) == pytest.approx(
        (2 / 3, (1 + 1 + 1 / 3) / 3, 1.0, 3))
    # got10k's ExperimentOTB: the frame stays and its NaN IoU and NaN error miss everything
    assert (experiment_otb["sr_50"], experiment_otb["ao"], experiment_otb["precision_20"],
            experiment_otb["norm_precision_20"], experiment_otb["frames"]) == pytest.approx(
        (2 / 4, (1 + 1 + 0 + 1 / 3) / 4, 3 / 4, 2 / 4, 4))
    assert experiment_otb["success_auc"] == pytest.approx(np.mean(ope.curves(
        [1, 1, math.nan, 1 / 3], [0, 0, math.nan, 5])[0]))


def test_got10k_otb_keeps_a_missing_prediction_as_a_miss_where_otb_repeats_the_previous_box():
    result = np.array([BOX, BOX, [math.nan] * 4, [5, 0, 10, 10]], float)
    truth = np.array([BOX] * 4, float)
    assert ope.evaluate_sequence(result, truth, "otb")["sr_50"] == pytest.approx(3 / 4)  # frame 3 takes frame 2's box
    assert ope.evaluate_sequence(result, truth, "got10k_otb")["sr_50"] == pytest.approx(2 / 4)


def test_the_means_over_sequences_carry_the_new_scores():
    a = _score([BOX] * 4, "got10k_otb")
    b = ope.evaluate_sequence(np.array([BOX] * 4, float), np.array([BOX] * 4, float), "got10k_otb")
    mean = ope.average([a, b])
    assert mean["ao"] == pytest.approx((a["ao"] + 1.0) / 2)
    assert mean["sr_50"] == pytest.approx((3 / 4 + 1) / 2)
    assert mean["norm_precision_20"] == pytest.approx((3 / 4 + 1) / 2)
