"""sim4cv.ope: one-pass evaluation, with hand-computed expected values.

Reminders for the arithmetic below: success thresholds t = 0, 0.05, ..., 1
(21 values) count overlap > t, so a frame with IoU 1 succeeds at 20 of them
(not at t = 1) and a frame with IoU 1/3 at 7 (t = 0 .. 0.30); success AUC is
the mean of the 21 values. Precision thresholds d = 0..50 px count error <= d.
The centre of (x, y, w, h) is (x + (w-1)/2, y + (h-1)/2).
"""

import importlib.util
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO_ROOT
from sim4cv import ope, ope_cli

NAN = [math.nan] * 4
GT = [0, 0, 10, 10]  # centre (4.5, 4.5), area 100


def scores(result, truth, convention="otb", origin=0):
    return ope.evaluate_sequence(np.array(result, float), np.array(truth, float), convention, origin)


# ----------------------------------------------------------------------------- geometry


def test_iou_of_known_boxes_both_ways():
    a = [[0, 0, 10, 10], [0, 0, 10, 10], [0.5, 0, 2, 1], [0, 0, 10, 10]]
    b = [[5, 5, 10, 10], [10, 0, 10, 10], [1.5, 0, 2, 1], [0, 0, 10, 10]]
    # 5x5 = 25 over 100+100-25 = 175 -> 1/7; touching edges -> 0; continuous
    # [0.5, 2.5) and [1.5, 3.5) overlap by 1 (not 2: width w, not w+1) -> 1/3; same box -> 1.
    expected = [1 / 7, 0.0, 1 / 3, 1.0]
    np.testing.assert_allclose(ope.iou_otb(a, b), expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ope.iou_got10k(a, b), expected, rtol=0, atol=1e-12)


def test_centre_convention_is_w_minus_one_over_two():
    np.testing.assert_array_equal(ope.centres([[0, 0, 10, 20], [2, 3, 1, 1]]), [[4.5, 9.5], [2.0, 3.0]])
    # (4.5, 4.5) to (7.5, 8.5): 3-4-5.
    np.testing.assert_allclose(ope.centre_errors([[3, 4, 10, 10]], [GT]), [5.0])


def test_otb_validity_depends_on_the_origin():
    truth = [[0, 0, 10, 10], [-1, 5, 10, 10], [3, 3, 0, 10], NAN]
    # 0-based x = 0 is OTB's x = 1 > 0 (valid); x = -1 is OTB's 0 (invalid); w = 0 invalid; NaN invalid.
    assert ope.valid_truth(truth, "otb", origin=0).tolist() == [True, False, False, False]
    assert ope.valid_truth(truth, "otb", origin=1).tolist() == [False, False, False, False]
    # got10k only looks for NaN.
    assert ope.valid_truth(truth, "got10k").tolist() == [True, True, True, False]


# ----------------------------------------------------------------------------- per-sequence rules


@pytest.mark.parametrize("convention", ope.CONVENTIONS)
def test_frame_one_is_replaced_by_the_ground_truth(convention):
    # Frame 1 far away, frames 2-3 exact: after replacement every IoU is 1,
    # which succeeds at 20 of 21 thresholds -> AUC 20/21; precision 1.
    s = scores([[100, 100, 10, 10], GT, GT], [GT] * 3, convention)
    assert s["success_auc"] == pytest.approx(20 / 21)
    assert s["success_curve"] == [1.0] * 20 + [0.0]
    assert s["precision_20"] == 1.0 and s["frames"] == 3


