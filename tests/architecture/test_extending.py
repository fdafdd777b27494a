"""docs/architecture.md, "Extending sim4cv": each worked example adds its
thing as one file plus one registration line. Here: the example's name
occurs in its file and on exactly one line of the registering file, nowhere
else in the code it extends, and the section quotes that line as it is.
(That each example works is shown by its own test, named in the section.)"""
import json
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CODE = ("server", "protocol", "clients", "studio", "tools", "tests", "fuzz")
SKIPPED = {"sim4cv_pb2.py"}  # generated from the proto

# (what, the name the example is known by (a regular expression), its one file, the registering file,
#  the registration line, the other places that may name it)
EXAMPLES = [
    ("tracker kind", r"\bcolour_tracker_kind\b", "tests/python/extending/colour_tracker_kind.py",
     "tests/python/test_extending_tracker_kind.py", 'trackers.register_tracker_kind("colour", "colour_tracker_kind")',
     ()),
    ("transport", r"\bMakeSeqpacketTransport\b", "tests/extending/seqpacket_transport.cpp",
     "tests/extending/extending_transport_test.cpp",
     'daemon::RegisterTransport({"seqpacket", demo::MakeSeqpacketTransport});', ()),
    ("entity kind", r"\bkBeacon\b", "tests/extending/beacon_kind.cpp", "tests/extending/extending_entity_kind_test.cpp",
     "sim::RegisterEntityKind(demo::kBeacon);", ()),
    ("Configure request", r"\bkGetWorld\b", "server/daemon/configure/get_world.cpp",
     "server/daemon/configure_requests.cpp", "X(kGetWorld)", ()),
    # A shipped channel: its enum, proto value or flag name. The proto's value is the protocol's own
    # registration (counted apart below); the table's copies for Python and the studio are generated from
    # channels.h; tests may name it.
    ("pixel channel", r'\b(?:CHANNEL_)?ALBEDO\b|"albedo"', "server/render/channels/albedo.cpp", "protocol/channels.h",
     'X(ALBEDO, "albedo", RGB8, U8, 3, ',
     ("protocol/sim4cv.proto", "clients/python/sim4cv/channel_table.py", "studio/js/channel_table.js", "tests/")),
]
# C++ names a function of another file by declaring it: that line is no registration.
DECLARATIONS = {"std::unique_ptr<transport::Transport> MakeSeqpacketTransport(const daemon::Config&, const sim::Scene&);",
                "extern const sim::EntityKindEntry kBeacon;"}


def files_naming(pattern):
    """{path: [lines]} of the code files with a line matching the regular expression `pattern`."""
    pattern = re.compile(pattern)
    found = {}
    for top in CODE:
        for path in (ROOT / top).rglob("*"):
            if not path.is_file() or path.name in SKIPPED or path == pathlib.Path(__file__).resolve() or path.suffix not in {".cpp", ".h", ".py", ".js", ".m",
                                                                                 ".proto", ".cmake", ".txt"}:
                continue
            lines = [line for line in path.read_text(errors="replace").splitlines() if pattern.search(line)]
            if lines:
                found[str(path.relative_to(ROOT))] = lines
    return found


def extending_section():
    text = (ROOT / "docs" / "architecture.md").read_text()
    start = text.index("\n## Extending sim4cv\n")
    end = text.find("\n## ", start + 1)
    return text[start:end if end > 0 else len(text)]


@pytest.mark.parametrize("what, name, example, registry, line, also", EXAMPLES, ids=[e[0] for e in EXAMPLES])
def test_the_example_is_one_file_plus_one_registration_line(what, name, example, registry, line, also):
    found = files_naming(name)
    elsewhere = sorted(path for path in found if path not in (example, registry) and not path.startswith(also))
    assert {example, registry} <= set(found) and not elsewhere, "%s %s: named in %s" % (what, name, sorted(found))
    code = [l.strip() for l in found[registry] if not l.strip().startswith(("//", "#", "\"\"\""))]
    registering = [l for l in code if l not in DECLARATIONS]
    assert len(registering) == 1 and registering[0].startswith(line), found[registry]


@pytest.mark.parametrize("what, name, example, registry, line, also", EXAMPLES, ids=[e[0] for e in EXAMPLES])
def test_the_architecture_document_gives_the_recipe(what, name, example, registry, line, also):
    section = extending_section()
    assert example in section and line in section, "%s: docs/architecture.md, Extending sim4cv" % what


# --- a pixel channel -------------------------------------------------------------------------------
# Its registration line is its row in protocol/channels.h; C++ (the daemon, the C++ client, the MEX)
# reads the table there, and tools/channel_tables.py copies it for Python and the studio. The albedo
# channel is drawn end to end by the daemon in tests/python/test_albedo.py.


def test_the_channel_has_one_proto_value():
    lines = [l.strip() for l in files_naming(r"\bCHANNEL_ALBEDO\b")["protocol/sim4cv.proto"]]
    assert lines == ["CHANNEL_ALBEDO = 8;"]


def test_the_clients_copies_of_the_channel_table_are_current():
    sys.path.insert(0, str(ROOT / "tools"))
    import channel_tables
    assert channel_tables.main(["--check"]) == 0, "run /usr/bin/python3 tools/channel_tables.py"


def test_the_studio_lists_the_channel_and_draws_it_in_colour():
    """The studio's channel menu and canvas follow the table: albedo is listed, and drawn as the colour it
    is (its row says RGB8) with no line of the studio naming it."""
    script = """
      import("%s").then((colours) => {
        const out = new Uint8ClampedArray(4 * 2);
        colours.toRgba("CHANNEL_ALBEDO", new Uint8Array([10, 20, 30, 40, 50, 60]), out);
        console.log(JSON.stringify({ channels: colours.CHANNELS, pixels: Array.from(out) }));
      });""" % (ROOT / "studio" / "js" / "colours.js")
    shown = json.loads(subprocess.run(["node", "--input-type=module", "-e", script], capture_output=True, text=True,
                                      check=True).stdout)
    assert {"name": "albedo", "label": "albedo", "channel": "CHANNEL_ALBEDO"} in shown["channels"]
    assert shown["pixels"] == [10, 20, 30, 255, 40, 50, 60, 255]
