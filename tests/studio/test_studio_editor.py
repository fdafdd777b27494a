"""The studio's map editor (studio/editor.html) in a real browser: Debian's
Chromium, headless, driven through the DevTools protocol (tools/cdp_driver.py)
with real mouse and key events, against a real sim4cvd whose --maps-dir is a
pytest folder holding a copy of every shipped map. The daemon is the one
judge of a map (CheckMap, SaveMap, LoadMap); these tests check that the page
shows what it says, keeps every byte of a map through Open and Save, and that
what is dragged onto the grid is what the daemon then plays.
Skipped, with the reason, where Chromium is not installed."""

import glob
import json
import os
import shutil

import pytest

import sim4cv
from sim4cv import sim4cv_pb2 as pb
from cdp_driver import Browser, chromium_path
from conftest import REPO_ROOT, TIMEOUT_S, clean_page, start_daemon

pytestmark = pytest.mark.skipif(
    chromium_path() is None,
    reason="Chromium is not installed: the studio's browser tests need Debian's chromium (scripts/setup.sh)")

SCENES = os.path.join(REPO_ROOT, "scenes")
SHIPPED = sorted(os.path.relpath(path, SCENES)[:-len(".map")]
                 for path in glob.glob(os.path.join(SCENES, "**", "*.map"), recursive=True))
TEST_MAP = "tracking/easy_desert"  # 5 x 4 tiles of 50 m: .#### / ##..# / #...# / #####


@pytest.fixture(scope="module")
def maps_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("maps")
    for name in SHIPPED:
        os.makedirs(os.path.dirname(os.path.join(folder, name)), exist_ok=True)
        shutil.copyfile(os.path.join(SCENES, name + ".map"), os.path.join(folder, name + ".map"))
    return str(folder)


@pytest.fixture(scope="module")
def daemon(maps_dir):
    daemon = start_daemon("--map", os.path.join(maps_dir, "tracking", "easy_urban.map"), "--maps-dir", maps_dir)
    yield daemon
    assert daemon.stop() == 0, "\n".join(daemon.stderr_tail[-30:])


@pytest.fixture(scope="module")
def client(daemon):
    client = sim4cv.connect(daemon.address, name="editor-test")
    yield client
    client.close()


@pytest.fixture(scope="module")
def browser():
    with Browser() as browser:
        yield browser


@pytest.fixture(scope="module")
def page(daemon, browser):
    with clean_page(browser, "http://127.0.0.1:%d/editor.html?token=%s" % (daemon.http, daemon.token), "window.editor && editor.ready") as page:
        page.evaluate("window.confirmed = []; window.confirm = (m) => { confirmed.push(m); return true; }")
        yield page


def js(value):
    return json.dumps(value)


def checked(page):
    """Waits for the daemon's check of the editor's current text; its result."""
    return page.wait_for("(r => r.text === editor.text() && ['valid', 'invalid'].includes(r.state) && r)"
                         "(editor.validator.result)", TIMEOUT_S)


def open_map(page, name):
    """Opens a map as a person would: picks it in the Open list, presses open."""
    page.wait_for("[...document.querySelectorAll('#open-name option')].some(o => o.value === %s)" % js(name),
                  TIMEOUT_S)
    page.evaluate("editor.note(''); document.getElementById('open-name').value = %s" % js(name))
    page.evaluate("document.getElementById('open-map').click()")
    page.wait_for("editor.model.name && document.getElementById('message').textContent === %s"
                  % js("opened " + name), TIMEOUT_S)
    return page.evaluate("editor.text()")


def press(page, selector):
    page.evaluate("document.querySelector(%s).click()" % js(selector))


def fill(page, selector, value):
    page.evaluate("""(() => { const e = document.querySelector(%s); e.value = %s;
                     e.dispatchEvent(new Event("input")); e.dispatchEvent(new Event("change")); })()"""
                  % (js(selector), js(value)))


def tile(page, col, row):
    return page.evaluate("editor.grid.tileOnPage(%d, %d)" % (col, row))


def palette(page, item):
    return page.evaluate("""(r => [r.left + r.width / 2, r.top + r.height / 2])
        (document.querySelector('.palette-item[data-id=%s]').getBoundingClientRect())""" % js(item))


KEYS = {"z": ("KeyZ", 90), "y": ("KeyY", 89), "r": ("KeyR", 82), "Delete": ("Delete", 46),
        "Backspace": ("Backspace", 8)}


