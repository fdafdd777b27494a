// The studio's map editor (editor.html): the map being edited, its undo
// history, the tool, the selection, and every panel. window.editor is this
// app, for the browser tests and the console.
//
// Every change goes through edit() (one step) or beginStroke()/endStroke()
// (a drag: one step however many tiles it paints), which records undo and
// asks the daemon to check the new text.

import { StudioSocket } from "../protocol.js";
import { History } from "./history.js";
import { blankMap, cloneMap, explicitMask, parseMapText, rotateChar, serializeMap, setTile } from "./map_model.js";
import { Palette } from "./palette.js";
import { GridView } from "./grid_view.js";
import { RoutePanel } from "./routes.js";
import { PropertiesPanel } from "./properties.js";
import { Validator } from "./validation.js";
import { Actions } from "./actions.js";
import { Preview } from "./preview.js";
import { bindKeys } from "./keys.js";

const $ = (id) => document.getElementById(id);
const MAX_MESSAGES = 30;

class EditorApp {
  constructor() {
    this.model = blankMap();
    this.history = new History();
    this.selection = {};  // {object: index} or {tile: {col, row}} or {}
    this.routeIndex = null;  // the route the route tool appends to
    this.problem = null;  // what the daemon's latest check names
    this.errors = [];  // every refusal shown, for the tests: {where, code, message}
    this.stroke = null;
    this.saved = null;
    this.ready = false;
  }

  async start() {
    this.palette = new Palette($("palette"), (item) => this.pickTool(item), (item, x, y) => this.grid.drop(item, x, y));
    this.grid = new GridView(this, $("grid"), $("grid-box"));
    this.routes = new RoutePanel(this);
    this.properties = new PropertiesPanel(this);
    this.validator = new Validator(this);
    this.actions = new Actions(this);
    this.preview = new Preview(this);
    bindKeys(this);
    $("undo").onclick = () => this.undo();
    $("redo").onclick = () => this.redo();
    $("rotate").onclick = () => this.rotate();
    $("delete").onclick = () => this.deleteSelection();
    $("new-map").onclick = () => this.edit("new map", (m) => Object.assign(m, blankMap(m.width, m.height)));
    this.pickTool(this.palette.item("road"));
    this.socket = new StudioSocket("studio-editor");
    this.socket.onError = (error) => this.reportError(error, "daemon");
    this.socket.onClose = (reason) => this.note(`disconnected: ${reason}; reload the page`, true);
    try {
      await this.socket.open();
      await this.actions.listMaps();
      const world = await this.configure({ get_world: { with_map_text: true } });
      if (world.map_text) this.model = parseMapText(world.map_text);
    } catch (error) {
      this.reportError(error, "connecting");
    }
    this.changed();
    this.ready = true;
  }

  // A Configure request to the daemon; refused at once when the page is not
  // (or no longer) connected, rather than waiting for an answer that never comes.
  configure(request) {
    const socket = this.socket;
    if (!socket || socket.closed || socket.ws?.readyState !== WebSocket.OPEN) {
      return Promise.reject(new Error("not connected to the daemon; reload the page"));
    }
    return socket.configure(request);
  }

  // --- the map --------------------------------------------------------------

  text() { return serializeMap(this.model); }

  // One undoable edit: fn(model) changes the map in place.
  edit(label, fn) {
    const before = cloneMap(this.model), textBefore = this.text();
    fn(this.model);
    if (this.text() === textBefore) return false;
    this.history.push(before, label);
    this.changed();
    return true;
  }

  beginStroke(label) {
    this.endStroke();
    this.stroke = { label, before: cloneMap(this.model), text: this.text() };
  }

  endStroke() {
    const stroke = this.stroke;
    this.stroke = null;
    if (stroke && this.text() !== stroke.text) this.history.push(stroke.before, stroke.label);
    this.renderPanels();
  }

  // Replaces the whole map with `text` (Open, Generate, Dress) as one edit;
  // text this page cannot read is shown as an error and changes nothing.
  loadText(text, label) {
    let model;
    try {
      model = parseMapText(text);
    } catch (error) {
      this.reportError(error, label);
      return false;
    }
    this.edit(label, (m) => { for (const key of Object.keys(m)) delete m[key]; Object.assign(m, model); });
    this.select({});
    this.pickRoute(null);
    return true;
  }

  undo() { this.restore(this.history.undo(cloneMap(this.model)), "undid"); }
  redo() { this.restore(this.history.redo(cloneMap(this.model)), "redid"); }

