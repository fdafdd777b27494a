"""TraX: message grammar, image and region encodings (sim4cv.trax_protocol),
and whole sessions with real tracker processes (sim4cv.trax): the NCC
example tracker, and tests/python/trax_misbehaving.py for every failure.
No daemon needed. Every test checks that no tracker process is left."""

import base64
import os
import sys
import time

import numpy as np
import pytest

from conftest import REPO_ROOT

from sim4cv import Sim4cvError
from sim4cv import trax_protocol as tp
from sim4cv.trax import TraxError, TraxTracker, open_tracker, parse_tracker_spec

NCC = os.path.join(REPO_ROOT, "clients", "python", "examples", "trax_ncc_tracker.py")
BAD = os.path.join(os.path.dirname(os.path.abspath(__file__)), "trax_misbehaving.py")


# --- helpers -----------------------------------------------------------------------

def _state_of(pid):
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return None


def assert_gone(pid, zombie_ok=False, wait=3.0):
    """The process no longer runs; ours must also be reaped (no zombie)."""
    end = time.monotonic() + wait
    while True:
        state = _state_of(pid)
        if state is None or (zombie_ok and state in ("Z", "X")):
            return
        if time.monotonic() > end:
            pytest.fail("process %d is still there (state %s)" % (pid, state))
        time.sleep(0.02)


def bad(*options, **kw):
    return TraxTracker([sys.executable, BAD] + list(options), **kw)


def ncc(*options, **kw):
    return TraxTracker([sys.executable, NCC] + list(options), **kw)


def scene(n=30, size=(240, 320), square=40, seed=7, step=(3, 2)):
    """Frames (HxWx3 uint8 RGB) of a textured square moving over noise, and its true boxes."""
    rng = np.random.default_rng(seed)
    texture = rng.integers(0, 256, (square, square, 3), dtype=np.uint8)
    for i in range(n):
        image = rng.integers(70, 130, size + (3,), dtype=np.uint8)
        x, y = 40 + step[0] * i, 30 + step[1] * i
        image[y:y + square, x:x + square] = texture
        yield image, (x, y, square, square)


def track(tracker, frames):
    """Runs a session; returns the largest corner error in pixels."""
    worst = 0.0
    for i, (image, truth) in enumerate(frames):
        if i == 0:
            tracker.init(image, truth)
            continue
        box = tracker.update(image)
        assert len(box) == 4 and tracker.elapsed > 0
        worst = max(worst, abs(box[0] - truth[0]), abs(box[1] - truth[1]),
                    abs(box[2] - truth[2]), abs(box[3] - truth[3]))
    return worst


def small():
    return np.zeros((8, 8, 3), np.uint8)


# --- messages --------------------------------------------------------------------------

def test_format_message_quotes_and_escapes():
    line = tp.format_message("state", ["1,2,3,4"], {"a.b_c": 'x "y" \\ z\nw'})
    assert line == '@@TRAX:state "1,2,3,4" "a.b_c=x \\"y\\" \\\\ z\\nw"\n'
    assert "\n" not in line[:-1]
    assert tp.format_message("quit") == "@@TRAX:quit\n"


@pytest.mark.parametrize("value", ["plain", "with spaces", "a,b,c", 'say "hi"', "back\\slash", "new\nline",
                                   "trailing\\", "x=y==z", "", " lead and trail ", "\\n literal", "ünïcode"])
def test_round_trip_properties(value):
    props = {"trax.name": value, "k": value + "!", "a.b": "2"}
    msg = tp.parse_message(tp.format_message("hello", [], props))
    assert msg == tp.Message("hello", [], props)


def test_round_trip_arguments():
    args = ["image:2;1;gray8;AAA=", "file:///tmp/dir with space/a=b.png", "1.5,2,3,4", 'q"uo\\te']
    msg = tp.parse_message(tp.format_message("initialize", args, {"x": "1"}))
    assert msg.arguments == args and msg.properties == {"x": "1"}


