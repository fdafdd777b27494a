"""Each example in clients/python/examples runs against the real daemon."""

import os
import subprocess
import sys

import pytest

from conftest import REPO_ROOT

EXAMPLES = os.path.join(REPO_ROOT, "clients", "python", "examples")


def _run(script, address, *extra):
    result = subprocess.run([sys.executable, os.path.join(EXAMPLES, script), "--address", address,
                             "--frames", "8"] + list(extra), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, timeout=60)
    assert result.returncode == 0, result.stdout
    return result.stdout


@pytest.mark.parametrize("transport", ["tcp", "shm"])
def test_opencv_tracker(start_transports_daemon, transport):
    pytest.importorskip("cv2", reason="needs Debian's python3-opencv")
    daemon = start_transports_daemon()
    out = _run("opencv_tracker.py", daemon.address(transport))
    assert "tracked 8 frames with kcf" in out and "mean IoU" in out
    assert float(out.split("mean IoU")[1]) > 0.3


def test_drive(start_transports_daemon):
    daemon = start_transports_daemon()
    out = _run("drive.py", daemon.address("udp"), "--throttle", "1")
    assert "drove car 1 for 8 frames" in out


def test_record_dataset(start_transports_daemon, tmp_path):
    daemon = start_transports_daemon()
    out = _run("record_dataset.py", daemon.address("shm"), "--out", str(tmp_path / "data"))
    assert "recorded 8 frames" in out
    files = sorted(os.listdir(tmp_path / "data"))
    assert files == ["%06d.png" % i for i in range(1, 9)] + ["boxes.csv"]
    with open(tmp_path / "data" / "000001.png", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    rows = (tmp_path / "data" / "boxes.csv").read_text().splitlines()
    assert rows[0].startswith("frame_id,file,object_id") and len(rows) > 8
    try:
        import cv2
    except ImportError:
        return
    image = cv2.imread(str(tmp_path / "data" / "000001.png"))
    assert image.shape == (180, 320, 3) and image.any()