def test_otb_replaces_nan_and_zero_size_results_by_the_previous_one():
    # f2 (5,0,10,10): IoU 50/150 = 1/3, error 5. f3 NaN -> f2's box. f4 w=0 ->
    # f3's repaired box (= f2's). Overlaps [1, 1/3, 1/3, 1/3]:
    # success counts 20 + 3*7 = 41 of 4*21 -> AUC 41/84.
    s = scores([GT, [5, 0, 10, 10], NAN, [0, 0, 0, 10]], [GT] * 4, "otb")
    assert s["success_auc"] == pytest.approx(41 / 84)
    assert s["success_curve"][6] == 1.0 and s["success_curve"][7] == 0.25  # t = 0.30 vs 0.35
    assert s["precision_curve"][4] == 0.25 and s["precision_curve"][5] == 1.0 and s["precision_20"] == 1.0


def test_got10k_keeps_invalid_results():
    # Same input: f3 NaN scores IoU NaN and error NaN (misses); f4 (0,0,0,10)
    # scores IoU 0 but its centre (-0.5, 4.5) is 5 px from (4.5, 4.5), a hit
    # from d = 5. Success counts 20 + 7 + 0 + 0 = 27 of 84 -> 9/28; P@20 3/4.
    s = scores([GT, [5, 0, 10, 10], NAN, [0, 0, 0, 10]], [GT] * 4, "got10k")
    assert s["success_auc"] == pytest.approx(27 / 84)
    assert s["precision_20"] == 0.75 and s["precision_curve"][4] == 0.25


def test_otb_repairs_frame_two_from_the_trackers_own_frame_one():
    # calcSeqErrRobust repairs before it sets frame 1 to the truth: a NaN f2
    # takes the tracker's f1 (100,100,10,10): IoU 0, error 100*sqrt(2).
    # AUC (20 + 0)/42 = 10/21; P@20 1/2.
    s = scores([[100, 100, 10, 10], NAN], [GT] * 2, "otb")
    assert s["success_auc"] == pytest.approx(10 / 21) and s["precision_20"] == 0.5


def test_otb_does_not_repair_where_the_truth_is_nan():
    # f2: truth NaN, so its NaN result is kept; f3's NaN result then copies
    # f2's NaN: IoU NaN (miss), error NaN (miss). Overlaps [1, -1, NaN]:
    # success 20/63; precision: f1 hit, f2 -1 <= d hit, f3 miss -> 2/3.
    s = scores([GT, NAN, NAN], [GT, NAN, GT], "otb")
    assert s["success_auc"] == pytest.approx(20 / 63) and s["precision_20"] == pytest.approx(2 / 3)


def test_missing_ground_truth_otb_counts_vs_got10k_excludes():
    # Truth NaN at f2; result f3 (30,0,10,10): IoU 0, error 30.
    result, truth = [GT, GT, [30, 0, 10, 10], GT], [GT, NAN, GT, GT]
    otb = scores(result, truth, "otb")
    # otb: overlaps [1, -1, 0, 1], errors [0, -1, 30, 0], 4 frames.
    # success: 2 of 4 at t = 0..0.95 (IoU 0 is not > 0) -> curve 0.5, AUC 20*0.5/21 = 10/21.
    assert otb["frames"] == 4 and otb["success_curve"] == [0.5] * 20 + [0.0]
    assert otb["success_auc"] == pytest.approx(10 / 21)
    # precision: -1 <= d for every d, so f2 is a HIT (the toolkit's rule): 3/4 at 20, 4/4 at 30.
    assert otb["precision_20"] == 0.75 and otb["precision_curve"][30] == 1.0 and otb["precision_curve"][0] == 0.75
    got = scores(result, truth, "got10k")
    # got10k: f2 dropped, 3 frames: success 2/3 -> AUC 40/63; P@20 2/3; 3/3 at 30.
    assert got["frames"] == 3 and got["success_auc"] == pytest.approx(40 / 63)
    assert got["precision_20"] == pytest.approx(2 / 3) and got["precision_curve"][30] == 1.0