def key(page, name, ctrl=False):
    """A real key press (keyDown, keyUp) with the page's body focused."""
    page.evaluate("document.activeElement && document.activeElement.blur()")
    code, vk = KEYS[name]
    event = {"key": name, "code": code, "windowsVirtualKeyCode": vk, "modifiers": 2 if ctrl else 0}
    page.send("Input.dispatchKeyEvent", dict(event, type="rawKeyDown"))
    page.send("Input.dispatchKeyEvent", dict(event, type="keyUp"))


def last_error(page, where):
    return page.wait_for("(e => e.length && e[e.length - 1].where === %s && e[e.length - 1])(editor.errors)"
                         % js(where), TIMEOUT_S)


def test_editor_loads_the_daemons_map_and_checks_it(page, client):
    assert page.evaluate("editor.model.name") == "tracking_easy_urban"
    result = checked(page)
    assert result["state"] == "valid", result
    assert page.evaluate("document.getElementById('check-state').textContent") == "valid"
    items = page.evaluate("[...document.querySelectorAll('.palette-item')].map(e => e.dataset.id)")
    for item in ("road", "dead-end", "straight", "curve", "junction", "crossroads", "erase",
                 "house", "tree", "lantern", "park", "obstacle"):
        assert item in items
    page.collect()
    assert page.problems == [], page.problems
    assert page.console == [], page.console


def test_every_shipped_map_opens_and_writes_back_byte_for_byte(page, maps_dir):
    listed = page.evaluate("[...document.querySelectorAll('#open-name option')].map(o => o.value)")
    assert set(SHIPPED) <= set(listed), set(SHIPPED) - set(listed)
    # Each through the Open button's own code (OpenMap, parse into the editor), then the editor's text.
    texts = page.evaluate("""(async () => { const out = {};
        for (const name of %s) { await editor.actions.open(name); out[name] = editor.text(); }
        return out; })()""" % js(SHIPPED), timeout=60)
    for name in SHIPPED:
        with open(os.path.join(maps_dir, name + ".map"), "rb") as f:
            assert texts[name].encode() == f.read(), name
    assert page.evaluate("editor.errors.filter(e => e.where === 'Open')") == []
    # And once through the page itself: the select and the button.
    assert open_map(page, TEST_MAP).encode() == open(os.path.join(maps_dir, TEST_MAP + ".map"), "rb").read()


def test_numbers_are_written_as_the_map_writers_printf_writes_them(page):
    """Objects' "%.2f" and the tile size's "%.10g" (map_writer.cpp), ties to even on the exact
    binary value as glibc (and Python's own formatting) does, where JavaScript's toFixed differs."""
    values = [0.125, -0.125, 0.375, 2.675, 1.005, -0.004, -0.005, 1999.995, 12.5, 20, 1 / 3, 33.333333333333,
              3.0517578125e-05, 1e-07, 123456789012.0, 9.99999999995, 0.0001, -0.0, 1234.5678]
    got = page.evaluate("""(async () => { const m = await import('/js/editor/map_model.js');
        const p = await import('/js/editor/printf.js');
        return %s.map(v => [m.fixed2(v), p.formatGeneral(v, 10)]); })()""" % js(values))
    for value, (fixed, general) in zip(values, got):
        expected = "%.2f" % value
        assert fixed == ("0.00" if expected == "-0.00" else expected), value
        assert general == "%.10g" % value, value


def test_dragged_road_tile_is_saved_and_played(page, client, maps_dir):
    before = open_map(page, TEST_MAP)
    assert page.evaluate("editor.model.rows[1][2]") == "."
    page.drag(*palette(page, "road"), *tile(page, 2, 1))
    assert page.evaluate("editor.model.rows[1]") == "###.#"
    text = page.evaluate("editor.text()")
    assert text != before and text.split("\n")[7] == "###.#"
    assert checked(page)["state"] == "valid"

    fill(page, "#save-name", "studio/dragged")
    press(page, "#save-map")
    page.wait_for("editor.saved && editor.saved.name === 'studio/dragged'", TIMEOUT_S)
    with open(os.path.join(maps_dir, "studio", "dragged.map"), "rb") as f:
        assert f.read() == text.encode()
    page.wait_for("[...document.querySelectorAll('#open-name option')].some(o => o.value === 'studio/dragged')",
                  TIMEOUT_S)

    press(page, "#play")
    page.wait_for("document.getElementById('message').textContent.startsWith('playing')", TIMEOUT_S)
    played = client.get_map_text()
    assert "name tracking_easy_desert\n" in played
    rows = played.split("grid 5 4\n")[1].split("\n")[:4]
    assert rows[1][2] == "#", rows

    # Saving again under the same name asks first, then replaces the file.
    page.drag(*palette(page, "road"), *tile(page, 3, 1))
    press(page, "#save-map")
    page.wait_for("confirmed.length === 1 && editor.saved.text === editor.text()", TIMEOUT_S)
    assert "dragged" in page.evaluate("confirmed[0]")
    with open(os.path.join(maps_dir, "studio", "dragged.map"), "rb") as f:
        assert f.read() == page.evaluate("editor.text()").encode()


