// The 2D map: the loaded map's roads, objects and routes (from its text),
// every entity's live position and heading (GetState), with trails. Drag to
// pan, wheel to zoom, click an entity to select it.

import { OBJECT_SHAPES, parseMap, tileCentre } from "./map_text.js";

const TRAIL_POINTS = 400;
const KIND_COLOURS = { ENTITY_KIND_CAR: "#4fc3f7", ENTITY_KIND_UAV: "#ffb74d", ENTITY_KIND_PEDESTRIAN: "#f06292" };
const OBJECT_COLOURS = { house: "#9e9e9e", tree: "#388e3c", lantern: "#fdd835", park: "#7cb342", obstacle: "#e57373" };
const ROUTE_COLOURS = ["#ff7043", "#ab47bc", "#26a69a", "#ffca28", "#5c6bc0", "#ec407a"];

// Heading (radians counter-clockwise from east) of a quaternion's x axis.
export function headingOf(q) {
  const w = q?.w ?? 1, x = q?.x ?? 0, y = q?.y ?? 0, z = q?.z ?? 0;
  return Math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z));
}

export class WorldMap {
  constructor(canvas, onSelect) {
    this.canvas = canvas;
    this.onSelect = onSelect;
    this.map = null;
    this.entities = [];
    this.trails = new Map();  // id -> [{x, y}]
    this.selected = null;
    this.view = { cx: 0, cy: 0, scale: 2 };  // pixels per metre
    this.fitted = false;
    this.showRoutes = true;
    this.dirty = true;
    this.listen();
    const frame = () => { if (this.dirty) this.draw(); requestAnimationFrame(frame); };
    requestAnimationFrame(frame);
  }

  setMapText(text) {
    this.map = text ? parseMap(text) : null;
    this.trails.clear();
    this.fitted = false;
    this.dirty = true;
  }

  setState(state) {
    this.entities = state.entities || [];
    for (const entity of this.entities) {
      const trail = this.trails.get(entity.id) || [];
      const p = entity.position || {};
      const last = trail[trail.length - 1];
      if (!last || Math.hypot(last.x - (p.x || 0), last.y - (p.y || 0)) > 0.2) trail.push({ x: p.x || 0, y: p.y || 0 });
      if (trail.length > TRAIL_POINTS) trail.shift();
      this.trails.set(entity.id, trail);
    }
    for (const id of this.trails.keys()) {
      if (!this.entities.some((e) => e.id === id)) this.trails.delete(id);
    }
    if (!this.fitted) this.fit();
    this.dirty = true;
  }

  fit() {
    const size = this.resize();
    let half = { x: 50, y: 50 };
    if (this.map) half = { x: (this.map.width * this.map.tileSize) / 2, y: (this.map.height * this.map.tileSize) / 2 };
    else if (this.entities.length) {
      const far = Math.max(30, ...this.entities.map((e) => Math.max(Math.abs(e.position?.x || 0), Math.abs(e.position?.y || 0))));
      half = { x: far * 1.2, y: far * 1.2 };
    }
    this.view = { cx: 0, cy: 0, scale: Math.min(size.width / (2 * half.x), size.height / (2 * half.y)) * 0.95 };
    this.fitted = true;
  }

  resize() {
    const rect = this.canvas.getBoundingClientRect();
    const width = Math.max(100, Math.round(rect.width)), height = Math.max(100, Math.round(rect.height));
    if (this.canvas.width !== width || this.canvas.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
    }
    return { width, height };
  }

  toScreen(x, y) {
    return [this.canvas.width / 2 + (x - this.view.cx) * this.view.scale,
            this.canvas.height / 2 - (y - this.view.cy) * this.view.scale];
  }

  toWorld(px, py) {
    return { x: this.view.cx + (px - this.canvas.width / 2) / this.view.scale,
             y: this.view.cy - (py - this.canvas.height / 2) / this.view.scale };
  }

