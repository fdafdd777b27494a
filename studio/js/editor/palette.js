// The palette: the tools and what can be placed (the map format's road
// pieces, empty, the object kinds). A click picks an item as the tool that
// clicks and drags on the grid use; pressing on an item and letting go over
// the grid places it there (pointer events, not HTML drag and drop, so the
// DevTools protocol's mouse events drive it like a person's).

import { GROUND, drawObject, drawRoadTile } from "./drawing.js";
import { OBJECT_KINDS } from "./map_model.js";

// type: select | tile | erase | object | route. A tile item's `char` is '#'
// (connects itself) or an explicit mask's hex digit (N 1, E 2, S 4, W 8).
export const PALETTE_ITEMS = [
  { id: "select", type: "select", label: "select / move",
    title: "click an object to select it, drag to move it; click a tile to select it (r turns it, Delete clears it)" },
  { id: "road", type: "tile", char: "#", label: "road #", title: "road that connects to every road neighbour" },
  { id: "dead-end", type: "tile", char: "1", label: "dead end", title: "explicit piece: one side (r turns it)" },
  { id: "straight", type: "tile", char: "5", label: "straight", title: "explicit piece: two opposite sides (r turns it)" },
  { id: "curve", type: "tile", char: "3", label: "curve", title: "explicit piece: two adjacent sides (r turns it)" },
  { id: "junction", type: "tile", char: "7", label: "T-junction", title: "explicit piece: three sides (r turns it)" },
  { id: "crossroads", type: "tile", char: "f", label: "crossroads", title: "explicit piece: four sides" },
  { id: "erase", type: "erase", label: "empty / erase", title: "clears tiles and removes the objects it touches" },
  ...OBJECT_KINDS.map((kind) => ({ id: kind, type: "object", kind, label: kind, title: `place a ${kind}` })),
  { id: "route", type: "route", label: "route tiles",
    title: "click tiles in driving order to append them to the selected route (Backspace removes the last)" },
];

const ICON = 30;
const DRAG_START_PX = 4;

export class Palette {
  // onPick(item): chosen as the tool; onDrop(item, clientX, clientY): let go
  // after a drag (the app decides whether that is over the grid).
  constructor(parent, onPick, onDrop) {
    this.parent = parent;
    this.onPick = onPick;
    this.onDrop = onDrop;
    this.items = PALETTE_ITEMS.map((item) => ({ ...item }));
    this.elements = new Map();
    this.drag = null;
    this.ghost = document.createElement("div");
    this.ghost.className = "palette-ghost";
    this.ghost.hidden = true;
    document.body.appendChild(this.ghost);
    for (const item of this.items) this.build(item);
  }

  item(id) {
    return this.items.find((i) => i.id === id) || null;
  }

  build(item) {
    const element = document.createElement("div");
    element.className = "palette-item";
    element.dataset.id = item.id;
    element.title = item.title;
    const icon = document.createElement("canvas");
    icon.width = icon.height = ICON;
    element.append(icon, Object.assign(document.createElement("span"), { textContent: item.label }));
    element.addEventListener("pointerdown", (e) => this.pressed(item, e));
    this.parent.appendChild(element);
    this.elements.set(item.id, element);
    this.drawIcon(item);
  }

  drawIcon(item, surroundings = "desert") {
    const g = this.elements.get(item.id).querySelector("canvas").getContext("2d");
    g.clearRect(0, 0, ICON, ICON);
    g.fillStyle = GROUND[surroundings] || GROUND.desert;
    g.fillRect(0, 0, ICON, ICON);
    if (item.type === "tile") {
      const mask = item.char === "#" ? 15 : parseInt(item.char, 16);
      drawRoadTile(g, 0, 0, ICON, mask, mask, null);
      if (item.char === "#") {
        g.fillStyle = "#fff";
        g.font = "bold 11px monospace";
        g.fillText("#", 2, 10);
      }
    } else if (item.type === "object") {
      const scale = { house: 2.2, tree: 3, lantern: 12, park: 1.5, obstacle: 8 }[item.kind];
      drawObject(g, item.kind, ICON / 2, ICON / 2, 0, scale);
    } else {
      g.strokeStyle = "#ddd";
      g.fillStyle = "#ddd";
      g.lineWidth = 2;
      g.beginPath();
      if (item.type === "select") {  // an arrow pointer
        g.moveTo(9, 6); g.lineTo(9, 24); g.lineTo(14, 19); g.lineTo(19, 26); g.lineTo(21, 24); g.lineTo(17, 18); g.lineTo(23, 18);
        g.closePath(); g.fill();
      } else if (item.type === "erase") {  // a cross
        g.moveTo(8, 8); g.lineTo(22, 22); g.moveTo(22, 8); g.lineTo(8, 22); g.stroke();
      } else {  // route: a path with an arrow
        g.moveTo(5, 24); g.lineTo(15, 24); g.lineTo(15, 8); g.lineTo(24, 8); g.stroke();
        g.beginPath(); g.moveTo(27, 8); g.lineTo(21, 4); g.lineTo(21, 12); g.closePath(); g.fill();
      }
    }
  }

  // The explicit piece of a tile item turned (the `r` key with no selection).
  setChar(id, char) {
    const item = this.item(id);
    item.char = char;
    this.drawIcon(item, this.surroundings);
  }

  setSurroundings(surroundings) {
    if (surroundings === this.surroundings) return;
    this.surroundings = surroundings;
    for (const item of this.items) this.drawIcon(item, surroundings);
  }

  showActive(id) {
    for (const [itemId, element] of this.elements) element.classList.toggle("active", itemId === id);
  }

  pressed(item, event) {
    if (event.button !== 0) return;
    event.preventDefault();
    const drag = { item, x0: event.clientX, y0: event.clientY, moved: false };
    const move = (e) => {
      if (!drag.moved && Math.hypot(e.clientX - drag.x0, e.clientY - drag.y0) < DRAG_START_PX) return;
      drag.moved = true;
      this.ghost.hidden = false;
      this.ghost.textContent = item.label;
      this.ghost.style.left = `${e.clientX + 8}px`;
      this.ghost.style.top = `${e.clientY + 8}px`;
    };
    const up = (e) => {
      window.removeEventListener("pointermove", move);
      window.removeEventListener("pointerup", up);
      window.removeEventListener("pointercancel", up);
      this.ghost.hidden = true;
      this.drag = null;
      this.onPick(item);
      if (drag.moved && e.type === "pointerup") this.onDrop(item, e.clientX, e.clientY);
    };
    window.addEventListener("pointermove", move);
    window.addEventListener("pointerup", up);
    window.addEventListener("pointercancel", up);
    this.drag = drag;
  }
}
