"""Octave trackers through TraX: "octave:FILE.m" runs FILE.m's tracker under
clients/matlab/trax/sim4cv_trax_server.m, a TraX server in Octave, driven
by sim4cv.trax.TraxTracker. The MOSSE tracker (clients/matlab/trax/mosse.m)
tracks the textured square of test_trax.py; a tracker's errors, bad
contracts and missing files end the session with a TraxError that names
them, never a hang. Needs GNU Octave (skipped without it); about 15 s."""

import os
import shlex
import shutil
import time

import numpy as np
import pytest

from conftest import REPO_ROOT
from test_trax import assert_gone, scene, track

from sim4cv.trax import (OCTAVE_SERVER_DIR, TraxError, TraxTracker, octave_command, open_tracker,
                         parse_tracker_spec)

pytestmark = pytest.mark.skipif(shutil.which("octave") is None, reason="GNU Octave is not installed")

MOSSE = os.path.join(REPO_ROOT, "clients", "matlab", "trax", "mosse.m")


def write_tracker(tmp_path, name, init_body="state = box;", update_body="box = state;", extra=""):
    """tmp_path/NAME.m: a tracker whose init and update run the given lines."""
    path = tmp_path / (name + ".m")
    path.write_text("""function tracker = %(name)s()
  tracker.init = @my_init;
  tracker.update = @my_update;
end
function state = my_init(image, box)
  %(init)s
end
function [state, box] = my_update(state, image)
  %(update)s
end
%(extra)s
""" % {"name": name, "init": init_body, "update": update_body, "extra": extra})
    return str(path)


def small():
    return np.zeros((16, 16, 3), np.uint8)


# --- the specification ------------------------------------------------------------------------

def test_spec_becomes_the_octave_command_line(tmp_path, monkeypatch):
    monkeypatch.chdir(REPO_ROOT)
    line = parse_tracker_spec("octave:clients/matlab/trax/mosse.m")
    assert line == ('octave --no-gui --no-window-system --quiet --no-history --eval '
                    '"addpath(\'%s\'); sim4cv_trax_server(\'%s\')"' % (OCTAVE_SERVER_DIR, MOSSE))
    assert OCTAVE_SERVER_DIR == os.path.join(REPO_ROOT, "clients", "matlab", "trax")
    # quotes in the path survive shlex and Octave's '' escaping
    odd = tmp_path / "it's \"odd\""
    odd.mkdir()
    path = write_tracker(odd, "odd_tracker")
    assert "sim4cv_trax_server('%s')" % path.replace("'", "''") in shlex.split(octave_command(path))[-1]
    with TraxTracker(octave_command(path)) as t:
        t.init(small(), (1, 2, 3, 4))
        assert t.update(small()) == (1, 2, 3, 4)
    for spec in ("octave:", "octave:tracker.py", "octave:.m"):
        with pytest.raises(ValueError, match="octave:FILE.m"):
            parse_tracker_spec(spec)


def test_missing_file_is_a_clear_error(tmp_path):
    missing = str(tmp_path / "no_such_tracker.m")
    with pytest.raises(TraxError, match=r"Octave tracker file .*no_such_tracker\.m does not exist"):
        open_tracker("octave:" + missing)
    # the server says the same if the file goes away before Octave starts
    path = write_tracker(tmp_path, "gone_tracker")
    line = octave_command(path)
    os.unlink(path)
    with pytest.raises(TraxError, match=r"quit the session: the Octave tracker file .*gone_tracker\.m "
                                        r"does not exist") as e:
        TraxTracker(line, timeout=20)
    assert "TraX tracker octave" in str(e.value)


# --- MOSSE -------------------------------------------------------------------------------------

def test_mosse_tracks_the_square_in_memory_images(monkeypatch):
    monkeypatch.chdir(REPO_ROOT)
    with open_tracker("octave:clients/matlab/trax/mosse.m", timeout=20) as t:
        pid = t.pid
        assert t.name == "mosse" and t.version == 1
        assert t.image_format == "memory" and t.region_format == "rectangle"
        times, tracker_times = [], []
        worst = 0.0
        for i, (image, truth) in enumerate(scene(n=40)):
            if i == 0:
                t.init(image, truth)
                continue
            box = t.update(image)
            times.append(t.elapsed)
            tracker_times.append(float(t.state_properties["octave.time"]))
            worst = max([worst] + [abs(a - b) for a, b in zip(box, truth)])
        assert worst <= 2.0
        print("octave MOSSE through TraX, memory: %.1f ms per update (median), %.1f ms of it in update"
              % (1000 * np.median(times), 1000 * np.median(tracker_times)))
        # re-initialisation on another target
        assert track(t, scene(n=8, step=(-2, 3), seed=3)) <= 2.0
    assert_gone(pid)


def test_mosse_tracks_in_path_images():
    pytest.importorskip("cv2")
    with TraxTracker(octave_command(MOSSE), timeout=20, image_format="path") as t:
        assert t.image_format == "path"
        assert track(t, scene(n=15)) <= 2.0


# --- the tracker's failures ------------------------------------------------------------------------

