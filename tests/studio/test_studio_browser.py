"""The studio in a real browser: Debian's Chromium, headless, driven through
the DevTools protocol by our own driver (tools/cdp_driver.py), against a real
sim4cvd. The Python client is the lockstep client, so the frame the page
shows can be compared with the one the client received, pixel for pixel.
Skipped, with the reason, where Chromium is not installed."""

import base64
import hashlib
import json
import time

import numpy as np
import pytest

import sim4cv
from sim4cv import visualize
from cdp_driver import Browser, chromium_path
from conftest import MAP, TIMEOUT_S, clean_page, start_daemon

pytestmark = pytest.mark.skipif(
    chromium_path() is None,
    reason="Chromium is not installed: the studio's browser tests need Debian's chromium (scripts/setup.sh)")


# The RGB of a view's image canvas, base64 (getImageData: exactly what was drawn).
CANVAS_RGB = """(() => {
  const canvas = studio.views[%d].image;
  const rgba = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
  const rgb = new Uint8Array(canvas.width * canvas.height * 3);
  for (let i = 0, j = 0; i < rgba.length; i += 4) { rgb[j++] = rgba[i]; rgb[j++] = rgba[i + 1]; rgb[j++] = rgba[i + 2]; }
  let text = "";
  for (let i = 0; i < rgb.length; i += 0x8000) text += String.fromCharCode.apply(null, rgb.subarray(i, i + 0x8000));
  return [canvas.width, canvas.height, btoa(text)];
})()"""


@pytest.fixture(scope="module")
def daemon():
    daemon = start_daemon("--map", MAP)
    yield daemon
    assert daemon.stop() == 0, "\n".join(daemon.stderr_tail[-30:])


@pytest.fixture(scope="module")
def stepper(daemon):
    client = sim4cv.connect(daemon.address, name="stepper")
    client.subscribe("uav", ["rgb", "depth", "semantic"], "lockstep")
    yield client
    client.close()


@pytest.fixture(scope="module")
def page(daemon, stepper):
    with Browser() as browser, clean_page(browser, "http://127.0.0.1:%d/?view=uav:rgb&rgb=raw&max_fps=0&token=%s" % (daemon.http, daemon.token),
                                          "window.studio && studio.ready && studio.views.length === 1") as page:
        page.wait_for("document.querySelector('#view-0 .view-stats').textContent.startsWith('subscribed')", TIMEOUT_S)
        yield page


def canvas_rgb(page, view=0):
    width, height, data = page.evaluate(CANVAS_RGB % view)
    return np.frombuffer(base64.b64decode(data), np.uint8).reshape(height, width, 3)


def show_frame(page, stepper, view=0):
    """Steps once; waits until view `view` has drawn that frame; the client's frame."""
    frame = stepper.step_and_receive(TIMEOUT_S)
    page.wait_for("studio.views[%d].lastHeader && Number(studio.views[%d].lastHeader.frame_id) === %d"
                  % (view, view, frame.frame_id), TIMEOUT_S)
    return frame


def choose(page, selector, value):
    """Sets a <select> or <input> as a person would, firing its change event."""
    page.evaluate("""(() => { const e = document.querySelector(%s); e.value = %s;
                     e.dispatchEvent(new Event("change")); })()""" % (json.dumps(selector), json.dumps(value)))


def press(page, selector):
    page.evaluate("document.querySelector(%s).click()" % json.dumps(selector))


def test_page_loads_and_shows_live_frames_without_console_errors(page, stepper):
    for _ in range(3):
        show_frame(page, stepper)
    assert page.evaluate("studio.views[0].frames") >= 1
    assert "uav" in page.evaluate("document.querySelector('#view-0 .view-stats').textContent")
    page.collect()
    assert page.problems == [], page.problems


def test_lossless_view_matches_the_daemons_frame_exactly(page, stepper):
    frame = show_frame(page, stepper)
    shown = canvas_rgb(page)
    expected = sim4cv.image_array(frame, "rgb")
    assert shown.shape == expected.shape
    assert hashlib.sha256(shown.tobytes()).hexdigest() == hashlib.sha256(expected.tobytes()).hexdigest(), \
        "canvas differs from the frame in %d pixels" % int(np.any(shown != expected, axis=-1).sum())


