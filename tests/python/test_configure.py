"""Integration tests of the Python client's world requests (Client.configure
and the methods built on it) against the real sim4cvd (fixtures: conftest.py).
Default scene: car 1 drives the road loop, UAV 2 films it."""

import math
import os
import time

import pytest

import sim4cv
from sim4cv import ServerError, image_array, pb

CAR_ID = 1
TIMEOUT_S = 20.0


def refused(call, code, *parts):
    """call() must raise a non-fatal ServerError with `code` that answers a
    Configure and names every one of `parts`."""
    with pytest.raises(ServerError) as caught:
        call()
    error = caught.value
    assert error.code == code, error
    assert not error.fatal and error.request_id != 0, error
    for part in parts:
        assert part in error.message, error.message
    return error


def entity(state, entity_id):
    matches = [e for e in state.entities if e.id == entity_id]
    return matches[0] if matches else None


def test_spawn_get_world_and_remove(connect):
    client = connect("configure")
    client.subscribe("uav", ["boxes"], "lockstep", with_state=True)
    uav = client.spawn("uav", "uav_b", -10, -20, 20)
    car = client.spawn(sim4cv.ENTITY_KIND_CAR, "car_b", 0, -25, 0, yaw_deg=90)
    assert (uav, car) == (3, 4)
    world = client.get_world()
    assert [(e.id, e.name, e.kind) for e in world.entities] == [
        (1, "car", pb.ENTITY_KIND_CAR), (2, "uav", pb.ENTITY_KIND_UAV),
        (uav, "uav_b", pb.ENTITY_KIND_UAV), (car, "car_b", pb.ENTITY_KIND_CAR)]

    # In the frames' State; a velocity order moves the UAV east.
    client.uav_velocity(uav, 2, 0, 0)
    for _ in range(60):
        frame = client.step_and_receive(TIMEOUT_S)
    flown = entity(frame.state, uav)
    assert flown.position.x > -10 + 2.0, flown
    assert abs(flown.position.y + 20) < 0.5, flown
    assert entity(frame.state, car).name == "car_b"

    refused(lambda: client.spawn("car", "uav_b", 5, -25, 0), pb.ERROR_CODE_INVALID_ARGUMENT, "'uav_b'")
    refused(lambda: client.remove(99), pb.ERROR_CODE_UNKNOWN_ENTITY, "99")
    assert [e.name for e in client.remove(uav).entities] == ["car", "uav", "car_b"]
    assert entity(client.step_and_receive(TIMEOUT_S).state, uav) is None


def test_added_camera_delivers_frames_until_removed(connect):
    client = connect("configure")
    client.spawn("uav", "uav_b", -40, -60, 20, yaw_deg=90)
    world = client.add_camera("uav_b_cam", mounted_on="uav_b", width=160, height=120, pitch_down_deg=30)
    assert [(c.name, c.width, c.height, c.mounted_on) for c in world.cameras][-1] == ("uav_b_cam", 160, 120, "uav_b")

    client.subscribe("uav_b_cam", ["rgb", "depth"], "lockstep")
    for _ in range(3):
        frame = client.step_and_receive(TIMEOUT_S)
        assert frame.camera == "uav_b_cam"
        assert image_array(frame, "rgb").shape == (120, 160, 3)
        assert image_array(frame, "depth").shape == (120, 160)

    # The Error about the subscription is not remove_camera()'s answer: it
    # comes from the next call that reads.
    world = client.remove_camera("uav_b_cam")
    assert "uav_b_cam" not in [c.name for c in world.cameras]
    with pytest.raises(ServerError) as caught:
        client.receive_frame(TIMEOUT_S)
    assert caught.value.code == pb.ERROR_CODE_UNKNOWN_CAMERA and caught.value.request_id == 0, caught.value
    assert len(client.get_state().entities) == 3, "the connection stays usable"


def test_frames_arriving_during_configure_are_kept(connect):
    client, other = connect("configure"), connect("other")
    client.subscribe("uav", ["boxes"], "lockstep")
    other.subscribe("uav", ["boxes"], "lockstep")
    client.step()
    other.step()
    # Once `other` has frame 1, the daemon has sent it to `client` too: it
    # comes in ahead of (or interleaved with) the answer to get_world().
    assert other.receive_frame(TIMEOUT_S).frame_id == 1
    assert client.get_world().scene_name == "default"
    assert client.receive_frame(TIMEOUT_S).frame_id == 1
    other.step()
    assert client.step_and_receive(TIMEOUT_S).frame_id == 2


