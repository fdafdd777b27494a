// The editor's map: read from the map text format (docs/maps.md) and
// written back in exactly the canonical form of the daemon's WriteMap
// (server/sim/map/map_writer.cpp): header, the comment lines that came right
// after it, name, tile_size (%.10g), surroundings, grid rows, end, routes
// with 12 tiles a `tiles` line, objects with 2 decimals. Grid characters
// are kept as written. The daemon's parser is the one that judges a map
// (CheckMap); this reader only builds what the editor edits, and refuses
// only what it could not hold.

import { formatFixed, formatGeneral } from "./printf.js";

export const HEADER = "sim4cv-map 1";
export const OBJECT_KINDS = ["house", "tree", "lantern", "park", "obstacle"];
const TILES_PER_LINE = 12;
const GRID_CHARS = /^[.#1-9a-fA-F]$/;

export function blankMap(width = 8, height = 6) {
  return {
    header: HEADER, comments: [], name: "untitled", tileSize: 20, surroundings: "desert",
    width, height, rows: Array.from({ length: height }, () => ".".repeat(width)), routes: [], objects: [],
  };
}

function problem(number, line, message) {
  return new Error(`map line ${number} '${line}': ${message}`);
}

function number(token, number_, line) {
  const value = Number(token);
  if (token === undefined || token === "" || !Number.isFinite(value)) {
    throw problem(number_, line, `'${token ?? ""}' is not a number`);
  }
  return value;
}

// Map text -> the editor's model; throws an Error naming the line for what
// it cannot hold (no header, an unknown keyword, a grid row of the wrong size).
export function parseMapText(text) {
  const model = { header: HEADER, comments: [], name: "", tileSize: 20, surroundings: "desert",
                  width: 0, height: 0, rows: [], routes: [], objects: [] };
  const lines = text.split("\n").map((line) => (line.endsWith("\r") ? line.slice(0, -1) : line));
  if (lines.length && lines[lines.length - 1] === "") lines.pop();
  let headerSeen = false, commentsOpen = false;
  for (let i = 0; i < lines.length; ++i) {
    const line = lines[i], n = i + 1;
    const trimmed = line.trim();
    if (!headerSeen) {
      if (trimmed === "" || trimmed.startsWith("#")) continue;
      if (trimmed.split(/\s+/).join(" ") !== HEADER) throw problem(n, line, `the first line must be '${HEADER}'`);
      headerSeen = commentsOpen = true;
      continue;
    }
    if (commentsOpen && trimmed.startsWith("#")) {
      model.comments.push(line);
      continue;
    }
    commentsOpen = false;
    const words = line.replace(/#.*/, "").trim().split(/\s+/).filter(Boolean);
    if (!words.length) continue;
    const [keyword, ...values] = words;
    if (keyword === "name") {
      model.name = values.join(" ");
    } else if (keyword === "tile_size") {
      model.tileSize = number(values[0], n, line);
    } else if (keyword === "surroundings") {
      model.surroundings = values[0] || "";
    } else if (keyword === "grid") {
      const width = number(values[0], n, line), height = number(values[1], n, line);
      if (!Number.isInteger(width) || !Number.isInteger(height) || width < 1 || height < 1) {
        throw problem(n, line, "the grid is not W H followed by H rows and 'end'");
      }
      model.width = width;
      model.height = height;
      for (let r = 0; r < height; ++r) {
        const row = (lines[i + 1 + r] ?? "").trim();
        if (row.length !== width || ![...row].every((c) => GRID_CHARS.test(c))) {
          throw problem(n + 1 + r, lines[i + 1 + r] ?? "", `grid row ${r} is not ${width} tiles`);
        }
        model.rows.push(row);
      }
      i += height;
      if ((lines[i + 1] ?? "").replace(/#.*/, "").trim() !== "end") {
        throw problem(i + 2, lines[i + 1] ?? "", `expected 'end' after ${height} grid rows`);
      }
      i += 1;
    } else if (keyword === "route") {
      model.routes.push({ name: values[0] || "", closed: values[1] !== "open", tiles: [] });
    } else if (keyword === "tiles") {
      const route = model.routes[model.routes.length - 1];
      if (!route) throw problem(n, line, "'tiles' before any 'route'");
      for (const token of values) {
        const [col, row] = token.split(",").map(Number);
        if (!Number.isInteger(col) || !Number.isInteger(row)) throw problem(n, line, `'${token}' is not a tile COL,ROW`);
        route.tiles.push([col, row]);
      }
    } else if (keyword === "object") {
      model.objects.push({ kind: values[0] || "", x: number(values[1], n, line), y: number(values[2], n, line),
                           rot: number(values[3], n, line) });
    } else {
      throw problem(n, line, `unknown keyword '${keyword}'`);
    }
  }
  if (!headerSeen) throw new Error(`map: no '${HEADER}' header`);
  if (!model.width) throw new Error(`map '${model.name}' has no grid`);
  return model;
}

// WriteMap's "%.2f", with "-0.00" written as "0.00".
export function fixed2(value) {
  const text = formatFixed(value, 2);
  return text === "-0.00" ? "0.00" : text;
}

// The canonical text, its lines and, for every line (0-based), what it came from:
// {what: "header"|"comment"|"name"|"tile_size"|"surroundings"|"grid"|"row"|"end"|"route"|"tiles"|"object",
//  row, route, object}.
export function serializeWithLines(model) {
  const out = [], origins = [];
  const put = (line, origin) => { out.push(line); origins.push(origin); };
  put(model.header, { what: "header" });
  model.comments.forEach((line, index) => put(line, { what: "comment", index }));
  put(`name ${model.name}`, { what: "name" });
  put(`tile_size ${formatGeneral(model.tileSize, 10)}`, { what: "tile_size" });
  put(`surroundings ${model.surroundings}`, { what: "surroundings" });
  put(`grid ${model.width} ${model.height}`, { what: "grid" });
  model.rows.forEach((row, r) => put(row, { what: "row", row: r }));
  put("end", { what: "end" });
  model.routes.forEach((route, index) => {
    put(`route ${route.name} ${route.closed ? "closed" : "open"}`, { what: "route", route: index });
    for (let k = 0; k < route.tiles.length; k += TILES_PER_LINE) {
      const tiles = route.tiles.slice(k, k + TILES_PER_LINE).map(([c, r]) => `${c},${r}`).join(" ");
      put(`tiles ${tiles}`, { what: "tiles", route: index, first: k });
    }
  });
  model.objects.forEach((o, index) => {
    put(`object ${o.kind} ${fixed2(o.x)} ${fixed2(o.y)} ${fixed2(o.rot)}`, { what: "object", object: index });
  });
  return { text: out.map((line) => `${line}\n`).join(""), lines: out, origins };
}

export function serializeMap(model) {
  return serializeWithLines(model).text;
}

export function cloneMap(model) {
  return structuredClone(model);
}

// --- tiles ------------------------------------------------------------------

export function tileAt(model, col, row) {
  if (col < 0 || row < 0 || col >= model.width || row >= model.height) return null;
  return model.rows[row][col];
}

export function setTile(model, col, row, char) {
  if (tileAt(model, col, row) === null || tileAt(model, col, row) === char) return false;
  const line = model.rows[row];
  model.rows[row] = line.slice(0, col) + char + line.slice(col + 1);
  return true;
}

// A grid character's explicit mask (N 1, E 2, S 4, W 8); null for '#' and '.'.
export function explicitMask(char) {
  return /^[1-9a-fA-F]$/.test(char) ? parseInt(char, 16) : null;
}

// A mask turned a quarter clockwise: north -> east -> south -> west -> north.
export function rotateMask(mask) {
  return ((mask << 1) | (mask >> 3)) & 15;
}

// An explicit piece's character turned clockwise; '#' and '.' stay as they are.
export function rotateChar(char) {
  const mask = explicitMask(char);
  return mask === null ? char : rotateMask(mask).toString(16);
}

// --- geometry (x east, y north; row 0 north, docs/maps.md) -------------------

export function tileOfPoint(model, x, y) {
  return { col: Math.floor(x / model.tileSize + model.width / 2), row: Math.floor(model.height / 2 - y / model.tileSize) };
}

export function round2(value) {
  return Math.round(value * 100) / 100;
}

// --- map-wide edits -----------------------------------------------------------

// New grid size, keeping what fits: the rows from the north-west corner,
// route tiles inside the new grid, objects over the tiles they stood on.
export function resizeMap(model, width, height) {
  const t = model.tileSize;
  const dx = ((model.width - width) / 2) * t, dy = ((height - model.height) / 2) * t;
  model.rows = Array.from({ length: height }, (_, r) =>
    (model.rows[r] ?? "").slice(0, width).padEnd(width, "."));
  for (const route of model.routes) route.tiles = route.tiles.filter(([c, r]) => c < width && r < height);
  model.objects = model.objects
    .map((o) => ({ ...o, x: round2(o.x + dx), y: round2(o.y + dy) }))
    .filter((o) => Math.abs(o.x) <= (width * t) / 2 && Math.abs(o.y) <= (height * t) / 2);
  model.width = width;
  model.height = height;
}

// New tile size: objects keep their place relative to the tiles.
export function setTileSize(model, tileSize) {
  const scale = tileSize / model.tileSize;
  if (Number.isFinite(scale) && scale > 0) {
    for (const o of model.objects) { o.x = round2(o.x * scale); o.y = round2(o.y * scale); }
  }
  model.tileSize = tileSize;
}
