"""Driving a car by hand from the studio page, and spawning entities and
setting routes from it: Debian's Chromium, headless, through our
DevTools driver (tools/cdp_driver.py), against a real-time sim4cvd on a
driving test map; a separate Python client checks what the daemon reports.
Keys are real DevTools key events (Input.dispatchKeyEvent), clicks real
mouse events. Skipped, with the reason, where Chromium is not installed."""

import json
import math
import os
import time

import pytest

import sim4cv
from sim4cv import driving_metrics
from cdp_driver import Browser, chromium_path
from conftest import REPO_ROOT, TIMEOUT_S, clean_page, start_daemon

pytestmark = pytest.mark.skipif(
    chromium_path() is None,
    reason="Chromium is not installed: the studio's browser tests need Debian's chromium (scripts/setup.sh)")

MAP = os.path.join(REPO_ROOT, "scenes", "driving", "test", "01_urban.map")
# driving/test/01_urban (12 x 12 tiles of 20 m): the road along the map's east edge runs north-south
# at x = 110 (its northbound lane's centre at x = 112); the route "loop" goes north at x = -50 (lane at -48).
EAST_ROAD = (112.5, -40.0)
LOOP_ROAD = (-47.5, -40.0)
UAV_POINT = (0.0, 60.0)
PEDESTRIAN_POINT = (-20.0, 60.0)


@pytest.fixture(scope="module")
def daemon():
    daemon = start_daemon("--map", MAP, mode="realtime")
    yield daemon
    assert daemon.stop() == 0, "\n".join(daemon.stderr_tail[-30:])


@pytest.fixture(scope="module")
def client(daemon):
    client = sim4cv.connect(daemon.address, name="checker")
    client.remove(1)  # the map's car: it drives the loop, and would meet the cars the tests put there
    yield client
    client.close()


@pytest.fixture(scope="module")
def page(daemon, client):
    with Browser() as browser, clean_page(browser, "http://127.0.0.1:%d/?max_fps=10&token=%s" % (daemon.http, daemon.token),
                                          "window.studio && studio.ready && studio.state && studio.map.fitted") as page:
        yield page


def press(page, selector):
    page.evaluate("document.querySelector(%s).click()" % json.dumps(selector))


def choose(page, selector, value):
    page.evaluate("""(() => { const e = document.querySelector(%s); e.value = %s;
                     e.dispatchEvent(new Event("change")); })()""" % (json.dumps(selector), json.dumps(value)))


def click_map(page, x, y):
    """A real mouse click on the map at world point (x, y)."""
    sx, sy = page.evaluate("studio.map.toScreen(%r, %r)" % (x, y))
    left, top = page.evaluate("(() => { const r = document.getElementById('map').getBoundingClientRect();"
                              " return [r.left, r.top]; })()")
    page.click(left + sx, top + sy)


def entity(client, entity_id):
    return next((e for e in client.get_state().entities if e.id == entity_id), None)


def yaw_deg(e):
    q = e.orientation
    return math.degrees(math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z)))


def speed(e):
    return math.hypot(e.linear_velocity.x, e.linear_velocity.y)


def wait_until(condition, what, timeout=TIMEOUT_S):
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        assert time.monotonic() < deadline, "waited %.0f s for %s" % (timeout, what)
        time.sleep(0.05)


def spawn_by_click(page, client, kind, x, y):
    """Spawn mode, `kind`, a click at (x, y): the new entity's id, from the daemon's own world."""
    before = {e.id for e in client.get_world().entities}
    choose(page, "#spawn-kind", kind)
    press(page, "#spawn-mode")
    assert page.evaluate("studio.entityTools.spawning")
    click_map(page, x, y)
    new = wait_until(lambda: [e for e in client.get_world().entities if e.id not in before], "the spawned entity")
    assert len(new) == 1, new
    assert new[0].kind == sim4cv.pb.EntityKind.Value(kind)
    page.wait_for("studio.controls.selected && studio.controls.selected.id === %d" % new[0].id, TIMEOUT_S)
    assert not page.evaluate("studio.entityTools.spawning")  # one spawn per press
    return new[0].id


def test_page_loads_with_the_drive_and_spawn_panels(page):
    assert page.evaluate("document.getElementById('drive-start').textContent") == "drive"
    assert page.evaluate("[...document.querySelectorAll('#route-name option')].map(o => o.value)") == ["loop"]
    assert page.evaluate("studio.driving.active") is False
    page.collect()
    assert page.problems == [], page.problems