def test_query_road_on_a_map(connect):
    client = connect("configure")
    refused(lambda: client.query_road(0, 0), pb.ERROR_CODE_INVALID_STATE, "needs a map scene")
    world = client.load_map_by_name("tracking/easy_desert")
    assert list(world.routes) == ["loop"]
    car = entity(client.get_state(), CAR_ID).position
    at_car = client.query_road(car.x, car.y)
    assert at_car.distance < 0.05 and len(at_car.ahead) == 0, at_car

    heading = at_car.nearest.heading_deg
    h = math.radians(heading)
    x, y = at_car.nearest.position.x - math.sin(h), at_car.nearest.position.y + math.cos(h)
    left = client.query_road(x, y, count=4, step=2, heading_deg=heading)
    assert left.lateral_offset == pytest.approx(1.0, abs=0.02), left
    points = [left.nearest.position] + [p.position for p in left.ahead]
    assert len(points) == 5
    for a, b in zip(points, points[1:]):
        assert math.hypot(b.x - a.x, b.y - a.y) == pytest.approx(2.0, abs=0.05), left


def test_map_text_and_the_shipped_maps(connect):
    client = connect("configure")
    assert client.get_map_text() == ""  # the default scene is a scene file, not a map
    maps = client.list_maps()
    assert {"tracking/easy_desert", "driving/test/01_urban"} <= set(maps) and maps == sorted(maps), maps
    client.load_map_by_name("tracking/easy_desert")
    text = client.get_map_text()
    assert text.startswith("sim4cv-map 1") and "name tracking_easy_desert" in text and "route loop closed" in text
    # The canonical text: loading it gives the same map back, word for word.
    assert client.load_map_text(text).scene_name == "tracking_easy_desert"
    assert client.get_map_text() == text


def test_map_files_generate_and_check(start_daemon, connect, tmp_path):
    """The editor's requests from Python: generate, check, save, open, list,
    load by the saved name; a broken map is not saved."""
    own = start_daemon("--maps-dir", str(tmp_path))
    client = connect("editor", target=own)
    text = client.generate_map(seed=7, width=8, height=6, surroundings="urban", name="mine")
    assert text.startswith("sim4cv-map 1\n# sim4cv_mapgen ") and "name mine\n" in text
    assert "grid 8 6\n" in client.check_map(text)
    client.save_map("studio/mine", text)
    assert (tmp_path / "studio" / "mine.map").read_text() == text
    assert client.open_map("studio/mine") == text and client.list_maps() == ["studio/mine"]
    assert client.load_map_by_name("studio/mine").scene_name == "mine"
    refused(lambda: client.save_map("studio/mine", text), pb.ERROR_CODE_ALREADY_EXISTS, "overwrite")
    refused(lambda: client.save_map("studio/mine", text + "bogus 1\n", overwrite=True), pb.ERROR_CODE_INVALID_ARGUMENT,
            "not saved", "'bogus 1'")
    assert (tmp_path / "studio" / "mine.map").read_text() == text
    refused(lambda: client.open_map("../outside"), pb.ERROR_CODE_INVALID_ARGUMENT, "OpenMap.name '../outside'")


def test_start_and_stop_a_run_log(start_daemon, connect, tmp_path):
    own = start_daemon("--logs-dir", str(tmp_path), "--mode", "realtime")
    client = connect("logger", target=own)
    path = client.start_log("runs/first", label="python")
    assert path == str(tmp_path / "runs" / "first.s4log") and client.get_world().log_file == path
    refused(lambda: client.reset(), pb.ERROR_CODE_INVALID_STATE, "StopLog first")
    assert client.stop_log() == path and client.get_world().log_file == ""
    assert (tmp_path / "runs" / "first.s4log").read_bytes()[:8] == b"S4CVLOG\0"


def test_configure_errors_name_the_problem(connect):
    client = connect("configure")
    refused(lambda: client.load_map_text("sim4cv-map 1\nname broken\ncolour red\n"),
            pb.ERROR_CODE_INVALID_ARGUMENT, "line 3", "colour")
    refused(lambda: client.load_map_by_name("../secret"), pb.ERROR_CODE_INVALID_ARGUMENT, "'..'")
    refused(lambda: client.spawn("uav", "x", math.nan, 0, 20), pb.ERROR_CODE_INVALID_ARGUMENT,
            "Spawn.position.x is nan")
    refused(lambda: client.add_camera("big", width=4000), pb.ERROR_CODE_INVALID_ARGUMENT, "AddCamera.width is 4000")
    refused(lambda: client.configure(pb.Configure()), pb.ERROR_CODE_INVALID_ARGUMENT, "carries no request")
    refused(lambda: client.set_route(CAR_ID, "loop", 5), pb.ERROR_CODE_INVALID_ARGUMENT, "'loop'", "routes: none")
    world = client.get_world()
    assert world.scene_name == "default" and len(world.entities) == 2, "nothing changed"


def test_spawned_pedestrian_walks_its_waypoints(connect):
    client = connect("pedestrian")
    client.subscribe("uav", ["boxes"], "lockstep", with_state=True)
    walker = client.spawn("pedestrian", "", -25, -47, 0)
    world = client.get_world()
    assert [e.kind for e in world.entities if e.id == walker] == [sim4cv.ENTITY_KIND_PEDESTRIAN]
    client.set_waypoints(walker, [(-25, -47), (40, -47)], False, 2.0)
    for _ in range(60):  # 2 s at 30 Hz
        frame = client.step_and_receive(timeout=TIMEOUT_S)
    body = entity(frame.state, walker)
    assert body.position.x == pytest.approx(-25 + 4.0, abs=0.1)
    assert body.position.y == pytest.approx(-47, abs=1e-6)
    assert body.position.z == 0


