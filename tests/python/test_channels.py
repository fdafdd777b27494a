"""The ground-truth channels through the Python client: every channel is a
numpy view shaped by the Image's element type and components; the dense
channels agree with depth; two lockstep daemons give identical bytes; the
colourising helpers give images of the right shape."""

import os
import re

import numpy as np

import sim4cv
from sim4cv import pb, visualize

FRAME_TIMEOUT_S = 30.0
EVERY = ["rgb", "depth", "mask", "boxes", "semantic", "normals", "flow"]
SHAPES = {"rgb": ((180, 320, 3), np.uint8), "depth": ((180, 320), np.float32), "mask": ((180, 320), np.uint16),
          "semantic": ((180, 320), np.uint8), "normals": ((180, 320, 3), np.float32),
          "flow": ((180, 320, 2), np.float32)}


def frames(client, count):
    client.subscribe("uav", EVERY, "lockstep")
    return [client.step_and_receive(FRAME_TIMEOUT_S) for _ in range(count)]


def test_every_channel_is_a_typed_view(daemon, connect):
    frame = frames(connect("channels"), 20)[-1]
    for name, (shape, dtype) in SHAPES.items():
        array = sim4cv.image_array(frame, name)
        assert array.shape == shape and array.dtype == dtype, name
    depth = sim4cv.image_array(frame, "depth")
    semantic = sim4cv.image_array(frame, "semantic")
    normals = sim4cv.image_array(frame, "normals")
    flow = sim4cv.image_array(frame, "flow")
    sky = np.isinf(depth)
    assert np.array_equal(semantic == 10, sky), "class 10 (sky) exactly where nothing was hit"
    assert not np.any(semantic == 255), "every surface is labelled"
    length = np.linalg.norm(normals, axis=-1)
    assert np.all(np.abs(length[~sky] - 1.0) < 1e-3), "unit normals on every surface"
    assert np.all(normals[sky] == 0) and np.all(flow[sky] == 0)
    assert np.all(np.isfinite(flow[~sky]))
    mask = sim4cv.image_array(frame, "mask")
    assert np.all(semantic[mask == 1] == 13), "the car (id 1) is class car"


def test_two_lockstep_daemons_give_the_same_bytes(start_daemon):
    runs = []
    for name in ("first", "second"):
        d = start_daemon("--seed", "7")
        client = sim4cv.Client()
        start_daemon.clients.append(client)
        client.connect("127.0.0.1", d.port, name)
        runs.append(frames(client, 8))
    for a, b in zip(*runs):
        for image_a, image_b in zip(a.images, b.images):
            assert image_a.channel == image_b.channel
            assert image_a.data == image_b.data, pb.Channel.Name(image_a.channel)


def test_colour_images(daemon, connect):
    frame = frames(connect("colours"), 12)[-1]
    for colours, name in ((visualize.semantic_colours, "semantic"), (visualize.normals_colours, "normals"),
                          (visualize.flow_colours, "flow"), (visualize.depth_colours, "depth")):
        rgb = colours(sim4cv.image_array(frame, name))
        assert rgb.shape == (180, 320, 3) and rgb.dtype == np.uint8, name
    ids = np.array([[10, 13, 0]], np.uint8)
    assert visualize.semantic_colours(ids).tolist() == [[[70, 130, 180], [0, 0, 142], [128, 64, 128]]]
    folded = visualize.cityscapes_train_ids(np.array([[19, 20, 21, 13]], np.uint8))
    assert folded.tolist() == [[0, 0, 255, 13]]


def test_python_class_table_matches_the_protocol_header():
    header = os.path.join(os.path.dirname(__file__), "..", "..", "protocol", "semantic_classes.h")
    rows = re.findall(r'X\((\w+), (\d+), "([^"]+)", (\d+), (\d+), (\d+), (\d+)\)', open(header).read())
    assert len(rows) == len(visualize.SEMANTIC_CLASSES)
    for _, value, name, r, g, b, fold in rows:
        assert visualize.SEMANTIC_CLASSES[int(value)] == (name, (int(r), int(g), int(b)), int(fold)), name
