"""The Python client as a package: its protocol module is the one protoc
makes from protocol/sim4cv.proto today, importing it never runs protoc, and
it installs offline with pip from Debian's packages alone."""

import filecmp
import os
import shutil
import subprocess
import sys

from conftest import REPO_ROOT

PACKAGE_ROOT = os.path.join(REPO_ROOT, "clients", "python")


def test_generated_module_matches_the_proto(tmp_path):
    subprocess.run(["protoc", "--proto_path=" + os.path.join(REPO_ROOT, "protocol"), "--python_out=" + str(tmp_path),
                    os.path.join(REPO_ROOT, "protocol", "sim4cv.proto")], check=True)
    shipped = os.path.join(PACKAGE_ROOT, "sim4cv", "sim4cv_pb2.py")
    assert filecmp.cmp(str(tmp_path / "sim4cv_pb2.py"), shipped, shallow=False), (
        "clients/python/sim4cv/sim4cv_pb2.py is stale: protocol/sim4cv.proto changed; "
        "run bash scripts/gen_python_proto.sh and commit the result")


def _import_in_a_fresh_interpreter(path_entry, env_path, cwd):
    script = ("import sim4cv; e = sim4cv.pb.Envelope(); e.next_frame.SetInParent(); "
              "print(sim4cv.__file__, sim4cv.Client.__name__, e.WhichOneof('kind'))")
    env = dict(os.environ, PYTHONPATH=path_entry, PATH=env_path)
    return subprocess.run([sys.executable, "-c", script], env=env, cwd=cwd, check=True,
                          stdout=subprocess.PIPE, text=True).stdout.split()


def test_importing_needs_no_protoc(tmp_path):
    # No PATH at all: a protoc run at import would fail.
    module, client, kind = _import_in_a_fresh_interpreter(PACKAGE_ROOT, "", str(tmp_path))
    assert module.startswith(PACKAGE_ROOT) and client == "Client" and kind == "next_frame"


def test_pip_installs_it_offline(tmp_path):
    source = tmp_path / "source"
    shutil.copytree(PACKAGE_ROOT, source, ignore=shutil.ignore_patterns("__pycache__", "build", "*.egg-info"))
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-build-isolation", "--no-deps", "--no-index",
                    "--quiet", "--disable-pip-version-check", "--target", str(target), str(source)],
                   check=True, env=dict(os.environ, PIP_NO_CACHE_DIR="1"))
    module, client, kind = _import_in_a_fresh_interpreter(str(target), os.environ.get("PATH", ""), str(tmp_path))
    assert module.startswith(str(target)) and client == "Client" and kind == "next_frame"
