#!/usr/bin/env python3
"""Screenshots of the studio for docs/studio.md, made the way the browser
tests drive it (tools/cdp_driver.py): a sim4cvd of our own on a shipped map,
a lockstep client stepping it, and headless Chromium at a fixed size.

    /usr/bin/python3 tools/studio_screenshots.py [--out docs/studio]

Writes overview.png (two live views, the map, the controls), channels.png
(ground-truth channels side by side), map.png (the map with a selected
entity) and night.png (after a SetConditions from the page): deterministic
up to the frame the views happen to show, the daemon is lockstep and every
shot is taken after a known frame. Then, on a real-time daemon of its own on
driving/test/01_urban: drive.png (the Drive panel after a few seconds of
keyboard driving, with its score) and editor.png, preview.png (the map
editor on that map with the daemon's check, and its 3D preview).
"""

import argparse
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(REPO, "clients", "python"))

import sim4cv  # noqa: E402
from sim4cv.daemon import OwnDaemon  # noqa: E402
from cdp_driver import Browser  # noqa: E402

MAP = os.path.join(REPO, "scenes", "tracking", "easy_urban.map")
DRIVING_MAP = os.path.join(REPO, "scenes", "driving", "test", "01_urban.map")


def element_clip(page, element_id):
    return page.evaluate("(() => { const r = document.getElementById(%s).getBoundingClientRect();"
                         " return {x: r.left, y: r.top, width: r.width, height: r.height}; })()"
                         % json.dumps(element_id))


def checked(page):
    page.collect()
    if page.problems:
        sys.exit("the page reported problems: %s" % page.problems)


def driving_and_editor(browser, out):
    """drive.png, editor.png and preview.png, on a real-time daemon."""
    with OwnDaemon(["--map", DRIVING_MAP, "--http-port", "0", "--udp-port", "-1"], mode="realtime") as daemon:
        base = "http://127.0.0.1:%s/" % daemon.fields["http"]
        page = browser.new_page(base + "?view=car_chase:rgb")
        page.wait_for("window.studio && studio.ready && studio.views.length === 1", 20.0)
        choose(page, "#drive-car", "1")
        page.evaluate("document.getElementById('drive-start').click()")
        page.wait_for("studio.views.length === 2 && studio.views[1].frames > 0", 20.0)
        page.key("w", True)
        time.sleep(4.0)
        page.key("w", False)
        time.sleep(1.0)
        page.screenshot(os.path.join(out, "drive.png"))
        page.evaluate("document.getElementById('drive-start').click()")  # stop driving: brake, free the car
        checked(page)
        page.close()

        page = browser.new_page(base + "editor.html")
        page.wait_for("window.editor && editor.ready", 20.0)
        time.sleep(1.0)  # the daemon's check of the loaded map
        page.screenshot(os.path.join(out, "editor.png"))
        page.evaluate("document.getElementById('preview').click()")
        page.wait_for("editor.preview.view && editor.preview.view.frames >= 3", 30.0)
        page.screenshot(os.path.join(out, "preview.png"), clip=element_clip(page, "preview-box"))
        checked(page)
        page.close()


def shown(page, client, views, steps=1):
    """Steps `steps` frames; waits until every view drew the last one."""
    for _ in range(steps):
        frame = client.step_and_receive(20.0)
    for view in range(views):
        page.wait_for("studio.views[%d].lastHeader && Number(studio.views[%d].lastHeader.frame_id) === %d"
                      % (view, view, frame.frame_id), 20.0)
    time.sleep(0.3)  # the map's next State poll
    return frame


def choose(page, selector, value):
    page.evaluate("""(() => { const e = document.querySelector(%s); e.value = %s;
                     e.dispatchEvent(new Event("change")); })()""" % (json.dumps(selector), json.dumps(value)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=os.path.join(REPO, "docs", "studio"))
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    with OwnDaemon(["--map", MAP, "--http-port", "0", "--udp-port", "-1", "--width", "480", "--height", "270",
                    "--traffic-cars", "6", "--traffic-pedestrians", "6"]) as daemon, Browser(1500, 950) as browser:
        client = sim4cv.connect(daemon.address, name="screenshots")
        client.subscribe("uav", ["rgb"], "lockstep")
        client.step_and_receive(20.0)
        url = "http://127.0.0.1:%s/?view=uav:rgb&view=car_chase:rgb&max_fps=0" % daemon.fields["http"]
        page = browser.new_page(url)
        page.wait_for("window.studio && studio.ready && studio.views.length === 2", 20.0)
        page.wait_for("studio.views.every(v => v.stats.textContent.startsWith('subscribed'))", 20.0)
        shown(page, client, 2, steps=150)
        car = page.evaluate("studio.map.entityOnScreen(1)")
        rect = page.evaluate("(() => { const r = document.getElementById('map').getBoundingClientRect();"
                             " return [r.left, r.top]; })()")
        page.click(rect[0] + car[0], rect[1] + car[1])
        shown(page, client, 2)
        page.screenshot(os.path.join(args.out, "overview.png"))
        page.screenshot(os.path.join(args.out, "map.png"), clip=element_clip(page, "right"))

        for view, channel in ((0, "CHANNEL_SEMANTIC"), (1, "CHANNEL_DEPTH")):
            choose(page, "#view-%d select.channel" % view, channel)
        page.evaluate("void studio.addView('uav', 'CHANNEL_MASK')")
        page.evaluate("void studio.addView('uav', 'CHANNEL_NORMALS')")
        page.wait_for("studio.views.length === 4 && studio.views.every(v => "
                      "v.stats.textContent.startsWith('subscribed') || v.frames > 0)", 20.0)
        shown(page, client, 4, steps=2)
        page.screenshot(os.path.join(args.out, "channels.png"), clip=element_clip(page, "views"))

        for view in (3, 2):
            page.evaluate("studio.removeView(studio.views[%d])" % view)
        for view in (0, 1):
            choose(page, "#view-%d select.channel" % view, "CHANNEL_RGB")
        choose(page, "#preset", "night")
        page.evaluate("document.getElementById('apply-conditions').click()")
        page.wait_for("document.getElementById('conditions-now').textContent.startsWith('night')", 20.0)
        shown(page, client, 2, steps=2)
        page.screenshot(os.path.join(args.out, "night.png"))
        checked(page)
        client.close()
        driving_and_editor(browser, args.out)
    print("studio_screenshots: wrote overview.png, map.png, channels.png, night.png, drive.png, editor.png, "
          "preview.png to %s" % args.out)


if __name__ == "__main__":
    main()
