"""docs/architecture.md, "Extending sim4cv": each worked example adds its
thing as one file plus one registration line. Here: the example's name
occurs in its file and on exactly one line of the registering file, nowhere
else in the code it extends, and the section quotes that line as it is.
(That each example works is shown by its own test, named in the section.)"""
import pathlib
import re

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
    ("Configure request", "kGetWorld", "server/daemon/configure/get_world.cpp",
     "server/daemon/configure_requests.cpp", "X(kGetWorld)"),
]
# C++ names a function of another file by declaring it: that line is no registration.
DECLARATIONS = {"std::unique_ptr<transport::Transport> MakeSeqpacketTransport(const daemon::Config&, const sim::Scene&);"}


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