  // Screen position of entity `id`, for tests and tooltips.
  entityOnScreen(id) {
    const entity = this.entities.find((e) => e.id === id);
    return entity ? this.toScreen(entity.position?.x || 0, entity.position?.y || 0) : null;
  }

  listen() {
    let drag = null;
    this.canvas.addEventListener("mousedown", (e) => { drag = { x: e.offsetX, y: e.offsetY, moved: false }; });
    this.canvas.addEventListener("mousemove", (e) => {
      if (!drag) return;
      const dx = e.offsetX - drag.x, dy = e.offsetY - drag.y;
      if (Math.abs(dx) + Math.abs(dy) > 2) drag.moved = true;
      this.view.cx -= dx / this.view.scale;
      this.view.cy += dy / this.view.scale;
      drag.x = e.offsetX;
      drag.y = e.offsetY;
      this.dirty = true;
    });
    this.canvas.addEventListener("mouseup", (e) => {
      if (drag && !drag.moved) this.pick(e.offsetX, e.offsetY);
      drag = null;
    });
    this.canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      const before = this.toWorld(e.offsetX, e.offsetY);
      this.view.scale *= e.deltaY < 0 ? 1.2 : 1 / 1.2;
      const after = this.toWorld(e.offsetX, e.offsetY);
      this.view.cx += before.x - after.x;
      this.view.cy += before.y - after.y;
      this.dirty = true;
    }, { passive: false });
    new ResizeObserver(() => { this.dirty = true; }).observe(this.canvas);
  }

  pick(px, py) {
    let best = null, bestDistance = 12;
    for (const entity of this.entities) {
      const [sx, sy] = this.toScreen(entity.position?.x || 0, entity.position?.y || 0);
      const d = Math.hypot(sx - px, sy - py);
      if (d < bestDistance) { best = entity; bestDistance = d; }
    }
    this.selected = best ? best.id : null;
    this.dirty = true;
    this.onSelect(best);
  }

  draw() {
    this.dirty = false;
    this.resize();
    const g = this.canvas.getContext("2d");
    g.fillStyle = this.map?.surroundings === "urban" ? "#2e3b2e" : "#3b352a";
    g.fillRect(0, 0, this.canvas.width, this.canvas.height);
    if (this.map) {
      this.drawRoads(g);
      this.drawObjects(g);
      if (this.showRoutes) this.drawRoutes(g);
    } else {
      g.fillStyle = "#aaa";
      g.font = "12px sans-serif";
      g.fillText("no tile map loaded (a scene file): entities only", 10, 20);
    }
    this.drawEntities(g);
  }

  drawRoads(g) {
    const map = this.map, t = map.tileSize, s = this.view.scale;
    g.strokeStyle = "#5f5f5f";
    g.lineWidth = 8 * s;  // two 4 m lanes
    g.lineCap = "butt";
    for (let row = 0; row < map.height; ++row) {
      for (let col = 0; col < map.width; ++col) {
        const mask = map.masks[row * map.width + col];
        if (!mask) continue;
        const c = tileCentre(map, col, row);
        const sides = [[1, 0, 1], [2, 1, 0], [4, 0, -1], [8, -1, 0]].filter(([bit]) => mask & bit);
        g.beginPath();
        if (sides.length === 2 && sides[0][1] !== -sides[1][1]) {
          // A curve: a quarter circle of radius T/2 about the corner between its two sides.
          const corner = { x: c.x + (sides[0][1] + sides[1][1]) * t / 2, y: c.y + (sides[0][2] + sides[1][2]) * t / 2 };
          const [cx, cy] = this.toScreen(corner.x, corner.y);
          const [a0, a1] = sides.map(([, dx, dy]) => {
            const [sx, sy] = this.toScreen(c.x + dx * t / 2, c.y + dy * t / 2);
            return Math.atan2(sy - cy, sx - cx);
          });
          let delta = a1 - a0;
          while (delta > Math.PI) delta -= 2 * Math.PI;
          while (delta <= -Math.PI) delta += 2 * Math.PI;
          g.arc(cx, cy, (t / 2) * s, a0, a1, delta < 0);
        } else {
          for (const [, dx, dy] of sides) {
            g.moveTo(...this.toScreen(c.x, c.y));
            g.lineTo(...this.toScreen(c.x + dx * t / 2, c.y + dy * t / 2));
          }
          if (sides.length > 2) {  // a junction's square
            g.stroke();
            const [x0, y0] = this.toScreen(c.x - 4, c.y + 4);
            g.fillStyle = "#5f5f5f";
            g.fillRect(x0, y0, 8 * s, 8 * s);
            continue;
          }
        }
        g.stroke();
      }
    }
  }

  drawObjects(g) {
    const s = this.view.scale;
    for (const object of this.map.objects) {
      const [hx, hy] = OBJECT_SHAPES[object.kind] || [0.5, 0.5];
      const [px, py] = this.toScreen(object.x, object.y);
      g.save();
      g.translate(px, py);
      g.rotate(-object.rotationDeg * Math.PI / 180);
      g.fillStyle = OBJECT_COLOURS[object.kind] || "#999";
      if (object.kind === "tree") {
        g.beginPath();
        g.arc(0, 0, Math.max(2, 3.5 * s), 0, 2 * Math.PI);
        g.fill();
      } else {
        g.fillRect(-hx * s, -hy * s, Math.max(2, 2 * hx * s), Math.max(2, 2 * hy * s));
      }
      g.restore();
    }
  }

  drawRoutes(g) {
    this.map.routes.forEach((route, i) => {
      g.strokeStyle = ROUTE_COLOURS[i % ROUTE_COLOURS.length];
      g.lineWidth = 1.5;
      g.setLineDash([6, 4]);
      g.beginPath();
      route.tiles.forEach((tile, k) => {
        const c = tileCentre(this.map, tile.col, tile.row);
        const [x, y] = this.toScreen(c.x, c.y);
        if (k === 0) g.moveTo(x, y); else g.lineTo(x, y);
      });
      if (route.closed) g.closePath();
      g.stroke();
      g.setLineDash([]);
    });
  }

  drawEntities(g) {
    for (const [id, trail] of this.trails) {
      const entity = this.entities.find((e) => e.id === id);
      g.strokeStyle = (KIND_COLOURS[entity?.kind] || "#fff") + "88";
      g.lineWidth = 1.5;
      g.beginPath();
      trail.forEach((p, k) => { const [x, y] = this.toScreen(p.x, p.y); if (k) g.lineTo(x, y); else g.moveTo(x, y); });
      g.stroke();
    }
    g.font = "11px sans-serif";
    for (const entity of this.entities) {
      const [x, y] = this.toScreen(entity.position?.x || 0, entity.position?.y || 0);
      const heading = headingOf(entity.orientation);
      const colour = KIND_COLOURS[entity.kind] || "#fff";
      g.save();
      g.translate(x, y);
      g.rotate(-heading);
      g.fillStyle = colour;
      g.strokeStyle = entity.id === this.selected ? "#ffffff" : "#000000";
      g.lineWidth = entity.id === this.selected ? 2.5 : 1;
      g.beginPath();
      if (entity.kind === "ENTITY_KIND_UAV") {
        g.arc(0, 0, 6, 0, 2 * Math.PI);
        g.moveTo(0, 0);
        g.lineTo(11, 0);
      } else {
        g.moveTo(10, 0);
        g.lineTo(-6, 6);
        g.lineTo(-6, -6);
        g.closePath();
      }
      g.fill();
      g.stroke();
      g.restore();
      // Labels stack by id, so entities on top of each other (a UAV over its car) stay readable.
      g.fillStyle = "#fff";
      g.fillText(`${entity.id} ${entity.name || ""}`, x + 9, y - 8 - 12 * (this.entities.indexOf(entity) % 3));
    }
  }
}
