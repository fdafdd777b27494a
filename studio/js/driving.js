// Driving a car by hand from the page (docs/studio.md, "Driving"): the
// keyboard and a gamepad (the browser's Gamepad API) become Controls, sent
// at a fixed rate on a WebSocket session of the driver's own; every State
// the driver's session gets while driving is scored (drive_score.js).
//
// Keys (not while typing in a field): W or Up throttle, S or Down brake,
// A/D or Left/Right steer, Space full brake. Steering ramps towards full
// lock at STEER_RATE per second and back to centre at CENTRE_RATE (as the
// Python human driver does, sim4cv/driving_human.py); throttle and brake
// ramp too. The page losing focus, or driving stopped, brakes the car.

import { StudioSocket } from "./protocol.js";
import { headingOf } from "./world_map.js";
import { DriveScore, scoreRows, scoreTotals } from "./drive_score.js";
import { option, setOptions } from "./dom.js";

export const CONTROLS_HZ = 20;
export const STEER_RATE = 2.5, CENTRE_RATE = 4.0;  // steering units per second
export const THROTTLE_RATE = 2.0, BRAKE_RATE = 5.0, RELEASE_RATE = 5.0;
const DEADZONE = 0.1;
const KEYS = {
  KeyW: "up", ArrowUp: "up", KeyS: "down", ArrowDown: "down", KeyA: "left", ArrowLeft: "left",
  KeyD: "right", ArrowRight: "right", Space: "brake",
};
// The driving study's first-person camera (docs/driving.md, "Camera") and the scenes' chase camera.
export const DRIVE_CAMERAS = {
  front: { suffix: "_front", width: 320, height: 180, fov_y_deg: 60, pitch_down_deg: 5, gimbal: false,
           offset: { x: 2.35, y: 0, z: 0.3 } },
  chase: { suffix: "_chase", width: 320, height: 180, fov_y_deg: 60, pitch_down_deg: 15, gimbal: false,
           offset: { x: -9, y: 0, z: 3 } },
};
const $ = (id) => document.getElementById(id);
const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
const towards = (value, target, rate, dt) => value + clamp(target - value, -rate * dt, rate * dt);

// Keys held and the first connected gamepad, turned into smooth controls.
export class DriveInput {
  constructor() {
    this.held = new Set();
    this.steering = this.throttle = this.brake = 0;
    this.t = null;
    this.gamepad = null;  // the id of the pad last read
    addEventListener("keydown", (e) => this.key(e, true));
    addEventListener("keyup", (e) => this.key(e, false));
    addEventListener("blur", () => this.held.clear());
  }

  key(event, down) {
    const name = KEYS[event.code];
    if (!name || /^(INPUT|SELECT|TEXTAREA)$/.test(event.target?.tagName || "")) return;
    if (down) this.held.add(name); else this.held.delete(name);
    if (this.active) event.preventDefault();  // no scrolling by arrows or space while driving
  }

  reset() {
    this.held.clear();
    this.steering = this.throttle = this.brake = 0;
    this.t = null;
  }

  // The standard mapping's left stick and triggers (else the left stick's
  // vertical axis: up throttle, down brake); null without a pad.
  readGamepad() {
    const pads = (navigator.getGamepads ? Array.from(navigator.getGamepads()) : []).filter((p) => p && p.connected);
    const pad = pads[0];
    this.gamepad = pad ? pad.id : null;
    if (!pad) return null;
    const dead = (v) => (Math.abs(v || 0) < DEADZONE ? 0 : v);
    const button = (i) => (pad.buttons[i] ? (typeof pad.buttons[i] === "object" ? pad.buttons[i].value : pad.buttons[i]) : 0);
    const steering = dead(pad.axes[0]);
    if (pad.mapping === "standard" && pad.buttons.length > 7) {
      return { steering, throttle: dead(button(7)), brake: dead(button(6)) };
    }
    const vertical = dead(pad.axes[1]);
    return { steering, throttle: Math.max(0, -vertical), brake: Math.max(0, vertical) };
  }

  // The controls at time `t` (s); `speedCap` cuts the throttle at or above it.
  update(t, speed = 0, speedCap = Infinity) {
    const dt = this.t === null ? 0 : clamp(t - this.t, 0, 0.25);
    this.t = t;
    const h = (name) => this.held.has(name);
    const steerTarget = (h("right") ? 1 : 0) - (h("left") ? 1 : 0);
    this.steering = towards(this.steering, steerTarget, steerTarget ? STEER_RATE : CENTRE_RATE, dt);
    this.throttle = towards(this.throttle, h("up") ? 1 : 0, h("up") ? THROTTLE_RATE : RELEASE_RATE, dt);
    this.brake = h("brake") ? 1 : towards(this.brake, h("down") ? 1 : 0, h("down") ? BRAKE_RATE : RELEASE_RATE, dt);
    const pad = this.readGamepad() || { steering: 0, throttle: 0, brake: 0 };
    const out = {
      steering: clamp(this.steering + pad.steering, -1, 1),
      throttle: clamp(Math.max(this.throttle, pad.throttle), 0, 1),
      brake: clamp(Math.max(this.brake, pad.brake), 0, 1),
    };
    if (speed >= speedCap) out.throttle = 0;
    return out;
  }
}

