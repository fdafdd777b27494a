// The map's properties: name, tile size, surroundings, grid size (resizing
// keeps what fits). Each change is one undoable edit; the daemon's check
// judges the values (a field its error names is outlined in red).

import { resizeMap, setTileSize } from "./map_model.js";

const $ = (id) => document.getElementById(id);
const MAX_EDITABLE_SIDE = 256;  // what the page can hold; the daemon's limit is lower and its check says so

export class PropertiesPanel {
  constructor(app) {
    this.app = app;
    $("prop-name").onchange = (e) => app.edit("rename", (m) => { m.name = e.target.value.trim(); });
    $("prop-tile-size").onchange = (e) => {
      const value = Number(e.target.value);
      if (e.target.value.trim() === "" || !Number.isFinite(value) || value <= 0) { this.render(); return; }
      app.edit("tile size", (m) => setTileSize(m, value));
    };
    $("prop-surroundings").onchange = (e) => app.edit("surroundings", (m) => { m.surroundings = e.target.value; });
    $("prop-resize").onclick = () => this.resize();
    for (const id of ["prop-width", "prop-height"]) {
      $(id).addEventListener("keydown", (e) => { if (e.key === "Enter") this.resize(); });
    }
  }

  resize() {
    const width = Math.round(Number($("prop-width").value)), height = Math.round(Number($("prop-height").value));
    const ok = (n) => Number.isFinite(n) && n >= 1 && n <= MAX_EDITABLE_SIDE;
    if (!ok(width) || !ok(height)) {
      this.app.note(`a grid is 1..${MAX_EDITABLE_SIDE} tiles each way here`, true);
      this.render();
      return;
    }
    const m = this.app.model;
    if (width === m.width && height === m.height) return;
    this.app.edit("resize", (model) => resizeMap(model, width, height));
  }

  render() {
    const m = this.app.model, problem = this.app.problem;
    const show = (id, value) => { if (document.activeElement !== $(id)) $(id).value = value; };
    show("prop-name", m.name);
    show("prop-tile-size", String(m.tileSize));
    show("prop-surroundings", m.surroundings);
    show("prop-width", String(m.width));
    show("prop-height", String(m.height));
    const bad = { name: "prop-name", tile_size: "prop-tile-size", surroundings: "prop-surroundings", grid: "prop-width" };
    for (const [what, id] of Object.entries(bad)) {
      $(id).classList.toggle("bad", problem?.what === what);
      if (what === "grid") $("prop-height").classList.toggle("bad", problem?.what === what);
    }
    $("prop-comments").textContent = m.comments.join("\n");
    $("prop-comments").hidden = !m.comments.length;
  }
}
