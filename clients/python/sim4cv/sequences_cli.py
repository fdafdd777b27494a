"""The command line of sim4cv.sequences (`python3 -m sim4cv.sequences ...`,
its module docstring has the synopsis): generate, attributes, maps, stats,
export, export-results."""

import argparse
import os
import sys

from .sequences import (CAMERA_MOTIONS, CONDITIONS, EXTRA_CHANNELS, MAPS_DIR, SequenceError, Spec, _write_json,
                        generate, map_name, paper_specs, recompute_attributes, shipped_tracking_maps)


def _csv_list(text):
    return [s.strip() for s in text.split(",") if s.strip()]


def parse_args(argv):
    p = argparse.ArgumentParser(prog="python3 -m sim4cv.sequences",
                                description="Synthetic UAV tracking sequences (OTB/UAV123 format) with attributes; "
                                            "docs/tracking.md, 'Sequences and attributes'.")
    sub = p.add_subparsers(dest="command", required=True)
    g = sub.add_parser("generate", help="generate sequences")
    g.add_argument("--out", required=True, help="root folder: OUT/<seq>/..., OUT/attribute_names.txt")
    g.add_argument("--maps", help="comma-separated maps, e.g. tracking/easy_urban,hard_urban (default: all of "
                                  "scenes/tracking)")
    g.add_argument("--speeds", default="4,6,8", help="comma-separated car speeds in m/s (default 4,6,8)")
    length = g.add_mutually_exclusive_group()
    length.add_argument("--frames", type=int, help="frames per sequence")
    length.add_argument("--laps", type=int, help="whole laps of the route per sequence (default 1)")
    g.add_argument("--preset", choices=("paper",), help="paper: the 5-sequence offline set (maps, speeds and laps "
                                                         "fixed; --maps/--speeds/--frames/--laps not allowed)")
    g.add_argument("--conditions", choices=CONDITIONS, help="weather / time of day of the RGB (default: the "
                                                            "daemon's, clear_noon)")
    g.add_argument("--channels", default="", help="extra channels saved per frame: %s" % ",".join(EXTRA_CHANNELS))
    g.add_argument("--quality", choices=("full", "fast"), help="render quality (default: the daemon's, full)")
    g.add_argument("--traffic-cars", type=int, default=0, help="other cars driving on the map (SOB)")
    g.add_argument("--seed", type=int, default=1, help="the daemon's --seed (own daemons) and the pilot's (default 1)")
    g.add_argument("--camera-motion", choices=CAMERA_MOTIONS, default="pilot",
                   help="pilot (default): sim4cv.pilot flies the camera; servo: the map's UAV follows the car")
    g.add_argument("--daemon", help="ADDRESS (tcp://HOST:PORT) of a running lockstep sim4cvd to use instead of "
                                    "starting one per sequence; it loads each map")
    g.add_argument("--jobs", type=int, default=1, help="sequences generated at once, each with its own daemon")
    a = sub.add_parser("attributes", help="recompute the attribute files of generated sequences")
    a.add_argument("--out", required=True)
    sub.add_parser("maps", help="list the shipped tracking maps")
    st = sub.add_parser("stats", help="camera-motion statistics of a sequence set (sim4cv.sequence_stats)")
    st.add_argument("dir")
    st.add_argument("--json", help="also write the statistics (with per-sequence figures) to this file")
    e = sub.add_parser("export", help="the sequences in UAV123's, GOT-10k's or OTB's layout (1-based boxes)")
    e.add_argument("dir")
    e.add_argument("--format", required=True, choices=("uav123", "got10k", "otb"))
    e.add_argument("--out", required=True)
    r = sub.add_parser("export-results", help="tracker results (RESULTS/<tracker>/<seq>.txt) in got10k's or "
                                              "pytracking's layout (1-based boxes, time files)")
    r.add_argument("results")
    r.add_argument("--layout", required=True, choices=("got10k", "pytracking"))
    r.add_argument("--out", required=True)
    return p, p.parse_args(argv)


def specs_from_args(p, args):
    channels = _csv_list(args.channels)
    bad = [c for c in channels if c not in EXTRA_CHANNELS]
    if bad:
        p.error("--channels: unknown %s (choose from %s)" % (", ".join(bad), ",".join(EXTRA_CHANNELS)))
    if args.preset == "paper":
        if args.maps or args.frames or args.laps or args.speeds != "4,6,8":
            p.error("--preset paper fixes the maps, speeds and lengths")
        specs = paper_specs(args.conditions, channels, args.seed)
        for s in specs:
            s.quality, s.traffic_cars, s.camera_motion = args.quality, args.traffic_cars, args.camera_motion
        return specs
    maps = [map_name(m) for m in _csv_list(args.maps)] if args.maps else shipped_tracking_maps()
    for m in maps:
        if args.daemon is None and not os.path.exists(os.path.join(MAPS_DIR, m + ".map")):
            p.error("--maps: no map %s (shipped: %s)" % (m, ", ".join(shipped_tracking_maps())))
    try:
        speeds = [float(s) for s in _csv_list(args.speeds)]
    except ValueError:
        p.error("--speeds: expected comma-separated numbers, got %r" % args.speeds)
    if not speeds or any(not 0.1 <= s <= 40 for s in speeds):
        p.error("--speeds: each speed must be in [0.1, 40] m/s")
    if args.frames is not None and args.frames < 1 or args.laps is not None and args.laps < 1:
        p.error("--frames / --laps must be at least 1")
    frames, laps = (args.frames, 0) if args.frames else (0, args.laps or 1)
    return [Spec(m, s, frames=frames, laps=laps, conditions=args.conditions, channels=channels, seed=args.seed,
                 quality=args.quality, traffic_cars=args.traffic_cars, camera_motion=args.camera_motion)
            for m in maps for s in speeds]


def _inspect_or_export(args):
    from . import sequence_export, sequence_stats
    try:
        if args.command == "stats":
            stats = sequence_stats.set_statistics(args.dir)
            print(sequence_stats.markdown(stats))
            if args.json:
                _write_json(args.json, stats)
        elif args.command == "export":
            sequence_export.export(args.dir, args.format, args.out)
            print("wrote %s (%s layout)" % (args.out, args.format))
        else:
            names = sequence_export.export_results(args.results, args.layout, args.out)
            print("wrote %s (%s layout): %s" % (args.out, args.layout, ", ".join(names)))
    except (sequence_export.ExportError, OSError, ValueError, KeyError) as e:
        print("sim4cv.sequences: error: %s" % e, file=sys.stderr)
        return 1
    return 0


def main(argv=None):
    p, args = parse_args(sys.argv[1:] if argv is None else argv)
    if args.command == "maps":
        for m in shipped_tracking_maps():
            print(m)
        return 0
    if args.command == "attributes":
        recompute_attributes(args.out)
        return 0
    if args.command in ("stats", "export", "export-results"):
        return _inspect_or_export(args)
    specs = specs_from_args(p, args)
    if args.jobs < 1:
        p.error("--jobs must be at least 1")
    try:
        generate(specs, args.out, daemon=args.daemon, jobs=args.jobs)
    except SequenceError as e:
        print("sim4cv.sequences: error: %s" % e, file=sys.stderr)
        return 1
    return 0


