// The route list: add a route (name, closed or open), pick one (the grid's
// route tool then appends the tiles clicked, in driving order), remove its
// last tile (Backspace), delete it. The daemon's check says whether a route
// follows the road; the one it names is outlined in red.

import { ROUTE_COLOURS } from "./drawing.js";

const $ = (id) => document.getElementById(id);

export class RoutePanel {
  constructor(app) {
    this.app = app;
    $("add-route").onclick = () => this.add();
    $("route-name").addEventListener("keydown", (e) => { if (e.key === "Enter") this.add(); });
    $("route-undo-tile").onclick = () => this.removeLastTile();
  }

  add() {
    const app = this.app, routes = app.model.routes;
    let name = $("route-name").value.trim();
    if (!name) {
      let n = routes.length + 1;
      while (routes.some((r) => r.name === `route${n}`)) ++n;
      name = `route${n}`;
    }
    const closed = $("route-shape").value === "closed";
    app.edit(`add route ${name}`, (m) => m.routes.push({ name, closed, tiles: [] }));
    app.pickRoute(app.model.routes.length - 1);
    $("route-name").value = "";
  }

  remove(index) {
    const name = this.app.model.routes[index]?.name;
    this.app.edit(`delete route ${name}`, (m) => m.routes.splice(index, 1));
    this.app.pickRoute(null);
  }

  removeLastTile() {
    const index = this.app.routeIndex;
    const route = this.app.model.routes[index];
    if (!route || !route.tiles.length) return false;
    this.app.edit("remove route tile", (m) => m.routes[index].tiles.pop());
    return true;
  }

  render() {
    const app = this.app, list = $("route-list");
    const problem = app.problem;
    list.replaceChildren(...app.model.routes.map((route, i) => {
      const item = document.createElement("li");
      item.className = "route-item";
      item.classList.toggle("active", i === app.routeIndex);
      item.classList.toggle("bad", problem?.route === i);
      item.dataset.index = String(i);
      const swatch = Object.assign(document.createElement("span"), { className: "swatch" });
      swatch.style.background = ROUTE_COLOURS[i % ROUTE_COLOURS.length];
      const label = Object.assign(document.createElement("span"), {
        className: "route-label",
        textContent: `${route.name} · ${route.closed ? "closed" : "open"} · ${route.tiles.length} tiles`,
      });
      const remove = Object.assign(document.createElement("button"), {
        className: "route-delete", textContent: "×", title: `delete route ${route.name}`,
      });
      remove.onclick = (e) => { e.stopPropagation(); this.remove(i); };
      item.append(swatch, label, remove);
      item.onclick = () => app.pickRoute(i === app.routeIndex ? null : i);
      return item;
    }));
    $("route-undo-tile").disabled = app.routeIndex === null;
    $("route-hint").textContent = app.routeIndex === null
      ? "pick a route to add tiles to it"
      : `click tiles along the road in driving order (${app.model.routes[app.routeIndex]?.name}); Backspace removes the last`;
  }
}