@pytest.mark.parametrize("convention", ope.CONVENTIONS)
def test_exact_threshold_ties(convention):
    # f2 (0,0,20,10): IoU 100/200 = 0.5 exactly -> not a success at t = 0.5
    # (index 10), a success at 0.45. f3 (12,16,10,10): centre error
    # sqrt(12^2 + 16^2) = 20 exactly -> a precision hit at d = 20, not at 19.
    s = scores([GT, [0, 0, 20, 10], [12, 16, 10, 10]], [GT] * 3, convention)
    assert s["success_curve"][9] == pytest.approx(2 / 3)  # f1, f2 (f3 does not overlap: IoU 0)
    assert s["success_curve"][10] == pytest.approx(1 / 3)  # f1 only
    assert s["precision_curve"][20] == 1.0 and s["precision_curve"][19] == pytest.approx(2 / 3)


def test_length_mismatch():
    truth = np.array([GT] * 3, float)
    short = np.array([GT, [5, 0, 10, 10]], float)
    res, tr, note = ope.align(short, truth, "otb")
    assert len(res) == 3 and res[2].tolist() == [5, 0, 10, 10] and "padded" in note
    res, tr, note = ope.align(short, truth, "got10k")
    assert len(res) == 2 and len(tr) == 2 and "cut" in note
    res, tr, note = ope.align(np.array([GT] * 5, float), truth, "otb")
    assert len(res) == 3 and "ignored" in note
    assert ope.align(truth, truth)[2] is None


def test_average_and_matlab_zero_curve_drop():
    a = {"success_curve": [1.0] * 20 + [0.0], "precision_curve": [1.0] * 51}
    z = {"success_curve": [0.0] * 21, "precision_curve": [0.0] * 51}
    plain = ope.average([a, z])
    assert plain["success_auc"] == pytest.approx(10 / 21) and plain["precision_20"] == 0.5
    dropped = ope.average([a, z], drop_zero_curves=True)
    assert dropped["success_auc"] == pytest.approx(20 / 21) and dropped["precision_20"] == 1.0


# ----------------------------------------------------------------------------- files


def test_separators_nan_and_malformed_lines(tmp_path):
    p = tmp_path / "r.txt"
    p.write_text("1,2,3,4\n5\t6\t7\t8\n9 10  11 12\nNaN,NaN,NaN,NaN\n1,nan,3,4\n\n")
    boxes = ope.read_boxes(str(p))
    assert boxes.shape == (5, 4) and boxes[:3].tolist() == [[1, 2, 3, 4], [5, 6, 7, 8], [9, 10, 11, 12]]
    assert np.isnan(boxes[3:]).all()
    p.write_text("1,2,3,4\n1,2,3,4\n1,2,x,4\n")
    with pytest.raises(ope.OpeError, match=r"r\.txt:3: expected 4 numbers.*'1,2,x,4'"):
        ope.read_boxes(str(p))
    p.write_text("1,2,3\n")
    with pytest.raises(ope.OpeError, match=r"r\.txt:1:"):
        ope.read_boxes(str(p))


def _write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)


def _boxes(rows):
    return "".join(",".join("%g" % v for v in r) + "\n" for r in rows)


def make_tree(root):
    """Sequences A (SV), B (SV, OCC), C (OCC from attributes_per_frame.csv), 2 frames each.
    Tracker "good": A exact (AUC 20/21, P 1); B f2 far (AUC 10/21, P 1/2);
    C f2 (0,0,20,10): IoU 0.5 -> 10 thresholds, AUC 30/42 = 5/7, error 5 -> P 1.
    Tracker "bad": only sequence A, f2 far: AUC 10/21, P 1/2."""
    seqs, res = os.path.join(root, "seqs"), os.path.join(root, "results")
    _write(os.path.join(seqs, "attribute_names.txt"), "SV\tScale Variation\nOCC\tOcclusion\n")
    for name in "ABC":
        _write(os.path.join(seqs, name, "groundtruth_rect.txt"), _boxes([GT, GT]))
    _write(os.path.join(seqs, "A", "attributes.txt"), "1,0\n")
    _write(os.path.join(seqs, "B", "attributes.txt"), "1,1\n")
    _write(os.path.join(seqs, "C", "attributes_per_frame.csv"), "SV,OCC\n0,0\n0,1\n")
    _write(os.path.join(res, "good", "A.txt"), _boxes([GT, GT]))
    _write(os.path.join(res, "good", "B.txt"), _boxes([GT, [100, 100, 10, 10]]))
    _write(os.path.join(res, "good", "C.txt"), _boxes([GT, [0, 0, 20, 10]]))
    _write(os.path.join(res, "bad", "A.txt"), _boxes([GT, [100, 100, 10, 10]]))
    return seqs, res


