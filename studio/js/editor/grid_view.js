// The grid: the map drawn tile by tile (roads, objects to scale, routes as
// arrows), what the daemon's check names outlined in red, and the pointer
// on it: paint tiles with the tool, erase, place objects, select and drag
// objects, click route tiles in order. Every change goes through the app
// (beginStroke / endStroke: one stroke is one undo step).

import { connectionMasks, OBJECT_SHAPES } from "../map_text.js";
import { GROUND, ROUTE_COLOURS, drawObject, drawRoadTile, drawRoute } from "./drawing.js";
import { explicitMask, round2, setTile } from "./map_model.js";

const MIN_CELL = 6, MAX_CELL = 128;
const BAD = "#ff1744";

// The tiles from `from` to `to` (both included), each a 4-neighbour of the
// last: a fast pointer skipping tiles still paints a connected road.
function* walk(from, to) {
  let { col, row } = from;
  yield { col, row };
  while (col !== to.col || row !== to.row) {
    const dc = to.col - col, dr = to.row - row;
    if (Math.abs(dc) >= Math.abs(dr)) col += Math.sign(dc); else row += Math.sign(dr);
    yield { col, row };
  }
}

export class GridView {
  constructor(app, canvas, box) {
    this.app = app;
    this.canvas = canvas;
    this.box = box;  // the scrolling container the grid fits
    this.cell = 32;
    this.drag = null;
    this.hover = null;
    this.dirty = true;
    this.listen();
    new ResizeObserver(() => { this.dirty = true; }).observe(box);
    const frame = () => { if (this.dirty) this.draw(); requestAnimationFrame(frame); };
    requestAnimationFrame(frame);
  }

  get model() { return this.app.model; }

  // Pixel centre of a tile, world point -> pixels and back (row 0 north).
  tileCentrePx(col, row) { return [(col + 0.5) * this.cell, (row + 0.5) * this.cell]; }
  toPx(x, y) {
    const m = this.model;
    return [(x / m.tileSize + m.width / 2) * this.cell, (m.height / 2 - y / m.tileSize) * this.cell];
  }
  toWorld(px, py) {
    const m = this.model;
    return { x: (px / this.cell - m.width / 2) * m.tileSize, y: (m.height / 2 - py / this.cell) * m.tileSize };
  }
  cellAt(px, py) {
    const col = Math.floor(px / this.cell), row = Math.floor(py / this.cell);
    return col >= 0 && row >= 0 && col < this.model.width && row < this.model.height ? { col, row } : null;
  }
  // Client (page) coordinates -> canvas pixels; null when outside the canvas.
  fromClient(clientX, clientY) {
    const rect = this.canvas.getBoundingClientRect();
    const px = clientX - rect.left, py = clientY - rect.top;
    return px >= 0 && py >= 0 && px < rect.width && py < rect.height ? [px, py] : null;
  }
  // Page coordinates of a tile's centre (tests drive the mouse with these).
  tileOnPage(col, row) {
    const rect = this.canvas.getBoundingClientRect();
    const [px, py] = this.tileCentrePx(col, row);
    return [rect.left + px, rect.top + py];
  }
  pixelsPerMetre() { return this.cell / this.model.tileSize; }

  layout() {
    const m = this.model;
    const fit = Math.floor(Math.min((this.box.clientWidth - 4) / m.width, (this.box.clientHeight - 4) / m.height));
    this.cell = Math.max(MIN_CELL, Math.min(MAX_CELL, fit || MIN_CELL));
    const width = m.width * this.cell, height = m.height * this.cell;
    if (this.canvas.width !== width || this.canvas.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
      this.canvas.style.width = `${width}px`;
      this.canvas.style.height = `${height}px`;
    }
  }