def test_error_in_update_names_the_octave_error(tmp_path):
    path = write_tracker(tmp_path, "exploding_tracker", init_body="state = struct('box', box, 'n', 1);",
                         update_body="state.n = state.n + 1;\n"
                                     "  if state.n == 3, error('exploding:boom', 'the filter exploded at frame %d', "
                                     "state.n); end\n  box = state.box;")
    t = open_tracker("octave:" + path, timeout=20)
    t.init(small(), (1, 2, 3, 4))
    assert t.update(small()) == (1, 2, 3, 4)
    start = time.monotonic()
    with pytest.raises(TraxError, match=r"quit the session: exploding_tracker update failed: the filter exploded "
                                        r"at frame 3 \(in exploding_tracker>my_update at line 10\)"):
        t.update(small())
    assert time.monotonic() - start < 19                  # the server said so: not the 20 s timeout
    assert_gone(t.pid)
    with pytest.raises(TraxError, match="is gone"):
        t.update(small())


def test_error_in_init_and_in_the_constructor_and_a_syntax_error(tmp_path):
    path = write_tracker(tmp_path, "bad_init", init_body="state = undefined_thing + 1;")
    with pytest.raises(TraxError, match=r"quit the session: bad_init init failed: .*undefined_thing"):
        with open_tracker("octave:" + path, timeout=20) as t:
            t.init(small(), (1, 2, 3, 4))
    path = tmp_path / "bad_ctor.m"
    path.write_text("function tracker = bad_ctor()\n  error('cannot load the model weights');\nend\n")
    with pytest.raises(TraxError, match=r"quit the session: bad_ctor\(\) failed: cannot load the model weights"):
        open_tracker("octave:" + str(path), timeout=20)
    path = tmp_path / "bad_syntax.m"
    path.write_text("function tracker = bad_syntax()\n  tracker = struct('init', @(i, b) b;\nend\n")
    with pytest.raises(TraxError, match=r"quit the session: parse error near line 2 of file .*bad_syntax\.m"):
        open_tracker("octave:" + str(path), timeout=20)


def test_bad_contracts(tmp_path):
    path = tmp_path / "not_a_struct.m"
    path.write_text("function tracker = not_a_struct()\n  tracker = 42;\nend\n")
    with pytest.raises(TraxError, match=r"not_a_struct\(\) must return a struct with the function handles init "
                                        r".* it returned a double"):
        open_tracker("octave:" + str(path), timeout=20)
    path = write_tracker(tmp_path, "bad_box", update_body="box = 'left';")
    with pytest.raises(TraxError, match=r"bad_box: update returned a \[1 4\] char, not a box"):
        with open_tracker("octave:" + path, timeout=20) as t:
            t.init(small(), (1, 2, 3, 4))
            t.update(small())


def test_printing_does_not_break_the_protocol_and_no_box_is_none(tmp_path):
    path = write_tracker(tmp_path, "chatty_tracker",
                         init_body="printf('no newline, '); disp('init'); fprintf(1, '@@TRAX:state \"9,9,9,9\"'); "
                                   "fputs(stdout, 'x'); state = box; image(1)",
                         update_body="printf('updating'); box = [];",
                         extra="% a comment at the end")
    with open_tracker("octave:" + path, timeout=20) as t:
        t.init(small(), (1, 2, 3, 4))
        assert t.state_properties.get("octave.time") is not None
        assert t.update(small()) is None                    # [] is a special region
        assert t.update(small()) is None
    # what it printed went to stderr (captured with evalc)
    text = "\n".join(t.stderr_tail)
    assert "no newline, init" in text and "updating" in text and "ans = 0" in text


def test_name_field_and_gray_images(tmp_path):
    path = tmp_path / "send.m"                          # as a function of sim4cv_trax_server.m: not confused
    path.write_text("function t = send()\n  t.name = 'my tracker';\n  t.init = @(image, box) size(image);\n"
                    "  t.update = @upd;\nend\n"
                    "function [s, box] = upd(s, image)\n"
                    "  if ~isequal(size(image), s) || ~isa(image, 'uint8'), error('bad image'); end\n"
                    "  box = [double(image(2, 3, 1)) double(image(2, 3, 3)) 1 1];\nend\n")
    with open_tracker("octave:" + str(path), timeout=20) as t:
        assert t.name == "my tracker"
        rgb = np.zeros((5, 7, 3), np.uint8)
        rgb[1, 2] = (10, 20, 30)
        t.init(rgb, (0, 0, 2, 2))
        assert t.update(rgb) == (10, 30, 1, 1)              # row 2, column 3 in Octave; R then B
        gray = np.zeros((5, 7), np.uint8)
        gray[1, 2] = 77
        assert t.update(gray) == (77, 77, 1, 1)             # gray8 arrives as three equal channels


def test_tracker_specifications_take_octave_files(monkeypatch):
    from sim4cv.trackers import make_tracker
    monkeypatch.chdir(REPO_ROOT)
    with make_tracker("octave:clients/matlab/trax/mosse.m") as t:
        frames = list(scene(n=6))
        t.init(frames[0][0], frames[0][1])
        for image, truth in frames[1:]:
            box = t.update(image)
            assert max(abs(a - b) for a, b in zip(box, truth)) <= 2.0


def test_docs_example_tracker(tmp_path):
    """The ssd_tracker block of docs/trax.md, "Octave trackers", as written."""
    with open(os.path.join(REPO_ROOT, "docs", "trax.md")) as f:
        text = f.read().split("## Octave trackers", 1)[1]
    block = text.split("```matlab\n", 1)[1].split("```", 1)[0]
    assert block.startswith("function tracker = ssd_tracker()")
    path = tmp_path / "ssd_tracker.m"
    path.write_text(block)
    with open_tracker("octave:" + str(path), timeout=20) as t:
        assert t.name == "ssd"
        assert track(t, scene(n=12)) <= 2.0
