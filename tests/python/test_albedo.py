"""The albedo channel (server/render/channels/albedo.cpp) rendered by the real
daemon: the surface's own colour, the same under every light, where RGB's
surfaces are, unshadowed, carried in the layout of its row in
protocol/channels.h over TCP and over the shared-memory ring."""

import numpy as np
import pytest

import sim4cv
from conftest import Daemon, unique_shm_name
from sim4cv import channel_table, pb

CAMERA = "car_chase"  # behind the car: road, terrain, buildings, the car's shadow and sky
STEPS = 10
SKY = 10  # semantic class where nothing was hit
ROAD = 0
CHANNELS = ["rgb", "albedo", "semantic"]


def render(daemon, camera=CAMERA):
    """The STEPS-th lockstep frame of `camera`: the frame and its rgb, albedo and semantic arrays."""
    with sim4cv.connect(daemon.address("tcp"), name="albedo") as client:
        client.subscribe(camera, CHANNELS, "lockstep")
        for _ in range(STEPS):
            frame = client.step_and_receive(60.0)
    return frame, {name: sim4cv.image_array(frame, name).copy() for name in CHANNELS}


@pytest.fixture(scope="module")
def lit(tmp_path_factory):
    """{preset: (frame, arrays)}: the same moment at noon and at dusk (lockstep daemons are deterministic)."""
    frames = {}
    for preset in ("clear_noon", "dusk"):
        daemon = Daemon(["--conditions", preset], tmp_path_factory.mktemp(preset))
        try:
            frames[preset] = render(daemon)
        finally:
            assert daemon.terminate() == 0, daemon.log()
    return frames


def test_albedo_is_the_same_under_any_light(lit):
    noon, dusk = lit["clear_noon"][1], lit["dusk"][1]
    assert np.array_equal(noon["semantic"], dusk["semantic"]), "the two daemons drew the same moment"
    assert np.abs(noon["rgb"].astype(int) - dusk["rgb"]).mean() > 20, "dusk's RGB is lit differently"
    assert np.array_equal(noon["albedo"], dusk["albedo"]), "albedo holds no light"


def test_albedo_is_where_the_surfaces_are(lit):
    arrays = lit["clear_noon"][1]
    sky = arrays["semantic"] == SKY
    assert 0 < sky.sum() < sky.size, "the view has sky and surfaces"
    nothing = np.all(arrays["albedo"] == 0, axis=-1)
    assert np.array_equal(nothing, sky), "0,0,0 exactly where nothing was hit"


def test_shadows_darken_rgb_but_not_albedo(lit):
    """The car's shadow on the road: the road's darkest RGB pixels are about half as bright as its lit ones,
    while their albedo is that of the rest of the road."""
    arrays = lit["clear_noon"][1]
    road = arrays["semantic"] == ROAD
    rgb, albedo = arrays["rgb"][road].mean(axis=-1), arrays["albedo"][road].mean(axis=-1)
    lit_pixels = rgb >= np.median(rgb)
    shadowed = rgb < 0.7 * np.median(rgb)
    assert shadowed.sum() > 100, "the car casts a shadow on the road"
    assert rgb[shadowed].mean() < 0.7 * rgb[lit_pixels].mean()
    ratio = albedo[shadowed].mean() / albedo[lit_pixels].mean()
    assert 0.9 < ratio < 1.1, "albedo in shadow / albedo in the sun: %.3f" % ratio


def test_the_image_has_its_rows_layout(lit):
    frame, arrays = lit["clear_noon"]
    row = next(r for r in channel_table.PIXEL_CHANNELS if r[0] == "albedo")
    name, channel, pixel_format, element, components, bytes_per_pixel, _ = row
    image = next(i for i in frame.message.images if i.channel == pb.Channel.Value(channel))
    assert pb.PixelFormat.Name(image.format) == pixel_format == "PIXEL_FORMAT_RGB8"
    assert pb.ElementType.Name(image.element) == "ELEMENT_TYPE_" + element.upper()
    assert image.components == components == 3
    assert image.stride == frame.width * bytes_per_pixel and len(image.data) == image.stride * frame.height
    assert arrays[name].shape == (frame.height, frame.width, 3) and arrays[name].dtype == np.uint8


def test_fast_look_albedo_is_the_vertex_colour(start_daemon):
    """--quality fast: the albedo is the vertex colour, which that look shades by one constant on flat
    ground, so RGB / albedo (in linear light) is the same on every road pixel."""
    _, arrays = render(start_daemon("--quality", "fast"))
    road = (arrays["semantic"] == ROAD) & np.all(arrays["albedo"] > 20, axis=-1)
    assert road.sum() > 1000
    # Linear light: the fast look's RGB is gamma 2.2, albedo gamma 2.
    shading = ((arrays["rgb"][road] / 255.0) ** 2.2 / (arrays["albedo"][road] / 255.0) ** 2).mean(axis=-1)
    assert shading.std() < 0.02 * shading.mean(), "RGB / albedo on the road: %s" % np.percentile(shading, [1, 50, 99])


def test_albedo_over_the_shm_ring_is_the_tcp_frame(start_daemon):
    """--shm-channels albedo: the ring's slot has an albedo plane (its size from the table), holding the
    bytes TCP sends for the same frame."""
    daemon = start_daemon("--shm-name", unique_shm_name(), "--shm-channels", "rgb,albedo")
    with sim4cv.connect(daemon.address("tcp"), name="tcp-twin") as tcp, \
            sim4cv.connect(daemon.address("shm"), name="shm") as shm:
        tcp.subscribe("uav", ["albedo"], "lockstep")
        shm.subscribe("uav", ["rgb", "albedo"], "lockstep")
        for _ in range(3):
            shm.step()
            over_tcp = tcp.step_and_receive(60.0)
            over_shm = shm.receive_frame()
        assert over_shm.frame_id == over_tcp.frame_id
        albedo = over_shm.image("albedo")
        assert albedo.shape == (180, 320, 3) and albedo.dtype == np.uint8 and albedo.any()
        assert np.array_equal(albedo, sim4cv.image_array(over_tcp, "albedo"))