def test_per_attribute_averaging(tmp_path):
    seqs, res = make_tree(str(tmp_path))
    report = ope.evaluate(seqs, res)
    assert report["attributes"]["SV"]["sequences"] == ["A", "B"]
    assert report["attributes"]["OCC"] == {"name": "Occlusion", "sequences": ["B", "C"]}
    good = report["trackers"]["good"]
    # overall (A, B, C): AUC (20 + 10 + 15)/21/3 = 5/7; P@20 (1 + 1/2 + 1)/3 = 5/6.
    assert good["success_auc"] == pytest.approx(5 / 7) and good["precision_20"] == pytest.approx(5 / 6)
    sv, occ = good["per_attribute"]["SV"], good["per_attribute"]["OCC"]
    # SV (A, B): (20/21 + 10/21)/2 = 5/7, P (1 + 1/2)/2 = 3/4.
    assert sv["sequences"] == 2 and sv["success_auc"] == pytest.approx(5 / 7) and sv["precision_20"] == 0.75
    # OCC (B, C): (10/21 + 15/21)/2 = 25/42, P (1/2 + 1)/2 = 3/4.
    assert occ["sequences"] == 2 and occ["success_auc"] == pytest.approx(25 / 42) and occ["precision_20"] == 0.75
    assert len(sv["success_curve"]) == 21 and len(sv["precision_curve"]) == 51
    bad = report["trackers"]["bad"]
    assert bad["skipped"] == ["B", "C"] and bad["sequences"] == 1 and bad["success_auc"] == pytest.approx(10 / 21)
    assert list(bad["per_attribute"]) == ["SV"]  # it has no OCC sequence
    assert any("bad" in w and "B.txt" in w for w in report["warnings"])
    with pytest.raises(ope.OpeError, match="missing"):
        ope.evaluate(seqs, res, require_all=True)


def test_got10k_skips_a_sequence_without_visible_target_and_unknown_trackers_fail(tmp_path):
    seqs, res = make_tree(str(tmp_path))
    _write(os.path.join(seqs, "C", "groundtruth_rect.txt"), "NaN,NaN,NaN,NaN\nnan\tnan\tnan\tnan\n")
    good = ope.evaluate(seqs, res, "got10k")["trackers"]["good"]
    # A and B only: AUC (20/21 + 10/21)/2 = 5/7, P@20 3/4.
    assert good["skipped"] == ["C"] and good["success_auc"] == pytest.approx(5 / 7) and good["precision_20"] == 0.75
    # otb keeps C: f1 := truth (NaN) and both frames invalid: overlap -1 (miss), error -1 (hit):
    # C scores AUC 0, P 1 -> overall AUC (20/21 + 10/21 + 0)/3 = 10/21, P (1 + 1/2 + 1)/3 = 5/6.
    good = ope.evaluate(seqs, res, "otb")["trackers"]["good"]
    assert good["success_auc"] == pytest.approx(10 / 21) and good["precision_20"] == pytest.approx(5 / 6)
    with pytest.raises(ope.OpeError, match="nosuch"):
        ope.evaluate(seqs, res, trackers=["good", "nosuch"])


