#!/usr/bin/env python3
"""Draws a time window of a `pathwave render --trace` file as an SVG timeline, the way a trace
viewer (ui.perfetto.dev) lays it out: one row per thread with its tiles and, inside each tile,
its stages; the queue-occupancy counter below. Standard library only.

    python3 docs/trace_timeline.py trace.json out.svg [--from MS] [--ms SPAN]
"""

import argparse
import json
import os

COLOURS = {
    "generate_camera_rays": "#4e79a7",
    "intersect_closest": "#f28e2b",
    "record_guides": "#9c755f",
    "handle_escaped": "#76b7b2",
    "handle_emissive": "#edc948",
    "shade_medium": "#bab0ac",
    "trace_shadow_rays": "#e15759",
    "accumulate_film": "#59a14f",
}
SHADE = ["#b07aa1", "#ff9da7", "#d37295", "#a0cbe8"]


def colour(name, shade_names):
    if name in COLOURS:
        return COLOURS[name]
    if name not in shade_names:
        shade_names.append(name)
    return SHADE[shade_names.index(name) % len(SHADE)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("trace")
    ap.add_argument("svg")
    ap.add_argument("--from", dest="start", type=float, default=None, help="window start, ms (default: the first tile)")
    ap.add_argument("--ms", type=float, default=20.0, help="window length, ms")
    a = ap.parse_args()
    events = json.load(open(a.trace))["traceEvents"]
    tiles = [e for e in events if e.get("name") == "tile"]
    if not tiles:
        raise SystemExit(f"{a.trace}: no tile spans (was it written by pathwave render --trace?)")
    t0 = a.start * 1000 if a.start is not None else min(e["ts"] for e in tiles)
    t1 = t0 + a.ms * 1000
    width, left, row_h = 1000, 120, 46
    threads = sorted({e["tid"] for e in tiles})
    x = lambda ts: left + (min(max(ts, t0), t1) - t0) / (t1 - t0) * (width - left - 10)
    stages = [e for e in events if e.get("ph") == "X" and "items" in e.get("args", {})]
    counter = sorted((e["ts"], e["args"]["value"]) for e in events if e.get("ph") == "C" and e["name"] == "queue occupancy %")
    height = 40 + row_h * len(threads) + 110
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" font-size="11">',
           f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="10" y="18" font-size="13">{os.path.basename(a.trace)}: {a.ms:g} ms from {t0 / 1000:.1f} ms</text>']
    shade_names = []
    for row, tid in enumerate(threads):
        y = 30 + row * row_h
        out.append(f'<text x="10" y="{y + 26}">thread {tid}</text>')
        for e in tiles:
            if e["tid"] != tid or e["ts"] + e["dur"] < t0 or e["ts"] > t1:
                continue
            out.append(f'<rect x="{x(e["ts"]):.1f}" y="{y}" width="{max(x(e["ts"] + e["dur"]) - x(e["ts"]), 0.5):.1f}" height="14" fill="#ddd" stroke="#888"/>')
        for e in stages:
            if e["tid"] != tid or e["ts"] + e["dur"] < t0 or e["ts"] > t1:
                continue
            w = max(x(e["ts"] + e["dur"]) - x(e["ts"]), 0.3)
            out.append(f'<rect x="{x(e["ts"]):.1f}" y="{y + 16}" width="{w:.1f}" height="20" fill="{colour(e["name"], shade_names)}"><title>{e["name"]}: {e["dur"]:.0f} us, {e["args"]["items"]} items</title></rect>')
    y = 40 + row_h * len(threads)
    out.append(f'<text x="10" y="{y + 30}">queue occupancy</text>')
    pts = [(x(ts), y + 45 - v * 0.4) for ts, v in counter if t0 <= ts <= t1]
    if pts:
        out.append('<polyline fill="none" stroke="#333" points="' + " ".join(f"{px:.1f},{py:.1f}" for px, py in pts) + '"/>')
    names = [n for n in COLOURS if any(e["name"] == n for e in stages)] + shade_names
    for i, n in enumerate(names):
        lx, ly = left + (i % 5) * 175, y + 65 + (i // 5) * 16
        out.append(f'<rect x="{lx}" y="{ly - 9}" width="10" height="10" fill="{colour(n, shade_names)}"/><text x="{lx + 14}" y="{ly}">{n}</text>')
    out.append("</svg>")
    open(a.svg, "w").write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