  // The object under a pixel (the last drawn first), or -1.
  objectAt(px, py) {
    const objects = this.model.objects, scale = this.pixelsPerMetre();
    for (let i = objects.length - 1; i >= 0; --i) {
      const o = objects[i];
      const [hx, hy] = OBJECT_SHAPES[o.kind] || [0.5, 0.5];
      const [ox, oy] = this.toPx(o.x, o.y);
      const a = o.rot * Math.PI / 180, dx = px - ox, dy = oy - py;  // dy: north up
      const u = dx * Math.cos(a) + dy * Math.sin(a), v = -dx * Math.sin(a) + dy * Math.cos(a);
      const slack = 4;
      if (Math.abs(u) <= Math.max(hx * scale, 3) + slack && Math.abs(v) <= Math.max(hy * scale, 3) + slack) return i;
    }
    return -1;
  }

  listen() {
    const c = this.canvas;
    c.addEventListener("pointerdown", (e) => this.pressed(e));
    c.addEventListener("pointermove", (e) => this.moved(e));
    c.addEventListener("pointerup", (e) => this.released(e));
    c.addEventListener("pointercancel", (e) => this.released(e));
    c.addEventListener("pointerleave", () => { this.hover = null; this.app.showHover(null); });
  }

  pressed(e) {
    if (e.button !== 0) return;
    e.preventDefault();
    this.canvas.setPointerCapture(e.pointerId);
    const px = e.offsetX, py = e.offsetY, cell = this.cellAt(px, py);
    const tool = this.app.tool, app = this.app;
    if (tool.type === "select") {
      const index = this.objectAt(px, py);
      if (index >= 0) {
        app.select({ object: index });
        const o = this.model.objects[index];
        app.beginStroke("move object");
        this.drag = { kind: "move", index, start: this.toWorld(px, py), from: { x: o.x, y: o.y } };
      } else {
        app.select(cell ? { tile: cell } : {});
      }
    } else if (tool.type === "tile" || tool.type === "erase") {
      app.beginStroke(tool.type === "tile" ? "paint" : "erase");
      this.drag = { kind: "paint", last: null };
      this.paintTo(px, py);
    } else if (tool.type === "object") {
      if (!cell) return;
      app.beginStroke(`add ${tool.kind}`);
      const at = this.toWorld(px, py);
      this.model.objects.push({ kind: tool.kind, x: round2(at.x), y: round2(at.y), rot: 0 });
      const index = this.model.objects.length - 1;
      app.select({ object: index });
      this.drag = { kind: "move", index, start: at, from: { x: round2(at.x), y: round2(at.y) } };
      app.changed();
    } else if (tool.type === "route") {
      if (app.routeIndex === null) { app.note("add a route or pick one in the list first", true); return; }
      app.beginStroke("route tiles");
      this.drag = { kind: "route", last: null };
      this.appendRouteTile(cell);
    }
  }

  moved(e) {
    const px = e.offsetX, py = e.offsetY, cell = this.cellAt(px, py);
    if (!this.hover || !cell || this.hover.col !== cell?.col || this.hover.row !== cell?.row) {
      this.hover = cell;
      this.app.showHover(cell, this.toWorld(px, py));
    }
    const drag = this.drag;
    if (!drag) return;
    if (drag.kind === "move") {
      const at = this.toWorld(px, py), o = this.model.objects[drag.index];
      if (!o) return;
      o.x = round2(drag.from.x + at.x - drag.start.x);
      o.y = round2(drag.from.y + at.y - drag.start.y);
      this.app.changed();
    } else if (drag.kind === "paint") {
      this.paintTo(px, py);
    } else if (drag.kind === "route") {
      this.appendRouteTile(cell);
    }
  }

  released() {
    if (!this.drag) return;
    this.drag = null;
    this.app.endStroke();
  }

  // Paints (or erases) every tile from the last one to the one under (px, py).
  paintTo(px, py) {
    const cell = this.cellAt(px, py), drag = this.drag;
    if (this.app.tool.type === "erase") {
      const index = this.objectAt(px, py);
      if (index >= 0) this.app.removeObject(index);
    }
    if (!cell) return;
    for (const { col, row } of walk(drag.last || cell, cell)) this.paintCell(col, row);
    drag.last = cell;
  }

  paintCell(col, row) {
    const tool = this.app.tool;
    const char = tool.type === "erase" ? "." : tool.char;
    if (setTile(this.model, col, row, char)) this.app.changed();
    this.app.select(tool.type === "tile" ? { tile: { col, row } } : {});
  }

