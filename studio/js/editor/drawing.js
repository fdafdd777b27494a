// How the editor draws tiles, objects and routes on a 2D canvas: shared by
// the grid and the palette's icons. Sizes in pixels; a tile is `size` wide.

import { OBJECT_SHAPES } from "../map_text.js";

export const GROUND = { desert: "#5a4e38", urban: "#34503a" };
export const OBJECT_COLOURS = { house: "#b0b0b0", tree: "#43a047", lantern: "#fdd835", park: "#8bc34a", obstacle: "#e57373" };
export const ROUTE_COLOURS = ["#ff7043", "#ab47bc", "#26c6da", "#ffca28", "#7986cb", "#ec407a"];
const ROAD = "#6d6d6d";
const SIDES = [[1, 0, -1], [2, 1, 0], [4, 0, 1], [8, -1, 0]];  // bit, dx, dy (screen: y down)

// A road tile at (x, y) (its top-left corner): `mask` the connections it
// makes, `declared` what its character asks for (dashed red where nothing
// connects back), `width` the road's (two 4 m lanes). An explicit piece
// shows its character.
export function drawRoadTile(g, x, y, size, mask, declared, char, width = size * 0.4) {
  const cx = x + size / 2, cy = y + size / 2, half = size / 2;
  width = Math.max(2, width);
  g.strokeStyle = ROAD;
  g.fillStyle = ROAD;
  g.lineWidth = width;
  g.lineCap = "butt";
  const sides = SIDES.filter(([bit]) => mask & bit);
  if (sides.length === 2 && sides[0][1] !== -sides[1][1]) {  // a curve: a quarter circle about the corner
    const ox = cx + (sides[0][1] + sides[1][1]) * half, oy = cy + (sides[0][2] + sides[1][2]) * half;
    const angles = sides.map(([, dx, dy]) => Math.atan2(cy + dy * half - oy, cx + dx * half - ox));
    let delta = angles[1] - angles[0];
    while (delta > Math.PI) delta -= 2 * Math.PI;
    while (delta <= -Math.PI) delta += 2 * Math.PI;
    g.beginPath();
    g.arc(ox, oy, half, angles[0], angles[1], delta < 0);
    g.stroke();
  } else {
    g.beginPath();
    for (const [, dx, dy] of sides) { g.moveTo(cx, cy); g.lineTo(cx + dx * half, cy + dy * half); }
    g.stroke();
    g.fillRect(cx - width / 2, cy - width / 2, width, width);
  }
  const missing = declared & ~mask;  // sides asked for that nothing connects back to
  if (missing || !mask) {
    g.strokeStyle = "#ef5350";
    g.lineWidth = Math.max(1, size * 0.08);
    g.setLineDash([3, 2]);
    g.beginPath();
    for (const [bit, dx, dy] of SIDES) if (missing & bit) { g.moveTo(cx, cy); g.lineTo(cx + dx * half, cy + dy * half); }
    if (!mask) g.rect(cx - width / 2, cy - width / 2, width, width);
    g.stroke();
    g.setLineDash([]);
  }
  if (char && char !== "#" && size >= 18) {
    g.fillStyle = "#ffffffcc";
    g.font = `${Math.round(size * 0.28)}px monospace`;
    g.fillText(char, x + 2, y + size * 0.3);
  }
}

// An object centred at (px, py), `scale` pixels a metre, turned `rotDeg`
// counter-clockwise (the map's convention, seen from above).
export function drawObject(g, kind, px, py, rotDeg, scale, outline = null) {
  const [hx, hy] = OBJECT_SHAPES[kind] || [0.5, 0.5];
  g.save();
  g.translate(px, py);
  g.rotate(-rotDeg * Math.PI / 180);
  g.fillStyle = OBJECT_COLOURS[kind] || "#999";
  g.beginPath();
  if (kind === "tree") {
    g.globalAlpha = 0.75;
    g.arc(0, 0, Math.max(3, 3.5 * scale * 0.6), 0, 2 * Math.PI);  // the crown, a little smaller than it is
  } else {
    const w = Math.max(3, 2 * hx * scale), h = Math.max(3, 2 * hy * scale);
    g.rect(-w / 2, -h / 2, w, h);
  }
  g.fill();
  g.globalAlpha = 1;
  if (kind === "house" || kind === "obstacle") {  // which way it faces: a tick on its own +x side
    g.strokeStyle = "#00000088";
    g.lineWidth = 1;
    g.beginPath();
    g.moveTo(0, 0);
    g.lineTo(Math.max(3, hx * scale), 0);
    g.stroke();
  }
  if (outline) {
    g.strokeStyle = outline;
    g.lineWidth = 2;
    g.beginPath();
    const r = Math.max(6, Math.hypot(hx, hy) * scale + 2);
    if (kind === "tree" || kind === "lantern") g.arc(0, 0, r, 0, 2 * Math.PI);
    else g.rect(-hx * scale - 2, -hy * scale - 2, 2 * hx * scale + 4, 2 * hy * scale + 4);
    g.stroke();
  }
  g.restore();
}

// A route through `points` (pixel centres of its tiles, in order), with an
// arrow halfway along each step; closed: back to the first too.
export function drawRoute(g, points, closed, colour, width) {
  if (!points.length) return;
  g.strokeStyle = colour;
  g.fillStyle = colour;
  g.lineWidth = width;
  g.lineJoin = "round";
  g.beginPath();
  points.forEach(([x, y], k) => (k ? g.lineTo(x, y) : g.moveTo(x, y)));
  if (closed && points.length > 1) g.closePath();
  g.stroke();
  const steps = points.length - 1 + (closed && points.length > 1 ? 1 : 0);
  const head = Math.max(5, width * 3);
  for (let k = 0; k < steps; ++k) {
    const [x0, y0] = points[k], [x1, y1] = points[(k + 1) % points.length];
    const angle = Math.atan2(y1 - y0, x1 - x0), mx = (x0 + x1) / 2, my = (y0 + y1) / 2;
    g.beginPath();
    g.moveTo(mx + Math.cos(angle) * head, my + Math.sin(angle) * head);
    g.lineTo(mx + Math.cos(angle + 2.5) * head, my + Math.sin(angle + 2.5) * head);
    g.lineTo(mx + Math.cos(angle - 2.5) * head, my + Math.sin(angle - 2.5) * head);
    g.closePath();
    g.fill();
  }
  g.beginPath();  // the first tile: a ring
  g.arc(points[0][0], points[0][1], head * 0.8, 0, 2 * Math.PI);
  g.stroke();
}
