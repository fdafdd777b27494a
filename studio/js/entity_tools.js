// Spawning entities and giving them routes from the page: "spawn on the map"
// then a click on the map adds a car (snapped to the nearest lane), a UAV
// (hovering at the height given) or a pedestrian there (Configure Spawn);
// the selected car or pedestrian gets one of the world's routes and a speed
// (SetRoute), or a new speed on its route (SetRoute.keep_route); the
// selected UAV follows an entity or holds where it is (CommandUav).

import { headingOf } from "./world_map.js";
import { option, setOptions } from "./dom.js";

const $ = (id) => document.getElementById(id);
const KIND_NAMES = { ENTITY_KIND_CAR: "car", ENTITY_KIND_UAV: "UAV", ENTITY_KIND_PEDESTRIAN: "pedestrian" };

export class EntityTools {
  constructor(app) {
    this.app = app;
    this.spawning = false;  // the next click on the map spawns
    this.lastClick = null;  // world point of the last click on the map (not a drag)
    setOptions($("spawn-kind"), Object.entries(KIND_NAMES).map(([k, n]) => option(n, k)));
    $("spawn-mode").onclick = () => this.setSpawning(!this.spawning);
    $("set-route").onclick = () => this.setRoute(false);
    $("set-speed").onclick = () => this.setRoute(true);
    $("uav-follow").onclick = () => this.uavFollow();
    $("uav-hold").onclick = () => this.uavHold();
    addEventListener("keydown", (e) => { if (e.code === "Escape" && this.spawning) this.setSpawning(false); });
    this.listen($("map"));
    this.select(null);
  }

  // Clicks on the map, after the map's own handler (which picks an entity):
  // a click is a press and release without a drag.
  listen(canvas) {
    let down = null;
    canvas.addEventListener("mousedown", (e) => { down = { x: e.offsetX, y: e.offsetY }; });
    canvas.addEventListener("mouseup", (e) => {
      if (!down || Math.abs(e.offsetX - down.x) + Math.abs(e.offsetY - down.y) > 2) { down = null; return; }
      down = null;
      this.lastClick = this.app.map.toWorld(e.offsetX, e.offsetY);
      if (this.spawning) {
        this.setSpawning(false);
        this.spawn($("spawn-kind").value, this.lastClick);
      }
    });
  }

  setSpawning(on) {
    this.spawning = on;
    $("map-box").classList.toggle("spawning", on);
    $("spawn-mode").classList.toggle("armed", on);
    $("spawn-mode").textContent = on ? "click on the map… (Esc: cancel)" : "spawn on the map";
  }

  // Spawn `kind` at world point {x, y}; selects it. Resolves with its id, or null when refused.
  async spawn(kind, point) {
    const request = { kind, position: { x: point.x, y: point.y, z: 0 }, yaw_deg: Number($("spawn-yaw").value) || 0 };
    if (kind === "ENTITY_KIND_CAR") request.snap_to_lane = true;
    if (kind === "ENTITY_KIND_UAV") request.position.z = Number($("spawn-height").value) || 10;
    const answer = await this.app.controls.run("Spawn", { spawn: request });
    if (!answer) return null;
    const id = answer.entity_id;
    let entity = (answer.world?.entities || []).find((e) => e.id === id) || { id, kind };
    try {  // its pose, for the Entity panel: the State from the frame after the Spawn
      const state = await this.app.control.getState();
      entity = (state.entities || []).find((e) => e.id === id) || entity;
    } catch (error) {
      // the control session closed; the status says so
    }
    this.app.map.selected = id;
    this.app.map.dirty = true;
    this.app.controls.select(entity);
    this.app.driving.picked(entity);
    this.app.note(`spawned ${entity.name || KIND_NAMES[kind]} (id ${id})`);
    return id;
  }

  // The world's routes and entities in the menus (the choices kept).
  setWorld(world) {
    const routes = world.routes || [];
    setOptions($("route-name"), routes.length ? routes.map((r) => option(r)) : [option("(no routes)", "")]);
    setOptions($("uav-target"), (world.entities || []).map((e) => option(`${e.id} ${e.name}`, e.id)));
    this.routes = routes;
    this.select(this.selected);
  }

  // The selected entity (refreshed with every State): which tools apply.
  select(entity) {
    this.selected = entity;
    const kind = entity?.kind;
    const walker = kind === "ENTITY_KIND_CAR" || kind === "ENTITY_KIND_PEDESTRIAN";
    $("set-route").disabled = !walker || !(this.routes || []).length;
    $("set-speed").disabled = !walker;
    $("uav-follow").disabled = $("uav-hold").disabled = kind !== "ENTITY_KIND_UAV";
    $("route-target").textContent = entity ? `${entity.id} ${entity.name || ""} (${KIND_NAMES[kind] || "?"})` : "none selected";
  }

  setRoute(keepRoute) {
    const entity = this.selected;
    if (!entity) return null;
    const request = { entity_id: entity.id, speed: Number($("route-speed").value) };
    if (keepRoute) request.keep_route = true; else request.route_name = $("route-name").value;
    return this.app.controls.run(keepRoute ? "SetRoute (speed)" : "SetRoute", { set_route: request });
  }

  uavFollow() {
    if (!this.selected) return null;
    return this.app.controls.run("CommandUav", {
      command_uav: { entity_id: this.selected.id, follow: { target_id: Number($("uav-target").value) } } });
  }

  uavHold() {
    const uav = this.selected;
    if (!uav) return null;
    const p = uav.position || {};
    return this.app.controls.run("CommandUav", { command_uav: { entity_id: uav.id, hold: {
      position: { x: p.x || 0, y: p.y || 0, z: Math.max(0.5, p.z || 0) },
      yaw_deg: (headingOf(uav.orientation) * 180) / Math.PI } } });
  }
}
