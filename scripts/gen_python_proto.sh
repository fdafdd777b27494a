#!/usr/bin/env bash
# Regenerates the Python client's protocol module, clients/python/sim4cv/sim4cv_pb2.py,
# from protocol/sim4cv.proto with Debian's protoc (protobuf-compiler 3.21). The module is
# shipped in the repository so that importing sim4cv never runs protoc; the Python test
# test_generated_module_matches_the_proto fails when the .proto changed and this was not run.
#   bash scripts/gen_python_proto.sh
set -euo pipefail
cd "$(dirname "$0")/.."
protoc --proto_path=protocol --python_out=clients/python/sim4cv protocol/sim4cv.proto
echo "gen_python_proto: clients/python/sim4cv/sim4cv_pb2.py from protocol/sim4cv.proto ($(protoc --version))"