def test_ground_truth_channels_are_colourised_like_the_python_client(page, stepper):
    choose(page, "#view-0 select.channel", "CHANNEL_SEMANTIC")
    page.wait_for("document.querySelector('#view-0 .view-stats').textContent.startsWith('subscribed')", TIMEOUT_S)
    frame = show_frame(page, stepper)
    assert np.array_equal(canvas_rgb(page), visualize.semantic_colours(sim4cv.image_array(frame, "semantic")))
    choose(page, "#view-0 select.channel", "CHANNEL_DEPTH")
    page.wait_for("document.querySelector('#view-0 .view-stats').textContent.startsWith('subscribed')", TIMEOUT_S)
    frame = show_frame(page, stepper)
    difference = np.abs(canvas_rgb(page).astype(int) - visualize.depth_colours(sim4cv.image_array(frame, "depth")))
    assert difference.max() <= 1  # float rounding of the grey level
    choose(page, "#view-0 select.channel", "CHANNEL_RGB")
    page.wait_for("document.querySelector('#view-0 .view-stats').textContent.startsWith('subscribed')", TIMEOUT_S)


def test_jpeg_view_is_close_to_the_daemons_frame(page, stepper):
    choose(page, "#view-0 select.rgb", "jpeg")
    page.wait_for("studio.views[0].socket.url.includes('rgb=jpeg') && studio.views[0].socket.welcome", TIMEOUT_S)
    page.wait_for("document.querySelector('#view-0 .view-stats').textContent.startsWith('subscribed')", TIMEOUT_S)
    frame = show_frame(page, stepper)
    difference = np.abs(canvas_rgb(page).astype(int) - sim4cv.image_array(frame, "rgb"))
    assert difference.mean() < 4.0, difference.mean()
    stats = page.evaluate("document.querySelector('#view-0 .view-stats').textContent")
    assert "fps" in stats and "latency" in stats and "boxes" in stats, stats
    assert page.evaluate("studio.views[0].latencyMs") is not None


def test_map_shows_every_entity_where_the_daemon_has_it(page, stepper):
    state = stepper.get_state()
    page.wait_for("studio.state && Number(studio.state.frame_id) === %d" % state.frame_id, TIMEOUT_S)
    assert page.evaluate("studio.map.map.routes.length") >= 1
    assert page.evaluate("studio.map.map.name") == "tracking_easy_urban"
    shown = {e["id"]: e for e in page.evaluate("studio.map.entities")}
    for entity in state.entities:
        position = shown[entity.id]["position"]
        assert abs(position["x"] - entity.position.x) < 1e-6 and abs(position["y"] - entity.position.y) < 1e-6
    car = page.evaluate("studio.map.entityOnScreen(1)")
    pixel = page.evaluate("Array.from(document.getElementById('map').getContext('2d')"
                          ".getImageData(%d, %d, 1, 1).data)" % (round(car[0]), round(car[1])))
    assert pixel[:3] == [0x4f, 0xc3, 0xf7], pixel  # the car's colour under its marker

    # Clicking the car selects it and shows its state.
    rect = page.evaluate("(() => { const r = document.getElementById('map').getBoundingClientRect();"
                         " return [r.left, r.top]; })()")
    page.click(rect[0] + car[0], rect[1] + car[1])
    text = page.wait_for("(t => t.includes('1 car') && t) (document.getElementById('entity-state').textContent)",
                         TIMEOUT_S)
    assert "position" in text and "speed" in text, text


def test_configure_from_the_page_takes_effect(page, stepper):
    before = show_frame(page, stepper)
    choose(page, "#preset", "night")
    press(page, "#apply-conditions")
    deadline = time.monotonic() + TIMEOUT_S
    while stepper.get_world().conditions.preset != "night":
        assert time.monotonic() < deadline, "the page's SetConditions never reached the daemon"
        time.sleep(0.05)
    after = show_frame(page, stepper)
    assert sim4cv.image_array(after, "rgb").mean() < 0.6 * sim4cv.image_array(before, "rgb").mean()
    page.wait_for("document.getElementById('conditions-now').textContent.startsWith('night')", TIMEOUT_S)


