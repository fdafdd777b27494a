"""Writes the clients' copies of the pixel channel table (protocol/channels.h,
SIM4CV_PIXEL_CHANNELS) for the languages that cannot include it: the Python
package's sim4cv/channel_table.py and the studio's js/channel_table.js.
C++ clients and the MEX include channels.h itself.

    /usr/bin/python3 tools/channel_tables.py          writes both
    /usr/bin/python3 tools/channel_tables.py --check  exits 1 naming any copy that is stale

The architecture test runs --check, so a channel added to channels.h without
running this fails the suite."""
import argparse
import json
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
SOURCE = "protocol/channels.h"
PYTHON = "clients/python/sim4cv/channel_table.py"
JS = "studio/js/channel_table.js"
ELEMENT_BYTES = {"U8": 1, "U16": 2, "F32": 4}
# X(ENUM, "name", FORMAT, ELEMENT, components, "summary")
ROW = re.compile(r'^\s*X\((\w+),\s*"([^"]+)",\s*(\w+),\s*(\w+),\s*(\d+),\s*"((?:[^"\\]|\\.)*)"\)')


def read_table(header_text):
    """[(enum, name, format, element, components, summary)] in the table's order."""
    start = header_text.index("#define SIM4CV_PIXEL_CHANNELS(X)")
    rows = []
    for line in header_text[start:].splitlines()[1:]:
        match = ROW.match(line)
        if not match:
            break
        enum, name, fmt, element, components, summary = match.groups()
        if element not in ELEMENT_BYTES:
            raise ValueError("%s: channel %s has element %s, none of %s" % (SOURCE, name, element, sorted(ELEMENT_BYTES)))
        rows.append((enum, name, fmt, element, int(components), summary))
    if not rows:
        raise ValueError("%s: no X(...) rows under SIM4CV_PIXEL_CHANNELS" % SOURCE)
    return rows


def python_text(rows):
    lines = ['"""The pixel channels, in plane order: generated from %s by' % SOURCE,
             'tools/channel_tables.py; do not edit (the architecture test checks it is current)."""',
             "",
             "# (name, proto Channel name, proto PixelFormat name, element: u8/u16/f32, components, bytes per pixel,",
             "#  what it holds)",
             "PIXEL_CHANNELS = ("]
    for enum, name, fmt, element, components, summary in rows:
        lines.append("    (%s, %s, %s, %s, %d, %d, %s)," % (
            json.dumps(name), json.dumps("CHANNEL_" + enum), json.dumps("PIXEL_FORMAT_" + fmt),
            json.dumps(element.lower()), components, components * ELEMENT_BYTES[element], json.dumps(summary)))
    lines.append(")")
    return "\n".join(lines) + "\n"


def js_text(rows):
    lines = ["// The pixel channels, in plane order: generated from %s by" % SOURCE,
             "// tools/channel_tables.py; do not edit (the architecture test checks it is current).",
             "export const PIXEL_CHANNELS = ["]
    for enum, name, fmt, element, components, summary in rows:
        lines.append("  { name: %s, channel: %s, format: %s, element: %s, components: %d, summary: %s }," % (
            json.dumps(name), json.dumps("CHANNEL_" + enum), json.dumps("PIXEL_FORMAT_" + fmt),
            json.dumps(element.lower()), components, json.dumps(summary)))
    lines.append("];")
    return "\n".join(lines) + "\n"


def outputs(root=ROOT):
    rows = read_table((root / SOURCE).read_text())
    return {PYTHON: python_text(rows), JS: js_text(rows)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if a copy is stale")
    parser.add_argument("--root", default=str(ROOT), help="the repository (default: this one)")
    args = parser.parse_args(argv)
    root = pathlib.Path(args.root)
    stale = []
    for path, text in outputs(root).items():
        current = (root / path).read_text() if (root / path).exists() else None
        if current == text:
            continue
        stale.append(path)
        if not args.check:
            (root / path).write_text(text)
    if args.check and stale:
        print("stale copies of %s: %s; run /usr/bin/python3 tools/channel_tables.py"
              % (SOURCE, ", ".join(stale)), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