def test_a_map_with_an_error_shows_the_daemons_message_and_is_not_saved(page, maps_dir):
    open_map(page, TEST_MAP)
    fill(page, "#save-name", "studio/kept")
    press(page, "#save-map")
    page.wait_for("editor.saved && editor.saved.name === 'studio/kept'", TIMEOUT_S)
    path = os.path.join(maps_dir, "studio", "kept.map")
    on_disk = open(path, "rb").read()

    # An explicit dead end pointing north from (2, 2), where nothing is.
    page.click(*palette(page, "dead-end"))
    page.click(*tile(page, 2, 2))
    assert page.evaluate("editor.model.rows[2]") == "#.1.#"
    result = checked(page)
    assert result["state"] == "invalid", result
    assert "tile 2,2 connects north to no road" in result["message"], result
    assert "map line 9 '#.1.#': " in result["message"], result
    assert page.evaluate("document.getElementById('check-message').textContent") == result["message"]
    assert page.evaluate("document.getElementById('check-where').textContent") == "at grid row 2"
    problem = page.evaluate("editor.problem")
    assert problem["row"] == 2 and {"col": 2, "row": 2} in problem["tiles"], problem

    text = page.evaluate("editor.text()")
    press(page, "#save-map")
    error = last_error(page, "Save")
    assert error["code"] == "ERROR_CODE_INVALID_ARGUMENT" and "connects north to no road" in error["message"], error
    assert "connects north" in page.evaluate("document.getElementById('messages').textContent")
    assert open(path, "rb").read() == on_disk
    assert page.evaluate("editor.text()") == text  # nothing lost

    # The map's name is named as a property: its field is outlined.
    fill(page, "#prop-name", "")
    page.click(*palette(page, "road"))
    page.click(*tile(page, 2, 1))  # fixes the dead end's north
    result = checked(page)
    assert result["state"] == "invalid" and "map line 3 'name ': " in result["message"], result
    assert page.evaluate("document.getElementById('prop-name').classList.contains('bad')")
    fill(page, "#prop-name", "fixed_up")
    assert checked(page)["state"] == "valid"
    assert not page.evaluate("document.getElementById('prop-name').classList.contains('bad')")


@pytest.mark.parametrize("name", ["../x", "/etc/x"])
def test_a_save_name_outside_the_maps_folder_is_refused(page, maps_dir, name):
    open_map(page, TEST_MAP)
    errors = page.evaluate("editor.errors.length")
    fill(page, "#save-name", name)
    press(page, "#save-map")
    error = page.wait_for("editor.errors.length > %d && editor.errors[editor.errors.length - 1]" % errors, TIMEOUT_S)
    assert error["where"] == "Save" and error["code"] == "ERROR_CODE_INVALID_ARGUMENT", error
    assert error["message"] in page.evaluate("document.getElementById('messages').textContent")
    assert not os.path.exists(os.path.join(os.path.dirname(maps_dir), "x.map"))
    assert not os.path.exists("/etc/x.map")