  // Appends the tile under the pointer (and, dragging, those passed on the
  // way) to the picked route; a tile is not appended twice in a row.
  appendRouteTile(cell) {
    const route = this.model.routes[this.app.routeIndex];
    if (!cell || !route) return;
    for (const { col, row } of walk(this.drag.last || cell, cell)) {
      const last = route.tiles[route.tiles.length - 1];
      if (last && last[0] === col && last[1] === row) continue;
      route.tiles.push([col, row]);
      this.app.changed();
    }
    this.drag.last = cell;
  }

  // Drops a palette item at page coordinates; true if it landed on the grid.
  drop(item, clientX, clientY) {
    const at = this.fromClient(clientX, clientY);
    const cell = at && this.cellAt(...at);
    if (!cell) return false;
    const app = this.app;
    if (item.type === "tile" || item.type === "erase") {
      const road = item.type === "tile";
      app.edit(road ? "place road" : "clear tile", (m) => setTile(m, cell.col, cell.row, road ? item.char : "."));
      app.select(road ? { tile: cell } : {});
    } else if (item.type === "object") {
      const w = this.toWorld(...at);
      app.edit(`add ${item.kind}`, (m) => m.objects.push({ kind: item.kind, x: round2(w.x), y: round2(w.y), rot: 0 }));
      app.select({ object: this.model.objects.length - 1 });
    }
    return true;
  }

  draw() {
    this.dirty = false;
    if (!this.model) return;
    this.layout();
    const g = this.canvas.getContext("2d"), m = this.model, s = this.cell;
    g.fillStyle = GROUND[m.surroundings] || "#444";
    g.fillRect(0, 0, this.canvas.width, this.canvas.height);
    g.strokeStyle = "#ffffff14";
    g.lineWidth = 1;
    g.beginPath();
    for (let c = 0; c <= m.width; ++c) { g.moveTo(c * s + 0.5, 0); g.lineTo(c * s + 0.5, m.height * s); }
    for (let r = 0; r <= m.height; ++r) { g.moveTo(0, r * s + 0.5); g.lineTo(m.width * s, r * s + 0.5); }
    g.stroke();
    const masks = connectionMasks(m), road = 8 * this.pixelsPerMetre();
    for (let r = 0; r < m.height; ++r) {
      for (let c = 0; c < m.width; ++c) {
        const char = m.rows[r][c];
        if (char === ".") continue;
        const mask = masks[r * m.width + c];
        drawRoadTile(g, c * s, r * s, s, mask, explicitMask(char) ?? mask, char, road);
      }
    }
    const scale = this.pixelsPerMetre(), check = this.app.problem;
    m.objects.forEach((o, i) => {
      const outline = check?.object === i ? BAD : this.app.selection.object === i ? "#ffffff" : null;
      drawObject(g, o.kind, ...this.toPx(o.x, o.y), o.rot, scale, outline);
    });
    m.routes.forEach((route, i) => {
      const selected = i === this.app.routeIndex;
      const colour = check?.route === i ? BAD : ROUTE_COLOURS[i % ROUTE_COLOURS.length];
      drawRoute(g, route.tiles.map(([c, r]) => this.tileCentrePx(c, r)), route.closed,
                selected ? colour : `${colour}99`, selected ? Math.max(2, s * 0.09) : 1.5);
    });
    this.drawMarks(g);
  }

  // The selected tile, and what the daemon's error names (a row, tiles).
  drawMarks(g) {
    const s = this.cell, tile = this.app.selection.tile, check = this.app.problem;
    if (tile) {
      g.strokeStyle = "#ffffff";
      g.lineWidth = 2;
      g.strokeRect(tile.col * s + 1, tile.row * s + 1, s - 2, s - 2);
    }
    if (!check) return;
    g.strokeStyle = BAD;
    g.lineWidth = 2;
    if (check.row !== undefined && check.row !== null) g.strokeRect(1, check.row * s + 1, this.model.width * s - 2, s - 2);
    g.lineWidth = 3;
    for (const t of check.tiles || []) g.strokeRect(t.col * s + 2, t.row * s + 2, s - 4, s - 4);
  }
}