def test_load_map_with_traffic(connect):
    client = connect("traffic")
    world = client.load_map_by_name("driving/train/01_urban", traffic={"cars": 5, "parked": 10, "pedestrians": 10})
    assert world.scene_name == "driving_train_01_urban"
    client.subscribe("car_front", ["boxes"], "lockstep")
    classes = set()
    for _ in range(90):
        classes.update(box.object_class for box in client.step_and_receive(TIMEOUT_S).boxes)
    assert pb.OBJECT_CLASS_TRAFFIC_LIGHT in classes, classes
    refused(lambda: client.load_map_by_name("driving/train/01_urban", traffic={"cars": 999}),
            pb.ERROR_CODE_INVALID_ARGUMENT, "LoadMap.traffic.cars is 999")


def test_conditions_change_rgb_only_and_bad_ones_are_refused(connect):
    client = connect("conditions")
    assert client.get_world().conditions.preset == "clear_noon"
    client.subscribe("uav", ["rgb", "depth", "mask"], "lockstep")
    noon = client.step_and_receive()
    night_world = client.set_conditions("night")
    assert (night_world.conditions.preset, night_world.conditions.quality) == ("night", "full")
    client.reset()
    night = client.step_and_receive()
    assert night.frame_id == noon.frame_id
    assert image_array(night, "depth").tobytes() == image_array(noon, "depth").tobytes()
    assert image_array(night, "mask").tobytes() == image_array(noon, "mask").tobytes()
    assert image_array(night, "rgb").mean() < 0.6 * image_array(noon, "rgb").mean()
    assert client.set_conditions(hour=6.5).conditions.hour == 6.5
    refused(lambda: client.set_conditions("sandstorm"), pb.ERROR_CODE_INVALID_ARGUMENT,
            "SetConditions.preset 'sandstorm' is not a preset", "clear_morning")
    refused(lambda: client.set_conditions(hour=-1), pb.ERROR_CODE_INVALID_ARGUMENT, "SetConditions.hour is -1")
    randomised = client.set_conditions(randomize_seed=5).conditions
    assert randomised.randomize_seed == 5 and randomised.variation != 0
    assert client.reset().conditions.variation != randomised.variation, "a new episode draws new conditions"


def test_camera_effects_keep_the_boxes_on_the_mask_and_bad_ones_are_refused(connect):
    client = connect("effects")
    client.subscribe("uav", ["rgb", "mask", "boxes"], "lockstep")
    plain = client.step_and_receive()
    world = client.set_effects(k1=-0.2, k2=0.03, jpeg_quality=70, antialias=1)
    assert (world.effects.k1, world.effects.jpeg_quality, world.effects.white_balance_k) == (-0.2, 70, 6500)
    client.reset()
    lensed = client.step_and_receive()
    assert lensed.frame_id == plain.frame_id
    assert lensed.camera_intrinsics.k1 == -0.2 and lensed.camera_intrinsics.k2 == 0.03
    mask = image_array(lensed, "mask")
    assert mask.tobytes() != image_array(plain, "mask").tobytes(), "the lens bends the mask"
    assert lensed.boxes, "something labelled in view"
    for box in lensed.boxes:  # every box is the tight box of its object's pixels
        rows, columns = (mask == box.object_id).nonzero()
        assert (box.x, box.y) == (columns.min(), rows.min())
        assert (box.x + box.width, box.y + box.height) == (columns.max() + 1, rows.max() + 1)
    refused(lambda: client.set_effects(motion_blur=1.5), pb.ERROR_CODE_INVALID_ARGUMENT,
            "SetEffects.motion_blur 1.5 is outside 0..1 frames")
    refused(lambda: client.set_effects(k1=-0.9), pb.ERROR_CODE_INVALID_ARGUMENT, "folds the image")
    assert client.get_world().effects.k1 == -0.2, "nothing changed"


def test_a_run_log_ends_with_its_client_unless_detached(start_daemon, connect, tmp_path):
    own = start_daemon("--logs-dir", str(tmp_path), "--mode", "realtime")
    owner = connect("owner", target=own)
    path = owner.start_log("runs/owned")
    owner.close()
    other = connect("other", target=own)
    deadline = time.monotonic() + 60
    while other.get_world().log_file and time.monotonic() < deadline:
        time.sleep(0.1)
    assert other.get_world().log_file == ""
    other.reset()  # allowed again: no log is written
    size = os.path.getsize(path)
    time.sleep(0.5)
    assert os.path.getsize(path) == size and open(path, "rb").read(8) == b"S4CVLOG\0"
    kept = other.start_log("runs/detached", detach=True)
    other.close()
    third = connect("third", target=own)
    time.sleep(0.5)
    assert third.get_world().log_file == kept
    assert third.stop_log() == kept
