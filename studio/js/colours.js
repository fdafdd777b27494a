// An Image's bytes as RGBA for a canvas: RGB8 channels as sent, ground truth
// colourised with the Python client's colour maps (clients/python/sim4cv/
// visualize.py): depth grey levels (near bright, sky black), instance ids
// as in clients/cpp/examples/channel_colours.cpp, semantic classes in the
// protocol's palette, normals (n + 1) / 2, flow on the colour wheel.

import { PIXEL_CHANNELS } from "./channel_table.js";

// protocol/semantic_classes.h, value -> [r, g, b] (tests/studio checks it matches).
export const SEMANTIC_COLOURS = {
  0: [128, 64, 128], 1: [244, 35, 232], 2: [70, 70, 70], 3: [102, 102, 156], 4: [190, 153, 153],
  5: [153, 153, 153], 6: [250, 170, 30], 7: [220, 220, 0], 8: [107, 142, 35], 9: [152, 251, 152],
  10: [70, 130, 180], 11: [220, 20, 60], 12: [255, 0, 0], 13: [0, 0, 142], 14: [0, 0, 70],
  15: [0, 60, 100], 16: [0, 80, 100], 17: [0, 0, 230], 18: [119, 11, 32], 19: [255, 255, 255],
  20: [200, 200, 200], 21: [255, 128, 0], 22: [180, 100, 40], 255: [0, 0, 0],
};

// The channels a view can show (protocol/channels.h's table, copied into
// channel_table.js): Subscribe's name, label, and the JSON enum.
const LABELS = { rgb: "RGB", mask: "instance ids", flow: "optical flow" };
export const CHANNELS = PIXEL_CHANNELS.map(({ name, channel }) => ({ name, label: LABELS[name] ?? name, channel }));

const semanticLut = new Uint8Array(256 * 3);
for (const [value, rgb] of Object.entries(SEMANTIC_COLOURS)) semanticLut.set(rgb, Number(value) * 3);

// A typed view of `bytes` (a Uint8Array slice of the binary message); copied
// when the slice is not aligned for the element (a JPEG before it).
function typed(Type, bytes) {
  if (bytes.byteOffset % Type.BYTES_PER_ELEMENT === 0) {
    return new Type(bytes.buffer, bytes.byteOffset, bytes.byteLength / Type.BYTES_PER_ELEMENT);
  }
  return new Type(bytes.slice().buffer);
}

// Fills `out` (Uint8ClampedArray, width*height*4) from a raw image of `channel`.
export function toRgba(channel, bytes, out) {
  const n = out.length / 4;
  const info = PIXEL_CHANNELS.find((c) => c.channel === channel);
  if (info?.format === "PIXEL_FORMAT_RGB8") {  // RGB, albedo: colour as sent
    for (let i = 0; i < n; ++i) {
      out[4 * i] = bytes[3 * i];
      out[4 * i + 1] = bytes[3 * i + 1];
      out[4 * i + 2] = bytes[3 * i + 2];
      out[4 * i + 3] = 255;
    }
  } else if (channel === "CHANNEL_DEPTH") {
    const depth = typed(Float32Array, bytes);
    let far = 0;
    for (let i = 0; i < n; ++i) if (Number.isFinite(depth[i]) && depth[i] > far) far = depth[i];
    far = Math.max(far, 1e-6);
    for (let i = 0; i < n; ++i) {
      const d = depth[i];
      const level = Number.isFinite(d) ? Math.floor((1 - Math.min(Math.max(d / far, 0), 1)) * 255) : 0;
      out[4 * i] = out[4 * i + 1] = out[4 * i + 2] = level;
      out[4 * i + 3] = 255;
    }
  } else if (channel === "CHANNEL_MASK") {
    const ids = typed(Uint16Array, bytes);
    for (let i = 0; i < n; ++i) {
      const id = ids[i];
      out[4 * i] = id ? 64 + ((id * 151) % 192) : 0;
      out[4 * i + 1] = id ? 64 + ((id * 57) % 192) : 0;
      out[4 * i + 2] = id ? 64 + ((id * 97) % 192) : 0;
      out[4 * i + 3] = 255;
    }
  } else if (channel === "CHANNEL_SEMANTIC") {
    for (let i = 0; i < n; ++i) {
      const k = bytes[i] * 3;
      out[4 * i] = semanticLut[k];
      out[4 * i + 1] = semanticLut[k + 1];
      out[4 * i + 2] = semanticLut[k + 2];
      out[4 * i + 3] = 255;
    }
  } else if (channel === "CHANNEL_NORMALS") {
    const normals = typed(Float32Array, bytes);
    for (let i = 0; i < n; ++i) {
      const x = normals[3 * i], y = normals[3 * i + 1], z = normals[3 * i + 2];
      const sky = x === 0 && y === 0 && z === 0;
      out[4 * i] = sky ? 0 : (x + 1) * 127.5;
      out[4 * i + 1] = sky ? 0 : (y + 1) * 127.5;
      out[4 * i + 2] = sky ? 0 : (z + 1) * 127.5;
      out[4 * i + 3] = 255;
    }
  } else if (channel === "CHANNEL_FLOW") {
    flowToRgba(typed(Float32Array, bytes), out, n);
  } else {
    greyToRgba(info, bytes, out, n);
  }
}