def test_parse_as_other_writers_write():
    # unquoted arguments and properties, several spaces, a CR, mixed case, "status" for "state"
    msg = tp.parse_message('@@TRAX:hello  trax.version=2   "trax.name=a b" trax.image=path;memory;\r\n')
    assert msg == tp.Message("hello", [], {"trax.version": "2", "trax.name": "a b", "trax.image": "path;memory;"})
    assert tp.parse_message("@@TRAX:Status 1,2,3,4").name == "state"
    assert tp.parse_message("@@TRAX:frame image:2;1;gray8;AAA=").arguments == ["image:2;1;gray8;AAA="]
    assert tp.parse_message('@@TRAX:state "1\\,2"').arguments == ["1,2"]      # \X is X
    long_key = "k" * 65
    assert tp.parse_message("@@TRAX:frame %s=1" % long_key).arguments == [long_key + "=1"]
    assert tp.parse_message("@@TRAX:frame %s=1" % long_key[:64]).properties == {long_key[:64]: "1"}
    assert tp.parse_message("@@TRAX:error \"model exploded\"").name == "error"


@pytest.mark.parametrize("line", ['@@TRAX:state "1,2', '@@TRAX:state "1,2"x', "@@TRAX:state 1,2\\",
                                  "@@TRAX:bogus 1", "@@TRAX:state! 1", "hello world", ""])
def test_parse_rejects(line):
    with pytest.raises(tp.MessageError):
        tp.parse_message(line)


def test_format_rejects():
    with pytest.raises(ValueError):
        tp.format_message("state", [], {"bad key": "1"})
    with pytest.raises(ValueError):
        tp.format_message("state", [], {"k" * 65: "1"})
    with pytest.raises(ValueError):
        tp.format_message("state", ["looks=like_a_property"])
    with pytest.raises(ValueError):
        tp.format_message("bad name", [])


def test_is_message_line_and_lists():
    assert tp.is_message_line("@@TRAX:hello") and not tp.is_message_line("x @@TRAX:hello")
    assert tp.split_list("path;memory;") == ["path", "memory"]
    assert tp.split_list("color, depth") == ["color", "depth"]
    assert tp.split_list(None) == []


# --- images and regions ---------------------------------------------------------------------

def test_memory_image_encoding():
    rgb = np.array([[[1, 2, 3], [4, 5, 6]]], np.uint8)                 # 1 row, 2 pixels
    text = tp.encode_memory_image(rgb)
    assert text == "image:2;1;rgb;" + base64.b64encode(bytes([1, 2, 3, 4, 5, 6])).decode()
    assert np.array_equal(tp.decode_memory_image(text), rgb)
    gray = np.arange(12, dtype=np.uint8).reshape(3, 4)
    assert tp.encode_memory_image(gray).startswith("image:4;3;gray8;")
    assert np.array_equal(tp.decode_memory_image(tp.encode_memory_image(gray)), gray)
    g16 = np.array([[1, 258]], np.uint16)
    assert tp.encode_memory_image(g16) == "image:2;1;gray16;" + base64.b64encode(b"\x01\x00\x02\x01").decode()
    assert np.array_equal(tp.decode_memory_image(tp.encode_memory_image(g16)), g16)
    with pytest.raises(ValueError):
        tp.encode_memory_image(np.zeros((2, 2, 4), np.uint8))
    with pytest.raises(ValueError):
        tp.decode_memory_image("image:3;1;rgb;" + base64.b64encode(b"12345").decode())


def test_other_image_encodings():
    assert tp.encode_path_image("/tmp/a b.png") == "file:///tmp/a b.png"
    assert tp.encode_buffer_image(b"\x89PNG") == "data:image/png;" + base64.b64encode(b"\x89PNG").decode()