  restore(entry, verb) {
    if (!entry) return;
    this.model = entry.model;
    this.select({});
    if (this.routeIndex !== null && this.routeIndex >= this.model.routes.length) this.routeIndex = null;
    this.note(`${verb} ${entry.label}`);
    this.changed();
  }

  // After every change: redraw, and ask the daemon (debounced).
  changed() {
    this.render();
    this.validator.schedule();
  }

  render() {
    this.grid.dirty = true;
    if (!this.stroke) this.renderPanels();
  }

  renderPanels() {
    this.properties.render();
    this.routes.render();
    this.actions.render();
    this.palette.setSurroundings(this.model.surroundings);
    $("undo").disabled = !this.history.canUndo();
    $("redo").disabled = !this.history.canRedo();
    const object = this.model.objects[this.selection.object], tile = this.selection.tile;
    $("selection").textContent = object
      ? `${object.kind} at ${object.x.toFixed(2)}, ${object.y.toFixed(2)} m, turned ${object.rot.toFixed(0)}°`
      : tile ? `tile ${tile.col},${tile.row} '${this.tileChar(tile)}'` : "";
  }

  tileChar(tile) { return this.model.rows[tile.row]?.[tile.col] ?? ""; }

  // --- tools and selection ----------------------------------------------------

  pickTool(item) {
    this.tool = item;
    this.palette.showActive(item.id);
    $("grid").dataset.tool = item.type;
    if (item.type !== "select") this.select({});
  }

  pickRoute(index) {
    this.routeIndex = index;
    if (index !== null) this.pickTool(this.palette.item("route"));
    this.render();
  }

  select(selection) {
    this.selection = selection;
    this.grid.dirty = true;
    if (!this.stroke) this.renderPanels();
  }

  removeObject(index) {
    this.model.objects.splice(index, 1);
    if (this.selection.object === index) this.selection = {};
    this.changed();
  }

  // r: the selected object 15 degrees clockwise, else the selected explicit
  // road piece a quarter clockwise, else the palette's piece.
  rotate(clockwise = true) {
    const object = this.selection.object, tile = this.selection.tile;
    if (this.model.objects[object]) {
      this.edit("turn object", (m) => {
        const rot = m.objects[object].rot + (clockwise ? -15 : 15);
        m.objects[object].rot = ((rot % 360) + 360) % 360;
      });
      return true;
    }
    const turn = (char) => {
      let out = char;
      for (let k = 0; k < (clockwise ? 1 : 3); ++k) out = rotateChar(out);
      return out;
    };
    if (tile && explicitMask(this.tileChar(tile)) !== null) {
      return this.edit("turn road piece", (m) => setTile(m, tile.col, tile.row, turn(this.tileChar(tile))));
    }
    if (this.tool.type === "tile" && explicitMask(this.tool.char) !== null) {
      this.palette.setChar(this.tool.id, turn(this.tool.char));
      return true;
    }
    this.note("select an object or an explicit road piece to turn ('#' tiles connect by themselves)");
    return false;
  }

  deleteSelection() {
    const object = this.selection.object, tile = this.selection.tile;
    if (this.model.objects[object]) {
      this.edit("delete object", (m) => m.objects.splice(object, 1));
      this.select({});
    } else if (tile) {
      this.edit("clear tile", (m) => setTile(m, tile.col, tile.row, "."));
    }
  }

  showHover(cell, world) {
    $("hover").textContent = cell ? `tile ${cell.col},${cell.row} · x ${world.x.toFixed(1)} y ${world.y.toFixed(1)} m` : "";
  }

  // --- messages ----------------------------------------------------------------

  note(text, bad = false) {
    $("message").textContent = text;
    $("message").className = bad ? "bad" : "";
  }

  reportError(error, where) {
    if (error.aborted) return;
    const entry = { where, code: error.code || "", message: error.message || String(error) };
    this.errors.push(entry);
    const item = document.createElement("li");
    const code = entry.code ? `${entry.code.replace("ERROR_CODE_", "")} · ` : "";
    item.textContent = `${new Date().toLocaleTimeString()} ${where}: ${code}${entry.message}`;
    $("messages").prepend(item);
    while ($("messages").children.length > MAX_MESSAGES) $("messages").lastChild.remove();
    this.note(`${where}: ${entry.message}`, true);
  }
}

window.editor = new EditorApp();
window.editor.start();