def test_the_score_is_the_driving_studys_time_weighted(page):
    # Samples 1 s apart: each deviation holds until the next sample.
    score = page.evaluate("""import("/js/drive_score.js").then(({ DriveScore }) => {
        const score = new DriveScore();
        [[0, 0.1], [1, -0.3], [2, 1.2], [3, 0.0], [3.5, null], [6.5, 2.0]].forEach(([t, d]) =>
            score.add({ t, x: 10 * t, y: 0, yaw_deg: 0, speed: 10, deviation_m: d, steering: 0, throttle: 0, brake: 0 }));
        return score.summary(); })""")
    # 0.1 m for 1 s, 0.3 for 1 s, 1.2 for 1 s, 0 for 0.5 s; the null sample's gap counts for the distance only.
    assert score["seconds"] == pytest.approx(3.5)
    assert score["mean_deviation_cm"] == pytest.approx(100 * 1.6 / 3.5)
    assert (score["within_25cm"], score["within_50cm"], score["within_1m"]) == pytest.approx((1.5 / 3.5, 2.5 / 3.5,
                                                                                             2.5 / 3.5))
    assert score["lane_departures"] == 2 and score["max_deviation_cm"] == pytest.approx(200.0)
    assert score["distance_m"] == pytest.approx(65.0) and score["samples"] == 6

    # Equally spaced samples (the evaluation's frames): the same numbers as driving_metrics.score.
    deviations = [round(0.6 * math.sin(0.05 * i) + 0.2 * math.cos(0.31 * i), 4) for i in range(301)]
    ours = page.evaluate("""import("/js/drive_score.js").then(({ DriveScore }) => {
        const score = new DriveScore();
        %s.forEach((d, i) => score.add({ t: i / 30, x: 0, y: i * 0.3, yaw_deg: 90, speed: 9, deviation_m: d,
                                          steering: 0, throttle: 0, brake: 0 }));
        return score.summary(); })""" % json.dumps(deviations))
    reference = driving_metrics.score(deviations[:-1])  # the last sample holds for no time
    for key in ("mean_deviation_cm", "max_deviation_cm", "within_25cm", "within_50cm", "within_1m"):
        assert ours[key] == pytest.approx(reference[key], abs=1e-3), key
    assert ours["lane_departures"] == driving_metrics.departures(deviations)


def test_spawning_from_the_map(page, client):
    car = spawn_by_click(page, client, "ENTITY_KIND_CAR", *EAST_ROAD)
    state = entity(client, car)
    # Snapped to the lane centre nearest the click, facing along it (north).
    assert abs(state.position.x - 112.0) < 0.3 and abs(state.position.y - EAST_ROAD[1]) < 1.0, state.position
    assert abs(yaw_deg(state) - 90.0) < 3.0, yaw_deg(state)
    assert page.evaluate("document.getElementById('drive-car').value") == str(car)  # the car to drive

    choose(page, "#spawn-height", "12")
    uav = spawn_by_click(page, client, "ENTITY_KIND_UAV", *UAV_POINT)
    state = entity(client, uav)
    assert math.hypot(state.position.x - UAV_POINT[0], state.position.y - UAV_POINT[1]) < 1.5, state.position
    assert abs(state.position.z - 12.0) < 1.0, state.position

    walker = spawn_by_click(page, client, "ENTITY_KIND_PEDESTRIAN", *PEDESTRIAN_POINT)
    state = entity(client, walker)
    assert math.hypot(state.position.x - PEDESTRIAN_POINT[0], state.position.y - PEDESTRIAN_POINT[1]) < 1.0
    assert page.evaluate("studio.errors") == []
    page.evaluate("studio.controls.select(null); studio.map.selected = null")  # the car is still the one to drive
    assert page.evaluate("document.getElementById('drive-car').value") == str(car)