def test_regions():
    assert tp.format_rectangle((1, 2.5, 3, 4)) == "1.0000,2.5000,3.0000,4.0000"
    assert tp.parse_region("1,2,3,4").bounding_box() == (1, 2, 3, 4)
    assert tp.parse_region("rect:1,2,3,4").kind == "rectangle"
    poly = tp.parse_region(tp.format_polygon_of_box((1, 2, 3, 4)))
    assert poly.kind == "polygon" and poly.bounding_box() == (1, 2, 3, 4)
    assert tp.parse_region("0").kind == "special" and tp.parse_region("0").bounding_box() is None
    assert tp.parse_region("nan,nan,nan,nan").kind == "special"
    assert tp.parse_region("mask:0,0,2,2,1,3").kind == "mask"
    for text in ("1,2,3", "1,2,3,4,5", "a,b,c,d", "", "circle:1,2,3"):
        with pytest.raises(ValueError):
            tp.parse_region(text)


def test_tracker_spec():
    assert parse_tracker_spec("trax:python3 t.py --x 'a b'") == "python3 t.py --x 'a b'"
    for spec in ("python3 t.py", "trax:", "trax:   "):
        with pytest.raises(ValueError):
            parse_tracker_spec(spec)


# --- sessions with the NCC tracker -------------------------------------------------------------

def test_ncc_session_prefers_memory_and_tracks():
    with open_tracker("trax:%s %s" % (sys.executable, NCC)) as t:
        pid = t.pid
        assert t.name == "ncc" and t.version == 3 and t.properties["trax.name"] == "ncc"
        assert t.image_format == "memory" and t.region_format == "rectangle"
        assert track(t, scene()) <= 2.0
    assert_gone(pid)


@pytest.mark.parametrize("fmt,version,transport", [("path", 3, "stdio"), ("memory", 1, "stdio"),
                                                   ("buffer", 2, "stdio"), ("memory", 4, "socket")])
def test_ncc_formats_versions_transports(fmt, version, transport):
    t = ncc("--image-formats", "path,memory,buffer", "--trax-version", str(version),
            image_format=fmt, transport=transport)
    try:
        assert t.image_format == fmt and t.version == version
        assert track(t, scene(n=15)) <= 2.0
        if fmt == "path":
            assert os.listdir(t._tmpdir) == []          # frames are removed once answered
        tmpdir = t._tmpdir
        # reinitialisation (version 4: an empty initialize first) on another target
        frames = list(scene(n=6, step=(-2, 3), seed=3))
        assert track(t, frames) <= 2.0
    finally:
        t.close()
    assert_gone(t.pid)
    assert tmpdir is None or not os.path.exists(tmpdir)


def test_ncc_announcing_only_path_gets_path_and_forcing_memory_is_refused():
    with ncc("--image-formats", "path") as t:
        assert t.image_format == "path"
        assert track(t, scene(n=5)) <= 2.0
    with pytest.raises(TraxError, match=r"accepts images as path, not memory") as e:
        ncc("--image-formats", "path", image_format="memory")
    assert isinstance(e.value, Sim4cvError)


def test_update_before_init_and_after_close():
    t = bad()
    with pytest.raises(TraxError, match="before init"):
        t.update(small())
    t.close()
    t.close()                                             # idempotent
    with pytest.raises(TraxError, match="closed"):
        t.init(small(), (1, 1, 2, 2))
    assert_gone(t.pid)


# --- failures ----------------------------------------------------------------------------------

def _fails(options, pattern, calls=2, **kw):
    """Starts the misbehaving tracker, runs init + (calls-1) updates, expects TraxError matching pattern."""
    t = None
    with pytest.raises(TraxError, match=pattern) as e:
        t = bad(*options, **kw)
        t.init(small(), (1, 2, 3, 4))
        for _ in range(calls - 1):
            t.update(small())
    if t is not None:
        assert_gone(t.pid)
        with pytest.raises(TraxError, match="is gone"):
            t.update(small())
        t.close()
    return str(e.value)


