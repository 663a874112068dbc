"""Load time and peak memory of XML scenes in pathwave and in Mitsuba 3, run by hand.

    python benches/load/load_cost.py --pathwave target/release/pathwave [--reps 11] SCENE.xml [...]

with a Python that imports `mitsuba` (3.x). For each scene, each repetition runs a fresh process
of each renderer, alternating (so that a change in the machine's load falls on both), and prints
a markdown row per renderer with the median wall time, its spread (least and most) and the
median peak resident set size:
- pathwave: `render --width 1 --height 1 --spp 1` (parse, meshes and textures read, BVHs
  and light table built, one sample), the whole process, timed from outside; its peak RSS is
  the process's own (`wait4`);
- Mitsuba: `mi.load_file` in the `scalar_rgb` variant (parse, shapes and BVH built), timed
  inside a process that has already imported Mitsuba; its peak RSS is the whole process's, and
  its peak minus the RSS after the import is reported beside it.
With `--json FILE` every run is also written there, one object a line.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

MITSUBA = r"""
import json, resource, sys, time
import mitsuba as mi
mi.set_variant('scalar_rgb')
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t = time.perf_counter()
scene = mi.load_file(sys.argv[1])
dt = time.perf_counter() - t
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"time": dt, "peak_kb": peak, "base_kb": base}))
"""


def pathwave(binary: str, scene: str) -> dict:
    """One run of pathwave: wall time and the peak RSS of that process alone."""
    with tempfile.TemporaryDirectory() as d:
        args = [binary, "render", scene, "--width", "1", "--height", "1", "--spp", "1"]
        args += ["-q", "-o", str(Path(d) / "x.exr")]
        t = time.perf_counter()
        p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        _, status, usage = os.wait4(p.pid, 0)
        dt = time.perf_counter() - t
        p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        raise SystemExit(f"pathwave exited {p.returncode} on {scene}")
    return {"time": dt, "peak_kb": usage.ru_maxrss}


def mitsuba(scene: str) -> dict:
    out = subprocess.run([sys.executable, "-c", MITSUBA, scene], check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def row(name: str, renderer: str, runs: list, note: str) -> str:
    times = [r["time"] for r in runs]
    peak = statistics.median(r["peak_kb"] for r in runs) / 1024
    return (
        f"| {name} | {renderer} | {statistics.median(times):.3f} | {min(times):.3f}-{max(times):.3f} "
        f"| {peak:.0f} | {note} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pathwave", required=True)
    ap.add_argument("--reps", type=int, default=11)
    ap.add_argument("--json", help="write every run here, one object a line")
    ap.add_argument("scenes", nargs="+")
    a = ap.parse_args()
    log = open(a.json, "a") if a.json else None
    print("| scene | renderer | load s (median) | spread s | peak RSS MB (median) | note |")
    print("|---|---|---|---|---|---|")
    for s in a.scenes:
        name = Path(s).parent.name
        mi_runs, pw_runs = [], []
        for rep in range(a.reps):
            mi_runs.append(mitsuba(s))
            pw_runs.append(pathwave(a.pathwave, s))
            if log:
                for renderer, r in (("mitsuba", mi_runs[-1]), ("pathwave", pw_runs[-1])):
                    log.write(json.dumps({"scene": name, "renderer": renderer, "rep": rep, **r}) + "\n")
                log.flush()
        extra = statistics.median(r["peak_kb"] - r["base_kb"] for r in mi_runs) / 1024
        print(row(name, "Mitsuba 3", mi_runs, f"load_file; {extra:.0f} MB above the import"), flush=True)
        print(row(name, "pathwave", pw_runs, "whole process, 1x1 render at 1 spp"), flush=True)


if __name__ == "__main__":
    main()