def test_daemon_errors_are_shown_in_the_page(page):
    assert page.evaluate("studio.errors") == []
    choose(page, "#camera-width", "5")
    press(page, "#add-camera")
    error = page.wait_for("studio.errors.length && studio.errors[studio.errors.length - 1]", TIMEOUT_S)
    assert error["code"] == "ERROR_CODE_INVALID_ARGUMENT" and "width" in error["message"], error
    assert "width" in page.evaluate("document.getElementById('errors').textContent")
    page.evaluate("studio.errors.length = 0")
    choose(page, "#camera-width", "320")


def test_added_camera_gets_a_view_with_frames(page, stepper):
    choose(page, "#camera-name", "studio_cam")
    choose(page, "#camera-z", "40")
    choose(page, "#camera-pitch", "80")
    press(page, "#add-camera")
    page.wait_for("studio.views.length === 2 && studio.views[1].camera === 'studio_cam'", TIMEOUT_S)
    page.wait_for("document.querySelector('#view-1 .view-stats').textContent.startsWith('subscribed')", TIMEOUT_S)
    show_frame(page, stepper, view=1)
    assert page.evaluate("studio.errors.length") == 0, page.evaluate("studio.errors")


def test_reset_and_load_map_from_the_page(page, stepper):
    press(page, "#view-1 button.remove")  # Reset removes added cameras, ending their views' subscriptions
    page.wait_for("studio.views.length === 1", TIMEOUT_S)
    press(page, "#reset")
    deadline = time.monotonic() + TIMEOUT_S
    while stepper.get_state().frame_id > 5:  # Reset: time back to the map's start
        assert time.monotonic() < deadline
        time.sleep(0.05)
    page.wait_for("[...document.querySelectorAll('#map-name option')].some(o => o.value === 'tracking/easy_desert')",
                  TIMEOUT_S)
    choose(page, "#map-name", "tracking/easy_desert")
    press(page, "#load-map")
    page.wait_for("studio.map.map && studio.map.map.surroundings === 'desert'", TIMEOUT_S)
    assert stepper.get_world().scene_name == page.evaluate("studio.world.scene_name")
    assert page.evaluate("studio.errors.length") == 0, page.evaluate("studio.errors")


def test_a_run_log_started_and_stopped_from_the_page(studio_daemon, tmp_path):
    daemon = studio_daemon("--map", MAP, "--logs-dir", str(tmp_path), mode="realtime")
    checker = sim4cv.connect(daemon.address, name="checker")
    with Browser() as browser, clean_page(browser, "http://127.0.0.1:%d/?max_fps=5&token=%s" % (daemon.http, daemon.token),
                                          "window.studio && studio.ready") as page:
        choose(page, "#log-name", "studio/run_1")
        page.evaluate("document.getElementById('log-label').value = 'from the page'")
        press(page, "#log-toggle")
        path = str(tmp_path / "studio" / "run_1.s4log")
        page.wait_for("document.getElementById('log-now').textContent === %s" % json.dumps(path), TIMEOUT_S)
        assert checker.get_world().log_file == path
        assert page.evaluate("document.getElementById('log-toggle').textContent") == "stop log"
        start = checker.get_state().frame_id
        while checker.get_state().frame_id < start + 30:
            time.sleep(0.05)
        press(page, "#log-toggle")
        page.wait_for("document.getElementById('log-now').textContent === 'none'", TIMEOUT_S)
        assert checker.get_world().log_file == ""
        with open(path, "rb") as f:
            data = f.read()
        assert data[:8] == b"S4CVLOG\0" and len(data) > 30 * 100, len(data)  # a header and ~30 records
        page.evaluate("window.asked = []; window.confirm = (m) => { asked.push(m); return true; }")
        press(page, "#log-toggle")  # the same name again: the page asks before replacing it
        page.wait_for("document.getElementById('log-now').textContent === %s" % json.dumps(path), TIMEOUT_S)
        assert "exists" in page.evaluate("asked[0]")
        press(page, "#log-toggle")
        page.wait_for("document.getElementById('log-now').textContent === 'none'", TIMEOUT_S)
        assert page.evaluate("studio.errors.length") == 0, page.evaluate("studio.errors")
    checker.close()
