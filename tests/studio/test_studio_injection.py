"""Names from any client cannot run script in the studio: a client spawns
entities and adds a camera whose names are HTML with event handlers, the page
(Debian's Chromium, tools/cdp_driver.py) shows them in its menus as literal
text and runs none of them; the daemon's Content-Security-Policy forbids
inline script, so even markup that reached the page could not run.
Skipped, with the reason, where Chromium is not installed."""

import json
import urllib.request

import pytest

import sim4cv
from cdp_driver import Browser, chromium_path
from conftest import MAP, TIMEOUT_S, clean_page

pytestmark = pytest.mark.skipif(
    chromium_path() is None,
    reason="Chromium is not installed: the studio's browser tests need Debian's chromium (scripts/setup.sh)")

# Each sets a flag on window when its handler runs; all within the 64-byte name limit.
CAR = '<img src=x onerror="window.ran_car=1">'
UAV = '<svg onload="window.ran_uav=1"></svg>'
CAMERA = '<img src=x onerror="window.ran_cam=1">'
RAN = "[window.ran_car, window.ran_uav, window.ran_cam, window.ran_inline].filter(Boolean).length"
MENUS = ("#uav-target", "#camera-mount", "#drive-car", "#view-0 select.camera")


def option_texts(page, selector):
    return page.evaluate("[...document.querySelectorAll(%s + ' option')].map((o) => o.textContent)"
                         % json.dumps(selector))


def test_hostile_names_show_as_text_and_run_nothing(studio_daemon):
    daemon = studio_daemon("--map", MAP)
    client = sim4cv.connect(daemon.address, name="namer")
    try:
        car = client.spawn("car", CAR, 0.0, 0.0, 0.0, snap_to_lane=True)
        uav = client.spawn("uav", UAV, 5.0, 5.0, 10.0)
        client.add_camera(CAMERA, mounted_on=UAV)
        with Browser() as browser, clean_page(
                browser, "http://127.0.0.1:%d/?view=%s:rgb&token=%s" % (daemon.http, urllib.request.quote(CAMERA), daemon.token),
                "window.studio && studio.ready && studio.views.length === 1") as page:
            page.wait_for("document.querySelectorAll('#uav-target option').length >= 2", TIMEOUT_S)
            page.wait_for("document.querySelectorAll('#view-0 select.camera option').length >= 1", TIMEOUT_S)
            assert "%d %s" % (car, CAR) in option_texts(page, "#uav-target")
            assert "%d %s" % (uav, UAV) in option_texts(page, "#uav-target")
            assert "%d %s" % (uav, UAV) in option_texts(page, "#camera-mount")
            assert "%d %s" % (car, CAR) in option_texts(page, "#drive-car")
            assert CAMERA in option_texts(page, "#view-0 select.camera")
            for menu in MENUS:  # the markup stayed text: no element was made from it
                assert page.evaluate("document.querySelectorAll(%s + ' img, ' + %s + ' svg').length"
                                     % (json.dumps(menu), json.dumps(menu))) == 0, menu
            assert page.evaluate(RAN) == 0
    finally:
        client.close()


def test_daemon_forbids_inline_script(studio_daemon):
    daemon = studio_daemon("--map", MAP)
    with urllib.request.urlopen("http://127.0.0.1:%d/" % daemon.http, timeout=TIMEOUT_S) as answer:
        policy = answer.headers["Content-Security-Policy"]
    assert policy is not None and "script-src 'self'" in policy and "unsafe-inline" not in policy.split("style-src")[0]
    with Browser() as browser:
        page = browser.new_page("http://127.0.0.1:%d/?token=%s" % (daemon.http, daemon.token))
        page.wait_for("window.studio && studio.ready", TIMEOUT_S)
        page.evaluate("""(() => { const s = document.createElement("script"); s.textContent = "window.ran_inline = 1";
                                  document.body.append(s);
                                  document.body.insertAdjacentHTML("beforeend",
                                    '<img src="data:," onerror="window.ran_inline = 1">'); })()""")
        page.wait_for("new Promise((done) => setTimeout(() => done(true), 300))", TIMEOUT_S)
        page.collect()
        assert page.evaluate(RAN) == 0
        assert any("Content Security Policy" in problem for problem in page.problems), page.problems
