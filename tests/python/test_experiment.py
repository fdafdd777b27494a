"""sim4cv.experiment end to end: the shipped smoke experiments (online and
offline), resume, and the checks of a bad experiment file (docs/tracking.md,
"Experiments"). Needs build/server/daemon/sim4cvd (or $SIM4CVD)."""

import csv
import glob
import json
import os
import subprocess
import sys

import pytest

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO_ROOT, "clients", "python"))

from sim4cv import experiment  # noqa: E402


def run_cli(*args, timeout=120):
    env = dict(os.environ, PYTHONPATH=os.path.join(REPO_ROOT, "clients", "python"))
    return subprocess.run([sys.executable, "-m", "sim4cv.experiment", "run"] + list(args), cwd=REPO_ROOT, env=env,
                          capture_output=True, text=True, timeout=timeout)


def test_shipped_files_load():
    for path in sorted(glob.glob(os.path.join(REPO_ROOT, "experiments", "*.yaml"))):
        cwd = os.getcwd()
        os.chdir(REPO_ROOT)  # octave: paths are relative to the working directory
        try:
            exp = experiment.load(path)
        finally:
            os.chdir(cwd)
        assert exp["trackers"], path
        if exp["kind"] == "online":
            assert experiment.online_runs(exp)


def test_run_names_and_grouping(tmp_path):
    path = tmp_path / "g.yaml"
    path.write_text("maps: [tracking/easy_urban]\nspeeds: [4, 8]\ntrackers: [gt, 'opencv:kcf', 'opencv:mosse']\n"
                    "uavs_per_run: 2\nrepetitions: 2\n")
    runs = experiment.online_runs(experiment.load(str(path)))
    assert len(runs) == 2 * 2 * 2  # speeds x repetitions x tracker groups (2 + 1)
    assert [r["session"]["trackers"] for r in runs[:2]] == [["gt", "opencv:kcf"], ["opencv:mosse"]]
    assert len({r["name"] for r in runs}) == len(runs)
    # a delay means nothing in lockstep: its runs are made at delay 0 only, the control of the realtime ones
    path.write_text("kind: online\nmodes: [realtime, lockstep]\ndelays_ms: [0, 100]\n")
    runs = experiment.online_runs(experiment.load(str(path)))
    assert sorted((r["session"]["mode"], r["session"]["delay_ms"]) for r in runs) == [
        ("lockstep", 0.0), ("realtime", 0.0), ("realtime", 100.0)]


@pytest.mark.parametrize("text, named", [
    ("kind: online\nmaps: [tracking/easy_urban]\nspeed: [8]\n", "speed"),
    ("kind: online\ntrackers: [gt, 'opencv:nosuch']\n", "opencv:nosuch"),
    ("kind: online\ntrackers: [gt, 'fancy:tracker']\n", "fancy:tracker"),
    ("kind: online\nmaps: [tracking/nowhere]\n", "tracking/nowhere"),
    ("kind: online\nmodes: [fast]\n", "modes"),
    ("kind: online\nmodes: [lockstep]\ndelays_ms: [0, 200]\n", "delays_ms: [0.0, 200.0] needs modes: [realtime]"),
    ("kind: offline\nsequences: {maps: [tracking/easy_urban], frame: 10}\ntrackers: [gt]\n", "frame"),
])
def test_bad_file_fails_before_any_run(tmp_path, text, named):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    proc = run_cli(str(path), "--out", str(out), timeout=30)
    assert proc.returncode == 2, proc.stderr
    assert named in proc.stderr and "error" in proc.stderr
    assert not out.exists()  # nothing started