def test_no_attribute_names_means_no_attribute_results(tmp_path):
    seqs, res = make_tree(str(tmp_path))
    os.remove(os.path.join(seqs, "attribute_names.txt"))
    report = ope.evaluate(seqs, res, trackers=["good"])
    assert report["attributes"] == {} and report["trackers"]["good"]["per_attribute"] == {}
    assert list(report["trackers"]) == ["good"]


def test_cli_end_to_end(tmp_path):
    seqs, res = make_tree(str(tmp_path))
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=os.path.join(REPO_ROOT, "clients", "python"), MPLBACKEND="Agg")
    run = subprocess.run([sys.executable, "-m", "sim4cv.ope", "--sequences", seqs, "--results", res,
                          "--out", str(out)], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert run.returncode == 0, run.stderr
    report = json.loads((out / "ope.json").read_text())
    assert {"convention", "sequences", "trackers", "warnings", "attributes"} <= set(report)
    assert report["convention"] == "otb" and report["sequences"] == ["A", "B", "C"]
    good = report["trackers"]["good"]
    assert {"success_auc", "precision_20", "per_sequence", "per_attribute"} <= set(good)
    assert set(good["per_sequence"]["C"]) >= {"success_auc", "precision_20", "success_curve", "precision_curve"}
    assert good["per_sequence"]["C"]["success_auc"] == pytest.approx(5 / 7)
    assert set(good["per_attribute"]["SV"]) >= {"success_auc", "precision_20", "success_curve",
                                                 "precision_curve", "sequences"}
    pngs = ["success_overall.png", "precision_overall.png", "success_SV.png", "precision_SV.png",
            "success_OCC.png", "precision_OCC.png"]
    if importlib.util.find_spec("matplotlib") is None:  # no matplotlib: JSON only, and it says so
        assert report["plots"] == [] and any(w.startswith("plots skipped") for w in report["warnings"])
        return
    for name in pngs:
        data = (out / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 1000, name
    assert sorted(report["plots"]) == sorted(pngs)
    assert "bad" in run.stderr and "missing" in run.stderr
    assert "good" in run.stdout


def test_cli_names_the_malformed_file_and_line(tmp_path, capsys):
    seqs, res = make_tree(str(tmp_path))
    _write(os.path.join(res, "good", "B.txt"), "0,0,10,10\n0;0;10;10\n")
    rc = ope_cli.main(["--sequences", seqs, "--results", res, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2 and os.path.join(res, "good", "B.txt") + ":2:" in err and "0;0;10;10" in err
    assert not (tmp_path / "out" / "ope.json").exists()


def test_cli_without_matplotlib_still_writes_json(tmp_path, monkeypatch, capsys):
    seqs, res = make_tree(str(tmp_path))
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # makes "import matplotlib" raise ImportError
    monkeypatch.delitem(sys.modules, "sim4cv.ope_plots", raising=False)
    monkeypatch.delattr("sim4cv.ope_plots", raising=False)
    out = tmp_path / "out"
    rc = ope_cli.main(["--sequences", seqs, "--results", res, "--out", str(out), "--convention", "got10k"])
    assert rc == 0
    report = json.loads((out / "ope.json").read_text())
    assert report["plots"] == [] and report["convention"] == "got10k"
    assert any(w.startswith("plots skipped") for w in report["warnings"])
    assert "plots skipped" in capsys.readouterr().err
    assert not list(out.glob("*.png"))


def test_legend_is_sorted_by_score_like_the_papers():
    pytest.importorskip("matplotlib")
    from sim4cv import ope_plots
    entries = [("a", {"success_auc": 0.4, "precision_20": 0.9}), ("b", {"success_auc": 0.6, "precision_20": 0.5}),
               ("c", {"success_auc": 0.6, "precision_20": 0.7})]
    assert [n for n, _ in ope_plots.ranked(entries, "success")] == ["b", "c", "a"]  # tie 0.6: by name
    assert [n for n, _ in ope_plots.ranked(entries, "precision")] == ["a", "c", "b"]
