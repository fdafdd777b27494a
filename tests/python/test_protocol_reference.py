"""docs/protocol.md's reference tables against the code: the shared-memory
layout version and channel masks (shm_layout, the daemon's ring), the
Subscribe delivery values and the error codes (the generated protobuf
module), the --shm-channels values and the conditions presets (the daemon's
own answers). A number changed in one place and not the other fails here."""

import os
import re

import pytest

import sim4cv
from sim4cv import pb
from sim4cv import shm_layout as L

PROTOCOL_MD = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "docs", "protocol.md")


@pytest.fixture(scope="module")
def text():
    with open(PROTOCOL_MD, encoding="utf-8") as f:
        return f.read()


def _ticked(cell):
    return re.findall(r"`([^`]+)`", cell)


def test_layout_version_rows_match_shm_layout(text):
    rows = [re.search(r"`(\d+)`", line.split("`layout_version` |", 1)[1]).group(1)
            for line in text.splitlines() if re.match(r"\s*\| \d+ \| u32 \| `layout_version` \|", line)]
    assert len(rows) == 3, rows  # the attach message, the frame object, the client area
    assert set(rows) == {str(L.LAYOUT_VERSION)}
    assert re.findall(r"`layout_version` is `(\d+)`", text) == [str(L.LAYOUT_VERSION)]


def test_channel_masks_match_shm_layout(text):
    every = "`%#04x`" % L.ALL_PIXELS_MASK
    assert every in re.search(r"no bits but those of\s+(`0x[0-9a-f]+`)", text).group(1)
    assert "%s for all pixel channels" % every in text
    default = sum(1 << c for c in (pb.CHANNEL_RGB, pb.CHANNEL_DEPTH, pb.CHANNEL_MASK))
    assert "`%#04x` (RGB, DEPTH, MASK) by default" % default in text


def test_shm_channels_flag_lists_every_pixel_channel(text):
    row = next(line for line in text.splitlines() if line.startswith("| `--shm-channels LIST` |"))
    documented = _ticked(row.split("|")[3])
    expected = [pb.Channel.Name(c)[len("CHANNEL_"):].lower() for c, _ in L.PIXEL_CHANNELS]
    assert documented == expected


def test_delivery_values_match_the_enum(text):
    row = next(line for line in text.splitlines() if line.startswith("| 3 | `delivery` | Delivery | `DELIVERY_LOCKSTEP`"))
    documented = dict(re.findall(r"`(DELIVERY_[A-Z_]+)` \((\d+)", row))
    expected = {name: str(value) for name, value in pb.Delivery.items() if value}
    assert documented == expected
    assert "`delivery` not %s (unspecified or unknown)" % ", ".join(
        str(v) for v in sorted(pb.Delivery.values()) if v).replace(", %d" % max(pb.Delivery.values()),
                                                                  " or %d" % max(pb.Delivery.values())) in text


def test_error_code_table_matches_the_enum(text):
    documented = {name: int(value) for value, name in re.findall(r"^\| (\d+) \| `(ERROR_CODE_[A-Z_]+)` \|", text, re.M)}
    expected = {name: value for name, value in pb.ErrorCode.items() if value}
    assert documented == expected


def test_presets_in_the_reference_are_the_daemons(text, start_daemon):
    row = next(line for line in text.splitlines() if line.startswith("| `--conditions PRESET` |"))
    documented = _ticked(row.split("|")[3])
    daemon = start_daemon()
    with sim4cv.connect(daemon.address("tcp"), name="reference") as client:
        with pytest.raises(sim4cv.ServerError) as info:
            client.configure(pb.Configure(set_conditions=pb.SetConditions(preset="snow")))
    assert str(info.value).endswith("SetConditions.preset 'snow' is not a preset; use one of " + ", ".join(documented))
    assert "rain" in documented