def test_crash_mid_session_reports_exit_code_and_stderr():
    text = _fails(["--crash-after", "1"], r"exited with code 3 before sending a state after frame")
    assert "boom: simulated crash" in text and "trax_misbehaving.py" in text


def test_killed_by_signal():
    _fails(["--signal-after", "2"], r"was killed by SIGSEGV", calls=3)


def test_exit_without_a_word():
    _fails(["--exit-after", "0"], r"exited with code 0 before sending a state after initialize")


def test_garbage_line_is_named():
    text = _fails(["--garbage-after", "1"], r"malformed TraX line")
    assert '@@TRAX:state "12,34' in text


def test_other_output_is_ignored():
    with bad("--chatter") as t:
        t.init(small(), (1, 2, 3, 4))
        assert t.update(small()) == (10, 20, 30, 40)
        # stderr has its own reader thread: the line may land a moment after the state on stdout.
        deadline = time.monotonic() + 30
        while "tracker stderr: working" not in t.stderr_tail and time.monotonic() < deadline:
            time.sleep(0.01)
        assert "tracker stderr: working" in t.stderr_tail


def test_hang_is_killed_after_timeout():
    start = time.monotonic()
    # 2 s per call, 30 s for the start: a busy machine may take longer than a short limit to start
    # a Python tracker or answer its init, which would fail the test for the wrong reason.
    _fails(["--hang-after", "1"], r"did not send a state after frame within 2 s; killed it", timeout=2,
           startup_timeout=30)
    assert time.monotonic() - start < 20  # killed at its timeout, not a default one (margin for busy hosts)


def test_hang_without_reading_a_large_frame():
    t = bad("--hang-after", "1", timeout=2, startup_timeout=30, image_format="memory")
    t.init(small(), (1, 2, 3, 4))
    start = time.monotonic()
    with pytest.raises(TraxError, match=r"did not read its input within 2 s; killed it"):
        t.update(np.zeros((480, 640, 3), np.uint8))    # 1.2 MB of Base64: more than a pipe holds
    assert time.monotonic() - start < 20  # margin for busy hosts; the message names the 2 s limit
    assert_gone(t.pid)


def test_hang_before_hello():
    _fails(["--hang-after", "-1"], r"did not send its hello within 0.5 s", timeout=0.5)


def test_error_message():
    _fails(["--error-after", "1"], r"reported an error: model exploded")


def test_quit_with_reason():
    _fails(["--quit-after", "0"], r"quit the session: out of memory")


@pytest.mark.parametrize("version,pattern", [("99", "speaks TraX version 99; sim4cv speaks versions 1 to 4"),
                                             ("0", "speaks TraX version 0"),
                                             ("two", "trax.version='two', not an integer")])
def test_wrong_version(version, pattern):
    _fails(["--version", version], pattern)


def test_unsupported_formats_are_refused():
    _fails(["--image-formats", "url;"], r"accepts images as url; sim4cv sends memory, buffer or path")
    _fails(["--region-formats", "mask;"], r"accepts regions mask; sim4cv sends rectangle or polygon")
    _fails(["--channels", "color;depth;"], r"needs image channels color,depth; sim4cv sends only color")


@pytest.mark.parametrize("region,pattern", [("mask:0,0,2,2,1,3", "answered frame with a mask region"),
                                            ("1,2,3", "answered frame with a bad region")])
def test_unsupported_region_answer(region, pattern):
    _fails(["--region", region], pattern)


def test_special_and_polygon_answers():
    with bad("--region", "0") as t:
        t.init(small(), (1, 2, 3, 4))
        assert t.update(small()) is None
    with bad("--region", "1,2,5,2,5,7,1,7", "--region-formats", "polygon;") as t:
        assert t.region_format == "polygon"
        t.init(small(), (1, 2, 3, 4))
        assert t.update(small()) == (1, 2, 4, 5)