def test_a_key_press_drives_the_car_and_the_score_counts(page, client):
    car = int(page.evaluate("document.getElementById('drive-car').value"))
    name = page.evaluate("document.getElementById('drive-car').selectedOptions[0].textContent").split()[1]
    press(page, "#drive-start")
    page.wait_for("studio.driving.active && studio.driving.score.samples.length > 2", TIMEOUT_S)
    # The first-person camera, mounted on the car, in a live view that shows its frames.
    camera = name + "_front"
    assert any(c.name == camera and c.mounted_on == name for c in client.get_world().cameras)
    page.wait_for("studio.views.some(v => v.camera === %s && v.frames > 0)" % json.dumps(camera), TIMEOUT_S)
    start = entity(client, car)

    page.key("w", True)
    page.wait_for("studio.driving.controls.throttle > 0.9", 5.0)  # ramped up, not at once
    # Held until the car is 4 m on (about 2.5 s on an idle machine; a busy one runs the
    # real-time daemon slower, so the wait is for the distance, not the time).
    moved = wait_until(lambda: (lambda e: e if e.position.y - start.position.y > 4.0 else None)(entity(client, car)),
                       "W held to drive the car 4 m north (it faces north)")
    page.key("w", False)
    assert abs(moved.position.x - start.position.x) < 1.5, (start.position, moved.position)
    assert speed(moved) > 2.0
    page.wait_for("studio.driving.controls.throttle === 0", 5.0)

    # Steering ramps while a key is held and returns to the centre after it.
    page.key("ArrowRight", True)
    steered = page.wait_for("studio.driving.controls.steering > 0.3 && studio.driving.controls.steering", 5.0)
    assert steered < 1.0  # a ramp, not full lock at once
    page.key("ArrowRight", False)
    page.wait_for("studio.driving.controls.steering === 0", 5.0)

    # A gamepad (the Gamepad API's standard mapping): left stick steers, right trigger accelerates.
    page.evaluate("""navigator.getGamepads = () => [{ id: "test pad", connected: true, mapping: "standard",
        axes: [-0.5, 0, 0, 0], buttons: Array.from({ length: 17 }, (_, i) => ({ value: i === 7 ? 0.4 : 0 })) }]""")
    page.wait_for("Math.abs(studio.driving.controls.steering + 0.5) < 1e-6 && "
                  "Math.abs(studio.driving.controls.throttle - 0.4) < 1e-6", 5.0)
    page.wait_for("document.getElementById('drive-status').textContent.includes('gamepad: test pad')", 5.0)
    page.evaluate("navigator.getGamepads = () => []")
    page.wait_for("studio.driving.controls.throttle === 0", 5.0)

    # The page losing focus brakes the car; focus back, the keys drive again.
    page.key("w", True)
    page.wait_for("studio.driving.controls.throttle > 0.2", 5.0)
    page.evaluate("window.dispatchEvent(new Event('blur'))")
    page.wait_for("studio.driving.controls.brake === 1 && studio.driving.controls.throttle === 0", 5.0)
    page.wait_for("document.getElementById('drive-status').textContent.includes('lost focus')", 5.0)
    page.key("w", False)
    page.evaluate("window.dispatchEvent(new Event('focus'))")
    page.wait_for("studio.driving.controls.brake === 0", 5.0)

    score = page.evaluate("studio.driving.score.summary()")
    assert score["mean_deviation_cm"] is not None and math.isfinite(score["mean_deviation_cm"]), score
    assert score["mean_deviation_cm"] < 100.0, score  # straight ahead in the lane
    assert score["distance_m"] > 4.0 and score["seconds"] > 2.0, score
    assert 0.0 <= score["within_25cm"] <= score["within_50cm"] <= score["within_1m"] <= 1.0, score
    assert "you" in page.evaluate("document.getElementById('drive-score').textContent")

    # Stopping brakes the car to a standstill.
    press(page, "#drive-start")
    assert page.evaluate("studio.driving.active") is False
    assert page.evaluate("studio.driving.controls") == {"steering": 0, "throttle": 0, "brake": 1}
    wait_until(lambda: speed(entity(client, car)) < 0.2, "the car to stop", 10.0)

    # The run's log: every sample, downloadable as JSON.
    run = page.evaluate("JSON.parse(JSON.stringify(studio.driving.score))")
    assert run["car_id"] == car and run["camera"] == camera and run["score"]["samples"] == len(run["samples"])
    assert run["columns"][:6] == ["t", "x", "y", "yaw_deg", "speed", "deviation_m"]
    assert len(run["samples"]) >= 10 and max(s[4] for s in run["samples"]) > 2.0
    press(page, "#drive-download")
    assert page.evaluate("document.getElementById('drive-download').href").startswith("blob:")
    assert page.evaluate("studio.errors") == []


