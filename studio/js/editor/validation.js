// Inline validation with the daemon as the one source of truth: after
// every edit (debounced) the map's text goes to CheckMap, and the answer
// ("valid", or the daemon's Error) is shown next to the grid. An error's
// "map line N '...'" is traced back, through the lines the text was written
// from, to the grid row, route, object or property it came from; tiles it
// names ("tile 3,2", "route goes from 1,2 to 2,2") are outlined too.

import { serializeWithLines } from "./map_model.js";

const DEBOUNCE_MS = 250;
const $ = (id) => document.getElementById(id);

// What an error message ("CheckMap.text: map line N 'LINE': ...") points
// at: {what, row, route, object, tiles: [{col, row}], line}; `lines` and
// `origins` are the text's lines and what each was written from.
export function locateProblem(message, lines, origins, model) {
  const found = { tiles: [] };
  let rest = message;
  const line = /map line (\d+) /.exec(message);
  if (line) {
    found.line = Number(line[1]);
    Object.assign(found, origins[found.line - 1] || {});
    // The quoted line is skipped (its tiles are not what the message names):
    // 'LINE' as written, or 'START…' (N bytes) when it is long.
    rest = message.slice(line.index + line[0].length);
    const quoted = `'${lines[found.line - 1] ?? ""}': `;
    if (rest.startsWith(quoted)) rest = rest.slice(quoted.length);
    else rest = rest.replace(/^'.*?…' \(\d+ bytes\): /, "");
  }
  for (const match of rest.matchAll(/(\d+),(\d+)/g)) {
    const col = Number(match[1]), row = Number(match[2]);
    if (col < model.width && row < model.height) found.tiles.push({ col, row });
  }
  if (found.what !== "row") delete found.row;
  return found;
}

export function describeProblem(found, model) {
  switch (found.what) {
    case "row": return `grid row ${found.row}`;
    case "route": case "tiles": return `route '${model.routes[found.route]?.name ?? ""}'`;
    case "object": return `object ${found.object + 1} (${model.objects[found.object]?.kind ?? ""})`;
    case "name": return "the map's name";
    case "tile_size": return "the tile size";
    case "surroundings": return "the surroundings";
    case "grid": return "the grid size";
    case "end": return "the grid";
    default: return found.line ? `line ${found.line}` : "";
  }
}

export class Validator {
  constructor(app) {
    this.app = app;
    this.timer = null;
    this.sequence = 0;
    // state: idle | pending | valid | invalid | failed; text: the text it is about.
    this.result = { state: "idle", text: null, message: "" };
  }

  schedule() {
    clearTimeout(this.timer);
    this.result = { ...this.result, state: "pending" };
    this.show();
    this.timer = setTimeout(() => this.run(), DEBOUNCE_MS);
  }

  async run() {
    const model = this.app.model;
    const { text, lines, origins } = serializeWithLines(model);
    const sequence = ++this.sequence;
    let result;
    try {
      const answer = await this.app.configure({ check_map: { text } });
      result = { state: "valid", text, message: "valid", canonical: answer.map_text || "" };
    } catch (error) {
      if (error.aborted) return;
      const daemonSaid = Boolean(error.code);
      result = { state: daemonSaid ? "invalid" : "failed", text, code: error.code || "",
                 message: daemonSaid ? error.message : `cannot check: ${error.message}` };
      if (daemonSaid) result.problem = locateProblem(error.message, lines, origins, model);
    }
    // An answer overtaken by a newer edit: that edit's own check follows.
    if (sequence !== this.sequence || text !== this.app.text()) return;
    this.result = result;
    this.app.problem = result.problem || null;
    this.show();
    this.app.render();
  }

  show() {
    const { state, message, problem } = this.result;
    const box = $("check");
    box.className = state;
    if (state === "pending") {
      box.dataset.state = "pending";
      $("check-state").textContent = "checking…";
      return;
    }
    box.dataset.state = state;
    $("check-state").textContent = state === "valid" ? "valid" : state === "idle" ? "" : "error";
    $("check-message").textContent = state === "valid" ? "the daemon's parser accepts this map" : message;
    const where = problem ? describeProblem(problem, this.app.model) : "";
    $("check-where").textContent = where ? `at ${where}` : "";
  }
}