// A channel with no colour map of its own: its first component in grey
// levels from its smallest finite value (black) to its largest (white).
function greyToRgba(info, bytes, out, n) {
  if (!info) return;
  const Type = { u8: Uint8Array, u16: Uint16Array, f32: Float32Array }[info.element];
  const values = typed(Type, bytes);
  let low = Infinity, high = -Infinity;
  for (let i = 0; i < n; ++i) {
    const v = values[info.components * i];
    if (Number.isFinite(v)) low = Math.min(low, v), high = Math.max(high, v);
  }
  const scale = high > low ? 255 / (high - low) : 0;
  for (let i = 0; i < n; ++i) {
    const v = values[info.components * i];
    out[4 * i] = out[4 * i + 1] = out[4 * i + 2] = Number.isFinite(v) ? (v - low) * scale : 0;
    out[4 * i + 3] = 255;
  }
}

// Hue is the direction, saturation the magnitude relative to the largest;
// NaN (no previous pixel) is black. visualize.flow_colours, pixel by pixel.
function flowToRgba(flow, out, n) {
  let largest = 0;
  for (let i = 0; i < n; ++i) {
    const m = Math.hypot(flow[2 * i], flow[2 * i + 1]);
    if (Number.isFinite(m) && m > largest) largest = m;
  }
  largest = Math.max(largest, 1e-6);
  for (let i = 0; i < n; ++i) {
    const dx = flow[2 * i], dy = flow[2 * i + 1];
    out[4 * i + 3] = 255;
    if (!Number.isFinite(dx) || !Number.isFinite(dy)) {
      out[4 * i] = out[4 * i + 1] = out[4 * i + 2] = 0;
      continue;
    }
    const saturation = Math.min(Math.hypot(dx, dy) / largest, 1);
    const hue = (Math.atan2(-dy, -dx) / Math.PI + 1) * 3;
    const sector = Math.floor(hue) % 6, f = hue - Math.floor(hue);
    const wheel = [[1, f, 0], [1 - f, 1, 0], [0, 1, f], [0, 1 - f, 1], [f, 0, 1], [1, 0, 1 - f]][sector];
    for (let c = 0; c < 3; ++c) out[4 * i + c] = (1 - saturation * (1 - wheel[c])) * 255;
  }
}

// Object classes (Box.object_class) for labels and box colours.
export const CLASS_COLOURS = {
  OBJECT_CLASS_CAR: "#4fc3f7", OBJECT_CLASS_UAV: "#ffb74d", OBJECT_CLASS_BUILDING: "#bdbdbd",
  OBJECT_CLASS_TREE: "#81c784", OBJECT_CLASS_LANTERN: "#fff176", OBJECT_CLASS_OBSTACLE: "#e57373",
  OBJECT_CLASS_PEDESTRIAN: "#f06292", OBJECT_CLASS_TRAFFIC_LIGHT: "#ffd54f", OBJECT_CLASS_PARK: "#aed581",
};

export function className(objectClass) {
  return (objectClass || "OBJECT_CLASS_UNSPECIFIED").replace("OBJECT_CLASS_", "").toLowerCase().replace("_", " ");
}
