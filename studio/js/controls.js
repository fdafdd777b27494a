// The controls panel: what Configure can do (docs/protocol.md, "Configuring
// the world"), each control one request whose Error, if any, is shown in the
// page's error list. The daemon checks every value; the page only builds
// requests.

import { headingOf } from "./world_map.js";
import { option, setOptions } from "./dom.js";

// SetConditions.preset's values (protocol/conditions.h).
export const PRESETS = ["clear_noon", "clear_morning", "overcast", "fog", "dusk", "night", "rain"];

const $ = (id) => document.getElementById(id);

export class Controls {
  constructor(app) {
    this.app = app;
    setOptions($("preset"), PRESETS.map((p) => option(p)));
    $("load-map").onclick = () => this.run("LoadMap", { load_map: { name: $("map-name").value } }, true);
    $("apply-conditions").onclick = () => {
      const request = { preset: $("preset").value, quality: $("quality").value };
      if ($("hour").value !== "") request.hour = Number($("hour").value);
      this.run("SetConditions", { set_conditions: request });
    };
    $("reset").onclick = () => this.run("Reset", { reset: {} }, true);
    $("add-camera").onclick = () => this.addCamera();
    $("follow").onclick = () => this.follow();
    $("log-toggle").onclick = () => this.toggleLog();
    $("remove-entity").onclick = () => {
      if (this.selected) this.run("Remove", { remove: { entity_id: this.selected.id } });
    };
  }

  setMaps(names) {
    setOptions($("map-name"), names.map((n) => option(n)));
  }

  // The world changed (or was fetched): entity list for mounts, conditions shown.
  setWorld(world) {
    const mount = $("camera-mount");
    const current = mount.value;
    setOptions(mount, [option("(fixed in the world)", ""),
                       ...(world.entities || []).map((e) => option(`${e.id} ${e.name}`, e.name))], false);
    mount.value = current;
    const look = world.conditions || {};
    $("conditions-now").textContent = `${look.preset || "?"}, ${Number(look.hour || 0).toFixed(1)} h, ${look.quality || "?"}`;
    this.logFile = world.log_file || "";
    $("log-now").textContent = this.logFile || "none";
    $("log-toggle").textContent = this.logFile ? "stop log" : "start log";
  }

  // StartLog under the daemon's --logs-dir, or StopLog; an existing file is
  // replaced only when the person says so.
  async toggleLog() {
    if (this.logFile) return this.run("StopLog", { stop_log: {} });
    const request = { name: $("log-name").value.trim(), label: $("log-label").value };
    try {
      await this.app.control.configure({ start_log: request });
    } catch (error) {
      if (error.code !== "ERROR_CODE_ALREADY_EXISTS" || !confirm(`${error.message}\n\nReplace it?`)) {
        this.app.reportError(error, "StartLog");
        return null;
      }
      return this.run("StartLog", { start_log: { ...request, overwrite: true } });
    }
    this.app.note("StartLog done");
    return this.app.refreshWorld(false);
  }

  async run(what, request, newWorld = false) {
    try {
      const answer = await this.app.control.configure(request);
      this.app.note(`${what} done`);
      await this.app.refreshWorld(newWorld);
      return answer;
    } catch (error) {
      this.app.reportError(error, what);
      return null;
    }
  }

  async addCamera(request = null) {
    request = request || {
      name: $("camera-name").value.trim(),
      mounted_on: $("camera-mount").value,
      width: Number($("camera-width").value),
      height: Number($("camera-height").value),
      fov_y_deg: Number($("camera-fov").value),
      pitch_down_deg: Number($("camera-pitch").value),
      gimbal: $("camera-mount").value !== "",
      offset: { x: Number($("camera-x").value), y: Number($("camera-y").value), z: Number($("camera-z").value) },
    };
    const answer = await this.run("AddCamera", { add_camera: request });
    if (answer) this.app.addView(request.name);
    return answer;
  }

  // A chase camera behind and above the selected entity, shown in a new view.
  follow() {
    const entity = this.selected;
    if (!entity) return;
    const uav = entity.kind === "ENTITY_KIND_UAV";
    this.addCamera({
      name: `follow_${entity.name || entity.id}`.slice(0, 64),
      mounted_on: entity.name,
      width: 320, height: 180, fov_y_deg: 70,
      pitch_down_deg: uav ? 60 : 12,
      gimbal: true,
      offset: uav ? { x: 0, y: 0, z: -0.3 } : { x: -9, y: 0, z: 3.5 },
    });
  }

  // The entity clicked on the map (null: none), refreshed with every State.
  select(entity) {
    this.selected = entity;
    this.app.entityTools?.select(entity);
    $("follow").disabled = $("remove-entity").disabled = !entity;
    if (!entity) {
      $("entity-state").textContent = "click an entity on the map";
      return;
    }
    const p = entity.position || {}, v = entity.linear_velocity || {};
    const speed = Math.hypot(v.x || 0, v.y || 0, v.z || 0);
    $("entity-state").textContent =
      `${entity.id} ${entity.name} (${(entity.kind || "").replace("ENTITY_KIND_", "").toLowerCase()})\n` +
      `position  ${(p.x || 0).toFixed(2)}, ${(p.y || 0).toFixed(2)}, ${(p.z || 0).toFixed(2)} m\n` +
      `heading   ${(headingOf(entity.orientation) * 180 / Math.PI).toFixed(1)}°\n` +
      `speed     ${speed.toFixed(2)} m/s (${(speed * 3.6).toFixed(1)} km/h)\n` +
      `velocity  ${(v.x || 0).toFixed(2)}, ${(v.y || 0).toFixed(2)}, ${(v.z || 0).toFixed(2)} m/s`;
  }
}
