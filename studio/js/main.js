// The studio page: a control session (world, state, Configure), the live
// views (a session each), the map, the controls, spawning and routes
// (entity_tools.js) and driving a car by hand (driving.js, with its own
// session). window.studio is this App, for the browser tests and the
// console; window.studio.driving the Drive panel (its .score the run's score).
//
// Page URL options: ?view=CAMERA[:CHANNEL] (repeatable; default: the first
// camera's RGB), &rgb=raw (lossless RGB in every view), &max_fps=N (each
// view's cap, default 30; 0: every frame), &poll_ms=N (State).

import { StudioSocket, estimateClockOffsetMs } from "./protocol.js";
import { CHANNELS } from "./colours.js";
import { LiveView } from "./live_view.js";
import { WorldMap } from "./world_map.js";
import { Controls } from "./controls.js";
import { Driving } from "./driving.js";
import { EntityTools } from "./entity_tools.js";

const MAX_VIEWS = 4;
const MAX_ERRORS_SHOWN = 30;
const $ = (id) => document.getElementById(id);

class App {
  constructor() {
    this.params = new URLSearchParams(location.search);
    this.maxFps = Number(this.params.get("max_fps") ?? 30);
    this.views = [];
    this.world = null;
    this.state = null;
    this.errors = [];
    this.clockOffsetMs = null;
    this.nextViewIndex = 0;
    this.mapTextScene = null;
    this.ready = false;
  }

  async start() {
    this.map = new WorldMap($("map"), (entity) => {
      this.controls.select(entity);
      this.driving.picked(entity);
    });
    this.controls = new Controls(this);
    this.entityTools = new EntityTools(this);
    this.driving = new Driving(this);
    this.control = new StudioSocket("studio");
    this.control.onError = (error) => this.reportError(error, "studio");
    this.control.onClose = (reason) => this.setStatus(`disconnected: ${reason}; reload the page`, true);
    $("add-view").onclick = () => this.addView(this.cameras()[0]);
    $("routes").onchange = (e) => { this.map.showRoutes = e.target.checked; this.map.dirty = true; };
    try {
      this.welcome = await this.control.open();
      this.clockOffsetMs = await estimateClockOffsetMs().catch(() => null);
      await this.refreshWorld(true);
      const listed = await this.control.configure({ list_maps: {} });
      this.controls.setMaps(listed.maps || []);
    } catch (error) {
      this.reportError(error, "connecting");
      return;
    }
    const views = this.params.getAll("view");
    for (const spec of views.length ? views : [this.cameras()[0]]) {
      const [camera, channel] = spec.split(":");
      const known = CHANNELS.find((c) => c.name === channel);
      this.addView(camera, known ? known.channel : "CHANNEL_RGB");
    }
    this.pollState(Number(this.params.get("poll_ms") || 100));
    setInterval(() => this.refreshWorld(false).catch((e) => this.reportError(e, "GetWorld")), 2000);
    this.ready = true;
  }

  cameras() {
    return (this.world?.cameras || []).map((c) => c.name).filter(Boolean);
  }

  addView(camera, channel = "CHANNEL_RGB", options = {}) {
    if (this.views.length >= MAX_VIEWS) {
      this.reportError(new Error(`at most ${MAX_VIEWS} views; close one first`), "view");
      return null;
    }
    const view = new LiveView(this, $("views"), this.nextViewIndex++, camera, channel, options);
    if (this.params.get("rgb") === "raw") {
      view.rgb = "raw";
      view.panel.querySelector("select.rgb").value = "raw";
    }
    this.views.push(view);
    view.connect();
    return view;
  }

  removeView(view) {
    view.close();
    this.views = this.views.filter((v) => v !== view);
  }

  // GetWorld; with `withMap` (or a new scene) also the map's text.
  async refreshWorld(withMap) {
    let answer = await this.control.configure({ get_world: { with_map_text: withMap } });
    if (!withMap && answer.world.scene_name !== this.world?.scene_name) {
      answer = await this.control.configure({ get_world: { with_map_text: true } });
      withMap = true;
    }
    this.world = answer.world;
    if (withMap) this.map.setMapText(answer.map_text || "");
    this.controls.setWorld(this.world);
    this.entityTools.setWorld(this.world);
    this.driving.setWorld(this.world);
    for (const view of this.views) view.updateCameras();
    const w = this.welcome;
    $("scene").textContent = `${this.world.scene_name} · ${(w.mode || "").replace("SIM_MODE_", "").toLowerCase()} · ` +
      `${w.frame_hz} fps · sim4cvd ${w.server_version}`;
  }

  // GetState one at a time, at most every `periodMs`.
  async pollState(periodMs) {
    for (;;) {
      const started = performance.now();
      try {
        this.state = await this.control.getState();
      } catch (error) {
        return;  // the control session closed; the status says so
      }
      this.map.setState(this.state);
      $("frame").textContent = `frame ${this.state.frame_id || 0} · t = ${Number(this.state.sim_time || 0).toFixed(2)} s`;
      if (this.controls.selected) {
        // A State asked for before a Spawn was carried out lacks the new entity:
        // the selection goes only when the world no longer holds it.
        const id = this.controls.selected.id;
        const now = (this.state.entities || []).find((e) => e.id === id);
        if (now) this.controls.select(now);
        else if (!(this.world?.entities || []).some((e) => e.id === id)) this.controls.select(null);
      }
      await new Promise((r) => setTimeout(r, Math.max(0, periodMs - (performance.now() - started))));
    }
  }

  setStatus(text, bad = false) {
    $("status").textContent = text;
    $("status").className = bad ? "bad" : "";
  }

  note(text) {
    this.setStatus(text);
  }

  // Every Error the daemon sends (and the page's own failures) lands here.
  reportError(error, where) {
    if (error.aborted) return;
    const entry = { where, code: error.code || "", message: error.message || String(error), fatal: Boolean(error.fatal),
                    time: new Date().toLocaleTimeString() };
    this.errors.push(entry);
    const item = document.createElement("li");
    item.textContent = `${entry.time} ${where}: ${entry.code ? entry.code.replace("ERROR_CODE_", "") + " · " : ""}${entry.message}`;
    $("errors").prepend(item);
    while ($("errors").children.length > MAX_ERRORS_SHOWN) $("errors").lastChild.remove();
    this.setStatus(`${where}: ${entry.message}`, true);
  }
}

window.studio = new App();
window.studio.start();