def test_no_such_program():
    with pytest.raises(TraxError, match="cannot start TraX tracker"):
        TraxTracker("/nonexistent/tracker --x")
    with pytest.raises(TraxError, match=r"exited with code 1 before sending its hello"):
        TraxTracker("false")


def test_process_group_is_killed_on_close_and_on_failure():
    t = bad("--spawn-child")
    child = int(t.properties["test.child_pid"])
    t.init(small(), (1, 2, 3, 4))
    t.close()
    assert_gone(t.pid)
    assert_gone(child, zombie_ok=True)                  # reparented: reaped by init, not by us
    t = bad("--spawn-child", "--hang-after", "1", timeout=2, startup_timeout=30)
    child = int(t.properties["test.child_pid"])
    t.init(small(), (1, 2, 3, 4))
    with pytest.raises(TraxError, match="killed it"):
        t.update(small())
    assert_gone(t.pid)
    assert_gone(child, zombie_ok=True)


# --- the recipe in docs/trax.md ---------------------------------------------------------------

def _recipe():
    with open(os.path.join(REPO_ROOT, "docs", "trax.md")) as f:
        text = f.read()
    start = text.index('```python\n#!/usr/bin/python3\n"""MyTracker') + len("```python\n")
    return text[start:text.index("```", start)]


@pytest.mark.parametrize("fmt", ["memory", "path"])
def test_docs_recipe_is_a_working_trax_server(tmp_path, fmt):
    (tmp_path / "my_trax_tracker.py").write_text(_recipe())
    (tmp_path / "my_package.py").write_text(
        "import sys\nsys.path.insert(0, %r)\nfrom trax_ncc_tracker import NCCTracker as MyTracker\n"
        % os.path.dirname(NCC))
    with TraxTracker([sys.executable, "my_trax_tracker.py"], cwd=str(tmp_path), image_format=fmt) as t:
        assert t.name == "my_tracker" and t.version == 1 and t.image_format == fmt
        assert track(t, scene(n=10)) <= 2.0
    assert_gone(t.pid)


# --- trackers that misbehave at the edges: process trees, floods, junk -------------------------

def test_a_grandchild_that_left_with_setsid_is_killed_too():
    # killpg alone misses it: setsid() gave it a group of its own; the marker in its environment finds it
    t = bad("--setsid-child", "--hang-after", "1", timeout=3.0)  # generous: a busy machine starts it slowly
    child = int(t.properties["test.child_pid"])
    assert os.getsid(child) == child
    t.init(small(), (1, 2, 3, 4))
    with pytest.raises(TraxError, match="killed it"):
        t.update(small())
    assert_gone(t.pid)
    assert_gone(child, zombie_ok=True)


def test_stderr_without_newlines_keeps_the_client_bounded():
    t = bad("--stderr-bytes", str(48 << 20))  # 48 MiB on stderr, no newline
    t.init(small(), (1, 2, 3, 4))
    t.update(small())
    t.close()
    tail = t.stderr_tail
    assert tail and max(len(line) for line in tail) <= (1 << 20) + 64 and "[line cut at 1048576 bytes]" in tail[0]


def test_a_tracker_flooding_state_lines_is_killed_with_a_message():
    t = bad("--flood-after", "1", timeout=5.0)
    t.init(small(), (1, 2, 3, 4))
    # It floods meanwhile; on a busy machine the 64 lines may take a while to pile up,
    # so the updates go on (bounded) until the client refuses the flood.
    deadline = time.monotonic() + 60.0
    with pytest.raises(TraxError, match="sent more than 64 TraX lines nobody asked for"):
        while time.monotonic() < deadline:
            t.update(small())
    assert_gone(t.pid)


def test_a_junk_region_names_the_tracker_and_the_line():
    t = bad("--region", "banana")
    t.init(small(), (1, 2, 3, 4))
    with pytest.raises(TraxError) as e:
        t.update(small())
    assert "trax_misbehaving.py" in str(e.value) and "@@TRAX:state \"banana\"" in str(e.value)