// The Drive panel: which car, from which camera, start/stop, the live score.
export class Driving {
  constructor(app) {
    this.app = app;
    this.input = new DriveInput();
    this.active = false;
    this.car = null;  // {id, name} while driving
    this.score = null;  // DriveScore of the current (or last) run
    this.controls = { steering: 0, throttle: 0, brake: 0 };  // the last Controls sent
    this.sent = 0;
    this.speed = 0;
    this.focused = true;
    this.socket = null;
    $("drive-start").onclick = () => (this.active ? this.stop("stopped") : this.start());
    $("drive-spawn").onclick = () => this.spawnCar();
    $("drive-download").onclick = () => this.prepareDownload();
    addEventListener("blur", () => { this.focused = false; this.show(); });
    addEventListener("focus", () => { this.focused = true; this.input.reset(); this.show(); });
    for (const change of ["gamepadconnected", "gamepaddisconnected"]) {
      addEventListener(change, () => { this.input.readGamepad(); this.show(); });
    }
    this.show();
  }

  // The world's cars in the car menu (the selection kept).
  setWorld(world) {
    const menu = $("drive-car"), current = menu.value;
    const cars = (world.entities || []).filter((e) => e.kind === "ENTITY_KIND_CAR");
    setOptions(menu, cars.length ? cars.map((e) => option(`${e.id} ${e.name}`, e.id)) : [option("(no car: spawn one)", "")],
               false);
    if (cars.some((e) => String(e.id) === current)) menu.value = current;
    // The map's routes: the score can follow one (QueryRoad.route) instead of the nearest lane.
    const routes = $("drive-route"), chosen = routes.value;
    routes.replaceChildren(new Option("score: nearest lane", ""),
                           ...(world.routes || []).map((name) => new Option(`score: route ${name}`, name)));
    if ((world.routes || []).includes(chosen)) routes.value = chosen;
  }

  // A car clicked on the map becomes the one to drive (not while driving).
  picked(entity) {
    if (entity && entity.kind === "ENTITY_KIND_CAR" && !this.active) $("drive-car").value = String(entity.id);
  }

  // A car on the lane nearest the last point clicked on the map (else the map's centre in view), selected.
  async spawnCar() {
    const point = this.app.entityTools.lastClick || { x: this.app.map.view.cx, y: this.app.map.view.cy };
    const id = await this.app.entityTools.spawn("ENTITY_KIND_CAR", point);
    if (id) $("drive-car").value = String(id);
  }

  async start() {
    if (this.starting) return;  // a second press while the session opens
    this.starting = true;
    try {
      await this.begin();
    } finally {
      this.starting = false;
    }
  }

  async begin() {
    const id = Number($("drive-car").value);
    const info = (this.app.world?.entities || []).find((e) => e.id === id && e.kind === "ENTITY_KIND_CAR");
    if (!info) {
      this.app.reportError(new Error("choose a car to drive (or spawn one)"), "Drive");
      return;
    }
    try {  // a session per run: closing it when driving stops frees the car for other clients at once
      const socket = new StudioSocket("studio-driver");
      socket.onError = (error) => this.refused(error, socket);
      socket.onClose = (reason) => { if (this.active && this.socket === socket) this.stop(reason, true); };
      await socket.open();
      this.socket = socket;
    } catch (error) {
      this.app.reportError(error, "Drive");
      return;
    }
    const camera = await this.ensureCamera(info, $("drive-view").value);
    this.car = { id: info.id, name: info.name };
    this.route = $("drive-route").value;
    this.score = new DriveScore({ car: info.name, car_id: info.id, scene: this.app.world.scene_name, camera,
                                  route: this.route || null, started: new Date().toISOString() });
    this.roadProblem = false;
    this.stopNote = "";
    this.speed = 0;
    this.input.reset();
    // Keys go to the page, not to the button or menu last used (space would press it, arrows change it).
    if (document.activeElement && document.activeElement !== document.body) document.activeElement.blur();
    this.input.active = this.active = true;
    this.run = {};  // this run's token: loops of an earlier run see it changed and end
    this.timer = setInterval(() => this.tick(), 1000 / CONTROLS_HZ);
    this.tick();
    this.scoreLoop(this.run);
    this.show();
  }

  // Stops sending: the last Controls are a full brake, which the car keeps
  // (unless `noBrake`: the car is gone, or not ours), and the driver's
  // session closes, so the car is free for any client at once.
  stop(reason, noBrake = false) {
    if (!this.active) return;
    clearInterval(this.timer);
    this.input.active = this.active = false;
    this.run = null;
    this.controls = { steering: 0, throttle: 0, brake: 1 };
    if (!noBrake) this.socket?.sendControls(this.car.id, this.controls);
    this.socket?.close();  // after the brake: a WebSocket sends what it holds before closing
    this.app.note(`driving ${reason}`);
    this.show(reason);
  }

