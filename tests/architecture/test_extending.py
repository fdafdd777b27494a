"""docs/architecture.md, "Extending sim4cv": each worked example adds its
thing as one file plus one registration line. Here: the example's name
occurs in its file and on exactly one line of the registering file, nowhere
else in the code it extends, and the section quotes that line as it is.
(That each example works is shown by its own test, named in the section.)"""
import json
import pathlib
import re
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
CODE = ("server", "protocol", "clients", "studio", "tools", "tests", "fuzz")
SKIPPED = {"sim4cv_pb2.py"}  # generated from the proto

# (what, the name the example is known by, its one file, the registering file, the registration line)
EXAMPLES = [
    ("tracker kind", "colour_tracker_kind", "tests/python/extending/colour_tracker_kind.py",
     "tests/python/test_extending_tracker_kind.py", 'trackers.register_tracker_kind("colour", "colour_tracker_kind")'),
    ("transport", "MakeSeqpacketTransport", "tests/extending/seqpacket_transport.cpp",
     "tests/extending/extending_transport_test.cpp",
     'daemon::RegisterTransport({"seqpacket", demo::MakeSeqpacketTransport});'),
    ("entity kind", "kBeacon", "tests/extending/beacon_kind.cpp", "tests/extending/extending_entity_kind_test.cpp",
     "sim::RegisterEntityKind(demo::kBeacon);"),
    ("Configure request", "kGetWorld", "server/daemon/configure/get_world.cpp",
     "server/daemon/configure_requests.cpp", "X(kGetWorld)"),
]
# C++ names a function of another file by declaring it: that line is no registration.
DECLARATIONS = {"std::unique_ptr<transport::Transport> MakeSeqpacketTransport(const daemon::Config&, const sim::Scene&);",
                "extern const sim::EntityKindEntry kBeacon;"}


def files_naming(word):
    """{path: [lines]} of the code files whose text holds `word` as a whole word."""
    pattern = re.compile(r"\b%s\b" % re.escape(word))
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


@pytest.mark.parametrize("what, name, example, registry, line", EXAMPLES, ids=[e[0] for e in EXAMPLES])
def test_the_example_is_one_file_plus_one_registration_line(what, name, example, registry, line):
    found = files_naming(name)
    assert set(found) == {example, registry}, "%s %s: named in %s" % (what, name, sorted(found))
    code = [l.strip() for l in found[registry] if not l.strip().startswith(("//", "#", "\"\"\""))]
    registering = [l for l in code if l not in DECLARATIONS]
    assert len(registering) == 1 and registering[0].startswith(line), found[registry]


@pytest.mark.parametrize("what, name, example, registry, line", EXAMPLES, ids=[e[0] for e in EXAMPLES])
def test_the_architecture_document_gives_the_recipe(what, name, example, registry, line):
    section = extending_section()
    assert example in section and line in section, "%s: docs/architecture.md, Extending sim4cv" % what


# --- a pixel channel -------------------------------------------------------------------------------
# Its registration line is its row in protocol/channels.h; C++ (the daemon, the C++ client, the MEX)
# reads the table there, and tools/channel_tables.py copies it for Python and the studio.
DEMO_CHANNEL = 'X(ALBEDO, "albedo", RGB8, U8, 3, "surface colour before any light")'


def test_the_clients_copies_of_the_channel_table_are_current():
    sys.path.insert(0, str(ROOT / "tools"))
    import channel_tables
    assert channel_tables.main(["--check"]) == 0, "run /usr/bin/python3 tools/channel_tables.py"


def test_a_channel_row_reaches_python_and_the_studio(tmp_path):
    """The worked example's row, added to a copy of channels.h, is in the copies the generator writes,
    and the studio lists it and draws it (grey, having no colour map of its own) with no other edit."""
    header = (ROOT / "protocol" / "channels.h").read_text()
    last_row = re.findall(r'^  X\(FLOW, .*$', header, re.M)[0]
    (tmp_path / "protocol").mkdir()
    (tmp_path / "protocol" / "channels.h").write_text(
        header.replace(last_row, last_row.rstrip(" \\") + " \\\n  " + DEMO_CHANNEL))
    (tmp_path / "clients" / "python" / "sim4cv").mkdir(parents=True)
    shutil.copytree(ROOT / "studio" / "js", tmp_path / "studio" / "js")
    assert subprocess.run([sys.executable, str(ROOT / "tools" / "channel_tables.py"), "--root", str(tmp_path)]).returncode == 0

    table = {}
    exec((tmp_path / "clients" / "python" / "sim4cv" / "channel_table.py").read_text(), table)
    assert table["PIXEL_CHANNELS"][-1] == ("albedo", "CHANNEL_ALBEDO", "PIXEL_FORMAT_RGB8", "u8", 3, 3,
                                           "surface colour before any light")
    script = """
      import("%s").then((colours) => {
        const out = new Uint8ClampedArray(4 * 2);
        colours.toRgba("CHANNEL_ALBEDO", new Uint8Array([10, 0, 0, 30, 0, 0]), out);
        console.log(JSON.stringify({ channels: colours.CHANNELS, pixels: Array.from(out) }));
      });""" % (tmp_path / "studio" / "js" / "colours.js")
    shown = json.loads(subprocess.run(["node", "--input-type=module", "-e", script], capture_output=True, text=True,
                                      check=True).stdout)
    assert shown["channels"][-1] == {"name": "albedo", "label": "albedo", "channel": "CHANNEL_ALBEDO"}
    assert shown["pixels"] == [0, 0, 0, 255, 255, 255, 255, 255]
