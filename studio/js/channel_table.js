// The pixel channels, in plane order: generated from protocol/channels.h by
// tools/channel_tables.py; do not edit (the architecture test checks it is current).
export const PIXEL_CHANNELS = [
  { name: "rgb", channel: "CHANNEL_RGB", format: "PIXEL_FORMAT_RGB8", element: "u8", components: 3, summary: "8-bit colour image, gamma encoded" },
  { name: "depth", channel: "CHANNEL_DEPTH", format: "PIXEL_FORMAT_DEPTH_F32", element: "f32", components: 1, summary: "distance along the optical axis in metres; +inf where nothing was hit" },
  { name: "mask", channel: "CHANNEL_MASK", format: "PIXEL_FORMAT_INSTANCE_U16", element: "u16", components: 1, summary: "instance id of labelled objects; 0 elsewhere" },
  { name: "semantic", channel: "CHANNEL_SEMANTIC", format: "PIXEL_FORMAT_SEMANTIC_U8", element: "u8", components: 1, summary: "semantic class per pixel, Cityscapes trainIds (protocol.md)" },
  { name: "normals", channel: "CHANNEL_NORMALS", format: "PIXEL_FORMAT_NORMAL_F32X3", element: "f32", components: 3, summary: "camera-space unit surface normal, OpenCV axes; 0,0,0 for sky" },
  { name: "flow", channel: "CHANNEL_FLOW", format: "PIXEL_FORMAT_FLOW_F32X2", element: "f32", components: 2, summary: "optical flow from the camera's previous frame to this one, pixels" },
  { name: "albedo", channel: "CHANNEL_ALBEDO", format: "PIXEL_FORMAT_RGB8", element: "u8", components: 3, summary: "surface colour before any light, gamma 2; 0,0,0 for sky" },
];