def test_the_score_can_measure_to_a_routes_lane(page, client):
    # The car stands on the east road, far from the route "loop": scored against
    # the loop's lane (QueryRoad.route), each sample is the distance to it.
    page.wait_for("[...document.getElementById('drive-route').options].some(o => o.value === 'loop')", TIMEOUT_S)
    choose(page, "#drive-route", "loop")
    press(page, "#drive-start")
    page.wait_for("studio.driving.active && studio.driving.score.samples.length > 2", TIMEOUT_S)
    press(page, "#drive-start")
    run = page.evaluate("JSON.parse(JSON.stringify(studio.driving.score))")
    assert run["route"] == "loop"
    x, y, deviation = (run["samples"][-1][i] for i in (1, 2, 5))
    assert abs(deviation) > 50.0  # the loop runs at x = -48, the car at x = 112
    assert deviation == pytest.approx(-client.query_road(x, y, route="loop").lateral_offset, abs=1e-6)
    choose(page, "#drive-route", "")
    assert page.evaluate("studio.errors") == []


def test_a_car_another_client_drives_is_refused_with_the_daemons_error(page, client):
    car = int(page.evaluate("document.getElementById('drive-car').value"))
    # Stopping closed the page's driver session, so the car is free at once: the checker drives it now.
    client.send_controls(car, 0.0, 0.0, 1.0)
    client.get_state()  # its Controls are in before the page's (an Error for them would be raised here)
    press(page, "#drive-start")
    error = page.wait_for("studio.errors.length && studio.errors[studio.errors.length - 1]", TIMEOUT_S)
    assert error["code"] == "ERROR_CODE_INVALID_STATE" and "another client" in error["message"], error
    page.wait_for("!studio.driving.active", TIMEOUT_S)
    assert "INVALID_STATE" in page.evaluate("document.getElementById('errors').textContent")
    time.sleep(0.3)  # the refusals of Controls already on their way are not listed again
    assert page.evaluate("studio.errors.length") == 1, page.evaluate("studio.errors")
    assert "refused: INVALID_STATE" in page.evaluate("document.getElementById('drive-status').textContent")
    page.evaluate("studio.errors.length = 0")


def test_set_route_from_the_page_moves_the_car_along_it(page, client):
    click_map(page, *LOOP_ROAD)  # a plain click: where "spawn a car to drive" puts it
    before = {e.id for e in client.get_world().entities}
    press(page, "#drive-spawn")
    car = wait_until(lambda: [e.id for e in client.get_world().entities if e.id not in before], "the new car")[0]
    page.wait_for("studio.controls.selected && studio.controls.selected.id === %d" % car, TIMEOUT_S)
    start = entity(client, car)
    assert abs(start.position.x + 48.0) < 0.3, start.position

    choose(page, "#route-name", "loop")
    choose(page, "#route-speed", "8")
    press(page, "#set-route")
    # 4 m north along the loop (waited for by distance: a busy machine runs the real-time daemon slower)
    now = wait_until(lambda: (lambda e: e if e.position.y - start.position.y > 4.0 else None)(entity(client, car)),
                     "the car to drive 4 m of its route")
    assert speed(now) > 3.0, now
    road = client.query_road(now.position.x, now.position.y, heading_deg=yaw_deg(now))
    assert abs(road.lateral_offset) < 0.5, road  # on the lane

    # Only the speed: 0 stops it on its route.
    choose(page, "#route-speed", "0")
    press(page, "#set-speed")
    wait_until(lambda: speed(entity(client, car)) < 0.3, "the car to stop on its route", 15.0)
    assert page.evaluate("studio.errors") == []


def test_a_uav_follows_an_entity_from_the_page(page, client):
    uav = next(e.id for e in client.get_world().entities if e.kind == sim4cv.pb.ENTITY_KIND_UAV and e.name != "uav")
    car = int(page.evaluate("document.getElementById('drive-car').value"))
    click_map(page, *UAV_POINT)  # selects it
    page.wait_for("studio.controls.selected && studio.controls.selected.id === %d" % uav, TIMEOUT_S)
    start = entity(client, uav)
    target = entity(client, car)
    choose(page, "#uav-target", str(car))
    press(page, "#uav-follow")
    wait_until(lambda: math.hypot(entity(client, uav).position.x - start.position.x,
                                  entity(client, uav).position.y - start.position.y) > 3.0, "the UAV to fly", 10.0)
    now = entity(client, uav)
    before = math.hypot(start.position.x - target.position.x, start.position.y - target.position.y)
    after = math.hypot(now.position.x - target.position.x, now.position.y - target.position.y)
    assert after < before - 2.0, (before, after)  # towards the car
    press(page, "#uav-hold")
    assert page.evaluate("studio.errors") == []
