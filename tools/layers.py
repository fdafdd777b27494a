#!/usr/bin/env python3
"""The server's layers, written down once, and the include graph between them.

Each folder under server/ is a layer; a file may include its own layer and the
layers listed for it below (and protocol/, which is below every layer). The
architecture test (tests/architecture/test_layers.py) fails on any other
include, and on any header of the physics engine reached by a layer that must
not know it. Run this file to print the graph as it is:

    /usr/bin/python3 tools/layers.py            # layer -> layers it includes, with counts
    /usr/bin/python3 tools/layers.py --check    # the violations, exit 1 if any
"""
from __future__ import annotations

import argparse
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent

# Bottom to top. The value is what the layer may include besides itself.
LAYERS: dict[str, frozenset[str]] = {
    "common": frozenset(),                               # logging, checks, files beneath a folder
    "sim": frozenset({"common"}),                        # Scene, State, World (Bullet), maps, traffic, logs
    "codec": frozenset({"common"}),                      # JPEG
    "wire": frozenset({"common", "sim"}),                # domain values <-> protocol messages
    "render": frozenset({"common", "sim", "codec", "wire"}),  # GL context, renderer, meshes, ground truth
    "session": frozenset({"common", "sim", "wire", "render"}),  # protocol rules, scheduler, frames
    "transport": frozenset({"common", "wire", "codec", "session"}),  # bytes on sockets and shared memory
    "daemon": frozenset({"common", "sim", "codec", "wire", "render", "session", "transport"}),  # wiring
}

# Layers that must not reach the physics engine's headers, even through other
# headers: they see vehicles through car_params.h / quadcopter_params.h.
PHYSICS_FREE = ("common", "codec", "wire", "render", "session", "transport")
PHYSICS_HEADER = re.compile(r'#include\s*<(btBulletDynamicsCommon|btBulletCollisionCommon|BulletDynamics/|'
                            r'BulletCollision/|LinearMath/)')
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)
SOURCES = (".h", ".hpp", ".cpp", ".cc")


def layer_of(path: pathlib.Path) -> str | None:
    """The layer of a file under server/ (its first folder), or None."""
    parts = path.relative_to(ROOT).parts
    return parts[1] if len(parts) > 2 and parts[0] == "server" else None


def server_files() -> list[pathlib.Path]:
    return sorted(p for p in (ROOT / "server").rglob("*") if p.suffix in SOURCES)


def resolve(including: pathlib.Path, name: str) -> pathlib.Path | None:
    """The file an #include "name" means: relative to the repository, else to the including file."""
    for base in (ROOT, including.parent):
        candidate = base / name
        if candidate.is_file():
            return candidate.resolve()
    return None


def includes(path: pathlib.Path) -> list[tuple[int, str, pathlib.Path | None]]:
    """(line number, written name, resolved file) of every quoted include."""
    text = path.read_text(errors="replace")
    found = []
    for match in INCLUDE.finditer(text):
        line = text.count("\n", 0, match.start()) + 1
        found.append((line, match.group(1), resolve(path, match.group(1))))
    return found


def layer_violations() -> list[str]:
    """'file:line: layer includes other-layer (name)' for every include the table does not allow."""
    problems = []
    for path in server_files():
        layer = layer_of(path)
        if layer not in LAYERS:
            problems.append(f"{path.relative_to(ROOT)}: folder server/{layer}/ is not in the layer table (tools/layers.py)")
            continue
        for line, name, target in includes(path):
            target_layer = layer_of(target) if target and ROOT in target.parents else None
            if target_layer and target_layer != layer and target_layer not in LAYERS[layer]:
                problems.append(f"{path.relative_to(ROOT)}:{line}: {layer} includes {target_layer} ({name})")
    return problems


def physics_reached() -> list[str]:
    """'file: reaches Bullet through a -> b -> c' for every physics-free file that reaches it."""
    memo: dict[pathlib.Path, list[pathlib.Path] | None] = {}

    def chain(path: pathlib.Path, visiting: set[pathlib.Path]) -> list[pathlib.Path] | None:
        if path in memo:
            return memo[path]
        if PHYSICS_HEADER.search(path.read_text(errors="replace")):
            memo[path] = [path]
            return memo[path]
        visiting.add(path)
        result = None
        for _, _, target in includes(path):
            if target is None or target in visiting or ROOT not in target.parents:
                continue
            below = chain(target, visiting)
            if below:
                result = [path] + below
                break
        visiting.discard(path)
        memo[path] = result
        return result

    problems = []
    for path in server_files():
        if layer_of(path) in PHYSICS_FREE:
            found = chain(path.resolve(), set())
            if found:
                route = " -> ".join(str(p.relative_to(ROOT)) for p in found)
                problems.append(f"{path.relative_to(ROOT)}: reaches the physics engine through {route}")
    return problems


def graph() -> dict[tuple[str, str], int]:
    """(layer, included layer) -> number of includes, between different layers."""
    edges: dict[tuple[str, str], int] = {}
    for path in server_files():
        layer = layer_of(path)
        for _, _, target in includes(path):
            target_layer = layer_of(target) if target and ROOT in target.parents else None
            if target_layer and target_layer != layer:
                edges[(layer, target_layer)] = edges.get((layer, target_layer), 0) + 1
    return edges


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="print the violations; exit 1 if there are any")
    args = parser.parse_args(argv)
    if args.check:
        problems = layer_violations() + physics_reached()
        print("\n".join(problems) if problems else "no layer violations")
        return 1 if problems else 0
    edges = graph()
    for layer in LAYERS:
        out = ", ".join(f"{b} ({n})" for (a, b), n in sorted(edges.items()) if a == layer)
        print(f"{layer:>9} -> {out or '(nothing)'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
