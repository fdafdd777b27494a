"""The server's layers (tools/layers.py): no file includes a layer above its
own or beside it unless the table allows it, and the layers that must not know
the physics engine do not reach its headers through any include."""
import pathlib
import sys

import pytest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "tools"))
import layers  # noqa: E402


def test_no_include_breaks_the_layer_table():
    assert layers.layer_violations() == []


def test_physics_free_layers_do_not_reach_bullet():
    assert layers.physics_reached() == []


@pytest.fixture
def fake_tree(tmp_path, monkeypatch):
    """A server/ tree of our own, so the checks are shown to find what they look for."""
    monkeypatch.setattr(layers, "ROOT", tmp_path)

    def write(name, text):
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return write


def test_a_back_arrow_is_named_with_file_line_and_layers(fake_tree):
    fake_tree("server/session/frame.h", "#pragma once\n")
    fake_tree("server/render/scene.cpp", '// draws\n#include "server/session/frame.h"\n')
    assert layers.layer_violations() == [
        "server/render/scene.cpp:2: render includes session (server/session/frame.h)"]


def test_a_folder_missing_from_the_table_is_reported(fake_tree):
    fake_tree("server/gadgets/thing.cpp", "int x;\n")
    assert layers.layer_violations() == [
        "server/gadgets/thing.cpp: folder server/gadgets/ is not in the layer table (tools/layers.py)"]


def test_bullet_reached_through_a_sim_header_is_reported_with_its_route(fake_tree):
    fake_tree("server/sim/vehicles/car.h", "#include <btBulletDynamicsCommon.h>\n")
    fake_tree("server/sim/scene.h", '#include "server/sim/vehicles/car.h"\n')
    fake_tree("server/render/draw.cpp", '#include "server/sim/scene.h"\n')
    fake_tree("server/daemon/main.cpp", '#include "server/sim/scene.h"\n')  # the daemon may know Bullet
    assert layers.physics_reached() == [
        "server/render/draw.cpp: reaches the physics engine through server/render/draw.cpp -> "
        "server/sim/scene.h -> server/sim/vehicles/car.h"]