def test_smoke_online_and_resume(tmp_path):
    out = tmp_path / "smoke"
    proc = run_cli("experiments/smoke.yaml", "--out", str(out), "--jobs", "1")
    assert proc.returncode == 0, proc.stderr
    assert "[2/2]" in proc.stderr and "left" in proc.stderr
    records = json.loads((out / "results.json").read_text())
    assert sorted(r["tracker"] for r in records) == ["gt", "opencv:kcf"]
    for r in records:
        for key in ("map", "speed", "tracker", "mode", "fps", "delay_ms", "repetition", "completion",
                    "frames_processed", "frames_skipped", "tracker_fps", "mean_center_error_px", "lost", "error"):
            assert key in r, key
        assert r["map"] == "tracking/easy_urban" and r["speed"] == 8 and r["mode"] == "lockstep"
        assert r["error"] == "" and r["frames_processed"] > 200 and r["completion"] > 0.5
    deviation = {r["tracker"]: r["deviation_from_gt_m"] for r in records}
    assert deviation["gt"] == 0.0 and deviation["opencv:kcf"] >= 0.0, deviation  # the gt run is the reference
    with open(out / "results.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 and "completion" in rows[0]
    report = (out / "report.md").read_text()
    assert "opencv:kcf" in report and "sim4cv.experiment run experiments/smoke.yaml" in report
    assert "nproc" in report and "wall time" in report
    assert (out / "plots" / "completion.png").stat().st_size > 1000
    assert (out / "plots" / "trajectories_tracking_easy_urban_s8.png").stat().st_size > 1000
    assert "trajectories_tracking_easy_urban_s8.png" in report
    # resume: every run is skipped
    again = run_cli("experiments/smoke.yaml", "--out", str(out), "--jobs", "1")
    assert again.returncode == 0, again.stderr
    assert again.stderr.count("skipped (done before)") == 2
    assert len(json.loads((out / "results.json").read_text())) == 2
    # an interrupted run (no session.json) is redone; the other one is kept
    runs = sorted(glob.glob(str(out / "runs" / "*")))
    os.remove(os.path.join(runs[0], "session.json"))
    third = run_cli("experiments/smoke.yaml", "--out", str(out), "--jobs", "1")
    assert third.returncode == 0 and third.stderr.count("skipped (done before)") == 1
    assert os.path.exists(os.path.join(runs[0], "session.json"))


def test_smoke_offline(tmp_path):
    out = tmp_path / "offline"
    proc = run_cli("experiments/smoke_offline.yaml", "--out", str(out), "--jobs", "1")
    assert proc.returncode == 0, proc.stderr
    seqs = sorted(os.listdir(out / "results" / "opencv_kcf"))
    assert seqs == ["easy_urban_s8.txt", "easy_urban_s8_time.txt", "hard_urban_s8.txt", "hard_urban_s8_time.txt"]
    lines = (out / "results" / "opencv_kcf" / "easy_urban_s8.txt").read_text().splitlines()
    assert len(lines) == 40 and len(lines[0].split(",")) == 4
    ope = json.loads((out / "ope" / "ope.json").read_text())
    # gt and the baselines are run in every offline study, beside the trackers asked for
    assert set(ope["trackers"]) == {"gt", "opencv_kcf", "baseline_static", "baseline_centre"}
    assert ope["trackers"]["gt"]["precision_20"] == 1.0
    assert ope["trackers"]["opencv_kcf"]["sequences"] == 2
    report = (out / "report.md").read_text()
    assert "success_auc" in report and "ope/success_overall.png" in report
    assert "| baseline:static |" in report and "| sr_50 | sr_75 | ao | norm_precision_20 |" in report
    records = json.loads((out / "results.json").read_text())
    assert len(records) == 8 and all(r["tracker_fps"] > 0 and r["fps_per_frame"] > 0 for r in records)
    again = run_cli("experiments/smoke_offline.yaml", "--out", str(out), "--jobs", "1")
    assert again.returncode == 0 and again.stderr.count("skipped (done before)") == 8


def test_report_of_repetitions_with_equal_completions(tmp_path):
    """Three real-time runs that all ended at 0.094: their mean rounds to
    0.09400000000000001, and the plot's min-max bars must not go negative
    (the paper-scale study's gather failed there)."""
    from sim4cv import experiment_report
    base = {"kind": "online", "map": "tracking/easy_urban", "speed": 4.0, "tracker": "opencv:mosse",
            "mode": "realtime", "fps": 30.0, "delay_ms": 0.0, "conditions": "", "uav": 0, "wall_s": 1.0,
            "completion": 0.094, "frames_processed": 10, "frames_skipped": 0, "tracker_fps": 100.0,
            "mean_center_error_px": 1.0, "median_center_error_px": 1.0, "mean_distance_m": 1.0, "seconds": 1.0,
            "lost": True, "error": "", "deviation_from_gt_m": 1.0}
    records = [dict(base, run="r%d" % i, repetition=i) for i in (1, 2, 3)]
    exp = {"name": "equal", "kind": "online", "trackers": ["opencv:mosse"], "seconds": 1.0}
    experiment_report.write_all(exp, records, str(tmp_path), "test", 1.0)
    assert (tmp_path / "plots" / "completion.png").stat().st_size > 0
    assert "| tracking/easy_urban | 4 | opencv:mosse | realtime |" in (tmp_path / "report.md").read_text()
