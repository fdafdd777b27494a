// The pixel channels, in plane order: generated from protocol/channels.h by
// tools/channel_tables.py; do not edit (the architecture test checks it is current).
export const PIXEL_CHANNELS = [
  { name: "rgb", channel: "CHANNEL_RGB", element: "u8", components: 3, summary: "8-bit colour image, gamma encoded" },
  { name: "depth", channel: "CHANNEL_DEPTH", element: "f32", components: 1, summary: "distance along the optical axis in metres; +inf where nothing was hit" },
  { name: "mask", channel: "CHANNEL_MASK", element: "u16", components: 1, summary: "instance id of labelled objects; 0 elsewhere" },
  { name: "semantic", channel: "CHANNEL_SEMANTIC", element: "u8", components: 1, summary: "semantic class per pixel, Cityscapes trainIds (protocol.md)" },
  { name: "normals", channel: "CHANNEL_NORMALS", element: "f32", components: 3, summary: "camera-space unit surface normal, OpenCV axes; 0,0,0 for sky" },
  { name: "flow", channel: "CHANNEL_FLOW", element: "f32", components: 2, summary: "optical flow from the camera's previous frame to this one, pixels" },
];
