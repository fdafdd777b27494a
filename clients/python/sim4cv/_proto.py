"""Loads the protobuf classes generated from protocol/sim4cv.proto.

The .proto is the single source of truth: on import, ``protoc --python_out``
(Debian package protobuf-compiler) generates ``sim4cv_pb2.py`` into a cache
directory unless an up-to-date copy is already there. "Up to date" means the
SHA-256 of the .proto recorded next to the generated file matches the .proto
now, so a stale copy is regenerated even if file times are misleading.

Environment overrides:
  SIM4CV_PROTO      path of sim4cv.proto (default: <repo>/protocol/sim4cv.proto)
  SIM4CV_PROTO_CACHE directory for the generated module
                    (default: this package's _generated/, or
                    $XDG_CACHE_HOME/sim4cv if that is not writable)
  SIM4CV_PROTOC     protoc executable (default: protoc on PATH)
"""

import hashlib
import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile

_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))
_MODULE_NAME = "sim4cv._generated.sim4cv_pb2"


def _proto_path():
    path = os.environ.get("SIM4CV_PROTO")
    if path:
        return os.path.abspath(path)
    # clients/python/sim4cv/ -> repository root is three levels up.
    root = os.path.dirname(os.path.dirname(os.path.dirname(_PACKAGE_DIR)))
    return os.path.join(root, "protocol", "sim4cv.proto")


def _candidate_cache_dirs():
    env = os.environ.get("SIM4CV_PROTO_CACHE")
    if env:
        return [env]
    xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return [os.path.join(_PACKAGE_DIR, "_generated"), os.path.join(xdg, "sim4cv")]


def _generate(proto, digest, cache_dir):
    """Runs protoc into a temporary directory, then moves the result into
    place atomically so concurrent importers never see a half-written file."""
    protoc = os.environ.get("SIM4CV_PROTOC") or shutil.which("protoc")
    if not protoc:
        raise ImportError("sim4cv: 'protoc' not found; install Debian's protobuf-compiler "
                          "(or set SIM4CV_PROTOC) to generate the protocol module")
    os.makedirs(cache_dir, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix=".gen-", dir=cache_dir)
    try:
        result = subprocess.run(
            [protoc, "--proto_path=" + os.path.dirname(proto), "--python_out=" + tmp,
             os.path.basename(proto)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if result.returncode != 0:
            raise ImportError("sim4cv: protoc failed on %s:\n%s" % (proto, result.stderr))
        with open(os.path.join(tmp, "sim4cv_pb2.sha256"), "w") as f:
            f.write(digest + "\n")
        # Module first, stamp last: a stamp never vouches for an older module.
        os.replace(os.path.join(tmp, "sim4cv_pb2.py"), os.path.join(cache_dir, "sim4cv_pb2.py"))
        os.replace(os.path.join(tmp, "sim4cv_pb2.sha256"), os.path.join(cache_dir, "sim4cv_pb2.sha256"))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _load():
    proto = _proto_path()
    try:
        with open(proto, "rb") as f:
            digest = hashlib.sha256(f.read()).hexdigest()
    except OSError as e:
        raise ImportError("sim4cv: cannot read the protocol definition %s (%s); "
                          "set SIM4CV_PROTO to its path" % (proto, e)) from e

    last_error = None
    for cache_dir in _candidate_cache_dirs():
        module_path = os.path.join(cache_dir, "sim4cv_pb2.py")
        stamp_path = os.path.join(cache_dir, "sim4cv_pb2.sha256")
        try:
            with open(stamp_path) as f:
                fresh = f.read().strip() == digest and os.path.exists(module_path)
        except OSError:
            fresh = False
        try:
            if not fresh:
                _generate(proto, digest, cache_dir)
        except OSError as e:  # e.g. read-only install location: try the next one
            last_error = e
            continue
        spec = importlib.util.spec_from_file_location(_MODULE_NAME, module_path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[_MODULE_NAME] = module
        spec.loader.exec_module(module)
        return module
    raise ImportError("sim4cv: no writable cache directory for the generated protocol module "
                      "(last error: %s); set SIM4CV_PROTO_CACHE" % last_error)


pb = _load()
