"""The pixel channels, in plane order: generated from protocol/channels.h by
tools/channel_tables.py; do not edit (the architecture test checks it is current)."""

# (name, proto Channel name, proto PixelFormat name, element: u8/u16/f32, components, bytes per pixel,
#  what it holds)
PIXEL_CHANNELS = (
    ("rgb", "CHANNEL_RGB", "PIXEL_FORMAT_RGB8", "u8", 3, 3, "8-bit colour image, gamma encoded"),
    ("depth", "CHANNEL_DEPTH", "PIXEL_FORMAT_DEPTH_F32", "f32", 1, 4, "distance along the optical axis in metres; +inf where nothing was hit"),
    ("mask", "CHANNEL_MASK", "PIXEL_FORMAT_INSTANCE_U16", "u16", 1, 2, "instance id of labelled objects; 0 elsewhere"),
    ("semantic", "CHANNEL_SEMANTIC", "PIXEL_FORMAT_SEMANTIC_U8", "u8", 1, 1, "semantic class per pixel, Cityscapes trainIds (protocol.md)"),
    ("normals", "CHANNEL_NORMALS", "PIXEL_FORMAT_NORMAL_F32X3", "f32", 3, 12, "camera-space unit surface normal, OpenCV axes; 0,0,0 for sky"),
    ("flow", "CHANNEL_FLOW", "PIXEL_FORMAT_FLOW_F32X2", "f32", 2, 8, "optical flow from the camera's previous frame to this one, pixels"),
    ("albedo", "CHANNEL_ALBEDO", "PIXEL_FORMAT_RGB8", "u8", 3, 3, "surface colour before any light, gamma 2; 0,0,0 for sky"),
)
