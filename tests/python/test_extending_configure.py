"""GetWorld, the worked example of a Configure request carried out by a file
of its own (server/daemon/configure/get_world.cpp, one line in
configure_requests.cpp's table; docs/architecture.md, "Extending sim4cv"),
answered by the real daemon."""

import os

import sim4cv
from conftest import REPO_ROOT

MAP = os.path.join(REPO_ROOT, "scenes", "tracking", "easy_urban.map")


def connected(start_daemon, *flags):
    client = sim4cv.Client()
    start_daemon.clients.append(client)
    client.connect("127.0.0.1", start_daemon(*flags).port, "extending")
    return client


def test_get_world_gives_the_map_text_of_a_map_and_none_of_a_scene(start_daemon):
    on_map = connected(start_daemon, "--map", MAP)
    text = on_map.get_map_text()
    assert text.startswith("sim4cv-map 1"), text[:80]
    assert on_map.get_world().frame_id == 0  # only asks: the world does not move
    assert connected(start_daemon).get_map_text() == ""


def test_get_world_lists_what_the_world_holds(start_daemon):
    world = connected(start_daemon).get_world()
    assert [c.name for c in world.cameras][:1] == ["uav"]
    assert {e.id for e in world.entities} >= {1, 2}
