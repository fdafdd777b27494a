"""tools/online_control_table.py: a real-time study's cells beside their lockstep
control, from the results.json files the experiment runner writes."""
import json
import os
import subprocess

REPO_ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
TOOL = os.path.join(REPO_ROOT, "tools", "online_control_table.py")


def record(mode, tracker, repetition, completion, lost, skipped=0, fps=100.0, error=""):
    return {"kind": "online", "run": "r", "map": "tracking/easy_urban", "speed": 4.0, "tracker": tracker, "mode": mode,
            "fps": 30.0, "delay_ms": 0.0, "conditions": "", "repetition": repetition, "uav": 0, "wall_s": 1.0,
            "completion": completion, "frames_processed": 10, "frames_skipped": skipped, "tracker_fps": fps,
            "mean_center_error_px": 1.0, "median_center_error_px": 1.0, "mean_distance_m": 1.0, "seconds": 1.0,
            "lost": lost, "error": error, "deviation_from_gt_m": 0.0}


def write(folder, records):
    folder.mkdir()
    (folder / "results.json").write_text(json.dumps(records))
    return str(folder)


def test_realtime_repetitions_beside_the_lockstep_control(tmp_path):
    realtime = write(tmp_path / "rt", [
        record("realtime", "opencv:kcf", 1, 1.0, False, skipped=2, fps=1200.0),
        record("realtime", "opencv:kcf", 2, 0.5, True, skipped=4, fps=1000.0),
        # a task the study has not run yet: gathered part way, it is a placeholder
        record("realtime", "opencv:kcf", 3, 0.0, True, error="missing: task 2 has not run"),
        record("realtime", "gt", 1, 1.0, False)])
    lockstep = write(tmp_path / "ls", [record("lockstep", "opencv:kcf", 1, 1.0, False)])
    proc = subprocess.run(["/usr/bin/python3", TOOL, realtime, lockstep], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    # mean 0.75, sample sd 0.354 over the two runs that ran; skipped and fps averaged
    assert "| easy_urban | 4 | opencv:kcf | 2 | 0.750 (0.354) | 0.500-1.000 | 1/2 | 3 | 1100 | 1.000 | 0/1 |" in lines
    assert "| easy_urban | 4 | gt | 1 | 1.000 (-) | 1.000-1.000 | 0/1 | 0 | 100 | not run | - |" in lines
    assert "Not run yet: 1 real-time and 0 lockstep runs" in proc.stdout