def test_objects_routes_and_undo_redo(page):
    original = open_map(page, TEST_MAP)
    start = page.evaluate("editor.history.undoStack.length")
    objects = page.evaluate("editor.model.objects.length")

    # A house dragged from the palette onto tile (2, 2): centred where it was let go.
    page.drag(*palette(page, "house"), *tile(page, 2, 2))
    house = page.evaluate("editor.model.objects[editor.model.objects.length - 1]")
    assert house["kind"] == "house" and abs(house["x"] - 0) < 1 and abs(house["y"] - -25) < 1, house
    assert page.evaluate("editor.text()").endswith("object house %.2f %.2f 0.00\n" % (house["x"], house["y"]))

    # Selected and moved by dragging it with the select tool, then turned.
    page.click(*palette(page, "select"))
    x0, y0 = tile(page, 2, 2)
    page.drag(x0, y0, x0 + page.evaluate("editor.grid.cell") * 0.5, y0)
    moved = page.evaluate("editor.model.objects[editor.model.objects.length - 1]")
    assert moved["x"] > house["x"] + 10 and moved["y"] == house["y"], moved
    key(page, "r")
    assert page.evaluate("editor.model.objects[editor.model.objects.length - 1].rot") == 345
    assert page.evaluate("editor.text()").endswith(" 345.00\n")

    # A route, its tiles clicked along the road; Backspace takes the last back.
    fill(page, "#route-name", "mine")
    fill(page, "#route-shape", "open")
    press(page, "#add-route")
    for col in range(4):
        page.click(*tile(page, col, 3))
    assert "route mine open\ntiles 0,3 1,3 2,3 3,3\n" in page.evaluate("editor.text()")
    key(page, "Backspace")
    assert "route mine open\ntiles 0,3 1,3 2,3\n" in page.evaluate("editor.text()")
    assert checked(page)["state"] == "valid"
    page.click(*tile(page, 2, 2))  # not road: the daemon says so, and the route is outlined
    result = checked(page)
    assert "route tile 2,2 is not a road tile" in result["message"], result
    assert page.evaluate("document.querySelector('.route-item[data-index=\"1\"]').classList.contains('bad')")
    assert page.evaluate("document.getElementById('check-where').textContent") == "at route 'mine'"
    key(page, "Backspace")

    # Delete removes the selected object (the select tool clicks it first).
    page.click(*palette(page, "select"))
    page.click(*page.evaluate("(o => { const [x, y] = editor.grid.toPx(o.x, o.y);"
                              " const r = editor.grid.canvas.getBoundingClientRect(); return [r.left + x, r.top + y]; })"
                              "(editor.model.objects[editor.model.objects.length - 1])"))
    assert page.evaluate("editor.selection.object") == objects
    key(page, "Delete")
    assert page.evaluate("editor.model.objects.length") == objects

    # Undo walks back through every edit to the opened map, redo forward again.
    final = page.evaluate("editor.text()")
    steps = page.evaluate("editor.history.undoStack.length") - start
    assert steps == 12, page.evaluate("editor.history.undoStack.map(e => e.label)")
    for _ in range(steps):
        key(page, "z", ctrl=True)
    assert page.evaluate("editor.text()") == original
    for _ in range(steps):
        key(page, "y", ctrl=True)
    assert page.evaluate("editor.text()") == final
    press(page, "#undo")  # the buttons do the same
    assert page.evaluate("editor.model.objects.length") == objects + 1
    press(page, "#redo")
    assert page.evaluate("editor.text()") == final


def test_painting_and_erasing_by_dragging_are_one_undo_step_each(page):
    original = open_map(page, TEST_MAP)
    page.click(*palette(page, "road"))
    page.drag(*tile(page, 1, 2), *tile(page, 3, 2), steps=3)
    assert page.evaluate("editor.model.rows") == [".####", "##..#", "#####", "#####"]
    assert checked(page)["state"] == "valid"
    page.click(*palette(page, "erase"))
    page.drag(*tile(page, 3, 1), *tile(page, 3, 2), steps=2)
    assert page.evaluate("editor.model.rows") == [".####", "##..#", "###.#", "#####"]
    page.click(*palette(page, "straight"))
    key(page, "r")  # the palette's piece turns: north-south becomes east-west ("a")
    page.click(*tile(page, 3, 2))
    assert page.evaluate("editor.model.rows[2]") == "###a#"
    key(page, "r")  # now the placed piece turns
    assert page.evaluate("editor.model.rows[2]") == "###5#"
    key(page, "Delete")
    assert page.evaluate("editor.model.rows[2]") == "###.#"
    labels = page.evaluate("editor.history.undoStack.slice(-5).map(e => e.label)")
    assert labels == ["paint", "erase", "paint", "turn road piece", "clear tile"], labels
    for _ in range(5):
        key(page, "z", ctrl=True)
    assert page.evaluate("editor.text()") == original