  // An Error on the driver's session with no request: its Controls were
  // refused (another client drives the car: INVALID_STATE). The first ends
  // the run; those of Controls already on their way are not repeated.
  refused(error, socket) {
    if (socket !== this.socket || !this.active) return;
    this.app.reportError(error, "Drive");
    this.stop(`refused: ${error.code.replace("ERROR_CODE_", "")}`, true);
  }

  // The driving camera mounted on the car (added unless the world has it), in a live view.
  async ensureCamera(car, kind) {
    const spec = DRIVE_CAMERAS[kind] || DRIVE_CAMERAS.front;
    const name = `${car.name}${spec.suffix}`.slice(0, 64);
    const known = (this.app.world.cameras || []).find((c) => c.name === name);
    if (!known) {
      const { suffix, ...request } = spec;
      const answer = await this.app.controls.run("AddCamera", { add_camera: { name, mounted_on: car.name, ...request } });
      if (!answer) return null;
    }
    if (!this.app.views.some((v) => v.camera === name)) this.app.addView(name, "CHANNEL_RGB", { boxes: false });
    return name;
  }

  tick() {
    if (!this.active) return;
    const cap = Number($("drive-max-speed").value) || Infinity;
    const wanted = this.input.update(performance.now() / 1000, this.speed, cap);
    this.controls = this.focused ? wanted : { steering: 0, throttle: 0, brake: 1 };
    this.socket.sendControls(this.car.id, this.controls);
    this.sent += 1;
    this.showStatus();
  }

  // GetState and QueryRoad on the driver's session, one after the other, at most CONTROLS_HZ a second.
  async scoreLoop(run) {
    while (this.run === run) {
      const started = performance.now();
      let state;
      try {
        state = await this.socket.getState();
      } catch (error) {
        return;  // the session closed: onClose stopped the run
      }
      if (this.run !== run) return;
      const car = (state.entities || []).find((e) => e.id === this.car.id);
      if (!car) {
        this.stop("stopped: the car is gone", true);
        return;
      }
      const p = car.position || {}, v = car.linear_velocity || {};
      const yaw = (headingOf(car.orientation) * 180) / Math.PI;
      this.speed = Math.hypot(v.x || 0, v.y || 0);
      let deviation = null;
      try {
        const point = { x: p.x || 0, y: p.y || 0, z: 0 };
        // Along a route its lane is the measure (a missed turn is off it); else the nearest lane this way.
        const query = this.route ? { point, route: this.route } : { point, heading_deg: yaw, use_heading: true };
        const answer = await this.socket.configure({ query_road: query });
        deviation = -(answer.road?.lateral_offset || 0);  // + right of the direction of travel, as driving_metrics
      } catch (error) {
        if (!this.roadProblem) this.app.reportError(error, "Drive score (QueryRoad)");
        this.roadProblem = true;
      }
      if (this.run !== run) return;
      const c = this.controls;
      this.score.add({ t: Number(state.sim_time || 0), x: p.x || 0, y: p.y || 0, yaw_deg: yaw, speed: this.speed,
                       deviation_m: deviation, steering: c.steering, throttle: c.throttle, brake: c.brake });
      this.showScore();
      this.showStatus();
      await new Promise((r) => setTimeout(r, Math.max(0, 1000 / CONTROLS_HZ - (performance.now() - started))));
    }
  }

  prepareDownload() {
    const link = $("drive-download");
    if (!this.score) return;
    if (link.href.startsWith("blob:")) URL.revokeObjectURL(link.href);
    link.href = URL.createObjectURL(new Blob([JSON.stringify(this.score, null, 1)], { type: "application/json" }));
    link.download = `drive_${this.score.info.car}_${this.score.info.started.replace(/[:.]/g, "-")}.json`;
  }

  show(note = null) {
    $("drive-start").textContent = this.active ? "stop driving" : "drive";
    $("drive-start").classList.toggle("driving", this.active);
    $("drive-car").disabled = $("drive-view").disabled = $("drive-route").disabled = this.active;
    $("drive-download").classList.toggle("hidden", !this.score);
    this.showStatus(note);
    this.showScore();
  }

  // The car, its speed and the Controls being sent; the input in use.
  showStatus(note = null) {
    const c = this.controls;
    const pad = this.input.gamepad ? `gamepad: ${this.input.gamepad.slice(0, 40)}` : "keyboard (no gamepad)";
    if (note !== null) this.stopNote = note;
    const status = !this.active ? this.stopNote || "" :
      `${this.car.id} ${this.car.name} · ${this.speed.toFixed(1)} m/s (${(this.speed * 3.6).toFixed(0)} km/h) · ` +
      `steer ${c.steering.toFixed(2)} · throttle ${c.throttle.toFixed(2)} · brake ${c.brake.toFixed(2)}` +
      (this.focused ? "" : " · the page lost focus: braking");
    $("drive-status").textContent = `${status}${status ? "\n" : ""}${pad}`;
  }

  showScore() {
    if (!this.score) return;
    const summary = this.score.summary();
    $("drive-score").innerHTML = scoreRows(summary);
    $("drive-totals").textContent = scoreTotals(summary);
  }
}
