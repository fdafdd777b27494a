// Reads the map text format (docs/maps.md) the daemon sends in
// Configured.map_text, for drawing only: the daemon has already checked it
// (its parser is the one source of truth), so this keeps to what a drawing
// needs and skips what it does not know.

const SIDES = [ // mask bit, column step, row step (row 0 is north)
  { bit: 1, dc: 0, dr: -1, opposite: 4 },  // N
  { bit: 2, dc: 1, dr: 0, opposite: 8 },   // E
  { bit: 4, dc: 0, dr: 1, opposite: 1 },   // S
  { bit: 8, dc: -1, dr: 0, opposite: 2 },  // W
];

// The size of every object of a kind (server/sim/map/map.cpp, ShapeOf):
// footprint half extents along its own axes, metres.
export const OBJECT_SHAPES = {
  house: [5.0, 4.0], tree: [0.3, 0.3], lantern: [0.15, 0.15], park: [8.0, 8.0], obstacle: [1.0, 0.5],
};

export function parseMap(text) {
  const map = { name: "", tileSize: 20, surroundings: "desert", width: 0, height: 0, rows: [], objects: [], routes: [] };
  const lines = text.split(/\r?\n/);
  for (let i = 0; i < lines.length; ++i) {
    const words = lines[i].replace(/#.*/, "").trim().split(/\s+/).filter(Boolean);
    if (!words.length) continue;
    const [key, ...values] = words;
    if (key === "name") map.name = values[0];
    else if (key === "tile_size") map.tileSize = Number(values[0]);
    else if (key === "surroundings") map.surroundings = values[0];
    else if (key === "grid") {
      map.width = Number(values[0]);
      map.height = Number(values[1]);
      map.rows = lines.slice(i + 1, i + 1 + map.height).map((row) => row.trim());
      i += map.height;  // the rows hold '#', which is not a comment there
    } else if (key === "object") {
      map.objects.push({ kind: values[0], x: Number(values[1]), y: Number(values[2]), rotationDeg: Number(values[3]) });
    } else if (key === "route") {
      map.routes.push({ name: values[0], closed: values[1] === "closed", tiles: [] });
    } else if (key === "tiles" && map.routes.length) {
      for (const tile of values) {
        const [col, row] = tile.split(",").map(Number);
        map.routes[map.routes.length - 1].tiles.push({ col, row });
      }
    }
  }
  map.masks = connectionMasks(map);
  return map;
}

function codeAt(map, col, row) {
  if (col < 0 || row < 0 || col >= map.width || row >= map.height) return ".";
  return map.rows[row][col] || ".";
}

// A '#' connects to each neighbour that is road and connects back; a hex
// digit gives its mask (N = 1, E = 2, S = 4, W = 8) and connects only where
// the neighbour connects back too.
export function connectionMasks(map) {
  const declared = (col, row) => {
    const code = codeAt(map, col, row);
    if (code === ".") return 0;
    if (code === "#") return 15;
    return parseInt(code, 16) || 0;
  };
  const masks = [];
  for (let row = 0; row < map.height; ++row) {
    for (let col = 0; col < map.width; ++col) {
      const own = declared(col, row);
      let mask = 0;
      for (const side of SIDES) {
        if ((own & side.bit) && (declared(col + side.dc, row + side.dr) & side.opposite)) mask |= side.bit;
      }
      masks.push(mask);
    }
  }
  return masks;
}

// Tile (col, row)'s centre in world metres (x east, y north).
export function tileCentre(map, col, row) {
  return { x: (col + 0.5 - map.width / 2) * map.tileSize, y: (map.height / 2 - row - 0.5) * map.tileSize };
}