def test_map_properties_and_resizing_keep_what_fits(page):
    original = open_map(page, TEST_MAP)
    model = page.evaluate("editor.model")
    fill(page, "#prop-width", "6")
    fill(page, "#prop-height", "5")
    press(page, "#prop-resize")
    grown = page.evaluate("editor.model")
    assert grown["rows"] == [row + "." for row in model["rows"]] + ["......"]
    assert grown["routes"] == model["routes"]
    # Objects stay over the tiles they stood on: the grid's centre moved half a tile east and south.
    assert [(o["x"], o["y"]) for o in grown["objects"]] == \
        [(round(o["x"] - 25, 2), round(o["y"] + 25, 2)) for o in model["objects"]]
    assert "grid 6 5\n" in page.evaluate("editor.text()")
    assert checked(page)["state"] == "valid"

    fill(page, "#prop-width", "3")
    fill(page, "#prop-height", "2")
    press(page, "#prop-resize")
    shrunk = page.evaluate("editor.model")
    assert shrunk["rows"] == [".##", "##."]
    assert all(c < 3 and r < 2 for route in shrunk["routes"] for c, r in route["tiles"])
    assert all(abs(o["x"]) <= 75 and abs(o["y"]) <= 50 for o in shrunk["objects"])
    assert checked(page)["state"] == "invalid"  # the cut roads end nowhere: the daemon says where

    fill(page, "#prop-tile-size", "25")
    fill(page, "#prop-surroundings", "urban")
    text = page.evaluate("editor.text()")
    assert "tile_size 25\nsurroundings urban\ngrid 3 2\n" in text
    for _ in range(4):
        press(page, "#undo")
    assert page.evaluate("editor.text()") == original


def test_generate_and_dress_come_from_the_daemon_and_undo(page, client):
    before = open_map(page, TEST_MAP)
    page.evaluate("document.getElementById('generate-box').open = true")
    for selector, value in (("#gen-seed", "7"), ("#gen-width", "6"), ("#gen-height", "5"),
                            ("#gen-tile-size", "25"), ("#gen-surroundings", "urban")):
        fill(page, selector, value)
    press(page, "#generate")
    page.wait_for("editor.text() !== %s && editor.model.width === 6" % js(before), TIMEOUT_S)
    expected = client.configure(pb.Configure(generate_map=pb.GenerateMap(
        seed=7, width=6, height=5, tile_size=25, surroundings="urban"))).map_text
    assert page.evaluate("editor.text()") == expected
    assert checked(page)["state"] == "valid"

    generated = page.evaluate("editor.model")
    fill(page, "#gen-seed", "8")
    press(page, "#dress")
    page.wait_for("document.getElementById('message').textContent.startsWith('dressed')", TIMEOUT_S)
    dressed = page.evaluate("editor.model")
    assert dressed["rows"] == generated["rows"] and dressed["routes"] == generated["routes"]
    assert dressed["objects"] != generated["objects"]

    key(page, "z", ctrl=True)
    assert page.evaluate("editor.model.objects") == generated["objects"]
    key(page, "z", ctrl=True)
    assert page.evaluate("editor.text()") == before


def test_3d_preview_shows_a_camera_that_orbits_the_map(studio_daemon, browser, maps_dir):
    daemon = studio_daemon("--map", os.path.join(maps_dir, TEST_MAP + ".map"), "--maps-dir", maps_dir,
                           mode="realtime")
    page = browser.new_page("http://127.0.0.1:%d/editor.html?token=%s" % (daemon.http, daemon.token))
    try:
        page.wait_for("window.editor && editor.ready", TIMEOUT_S)
        press(page, "#preview")
        page.wait_for("editor.preview.view && editor.preview.view.frames >= 1", TIMEOUT_S)
        header = page.evaluate("editor.preview.view.lastHeader")
        assert header["camera"] == "preview" and header["width"] == 480 and header["height"] == 270
        first = header["camera_pose"]["position"]
        # Above the south-west corner of the 5 x 4 grid of 50 m tiles.
        assert abs(first["x"] - -125) < 0.5 and abs(first["y"] - -100) < 0.5 and first["z"] > 20, first
        press(page, "#orbit-right")
        page.wait_for("(p => p && Math.hypot(p.x - (%f), p.y - (%f)) > 10)"
                      "(editor.preview.view.lastHeader.camera_pose.position)" % (first["x"], first["y"]), TIMEOUT_S)
        moved = page.evaluate("editor.preview.view.lastHeader.camera_pose.position")
        assert abs(moved["z"] - first["z"]) < 1e-6
        assert abs((moved["x"] ** 2 + moved["y"] ** 2) - (first["x"] ** 2 + first["y"] ** 2)) < 1.0
        # Dragging across the image orbits it too.
        x, y = page.evaluate("(r => [r.left + r.width / 2, r.top + r.height / 2])"
                             "(editor.preview.view.overlay.getBoundingClientRect())")
        page.drag(x, y, x + 100, y, steps=4)
        page.wait_for("(p => p && Math.hypot(p.x - (%f), p.y - (%f)) > 10)"
                      "(editor.preview.view.lastHeader.camera_pose.position)" % (moved["x"], moved["y"]), TIMEOUT_S)
        assert page.evaluate("editor.errors") == []
        page.collect()
        assert page.problems == [], page.problems
    finally:
        page.evaluate("editor.preview.stopView()")
        page.close()
