"""Load time and peak memory of XML scenes in pathwave and in Mitsuba 3, run by hand.

    python benches/load/load_cost.py --pathwave target/release/pathwave SCENE.xml [...]

with a Python that imports `mitsuba` (3.x). For each scene and renderer it runs a fresh process
three times and prints a markdown row with the shortest wall time (the machine is shared; the best run is the least disturbed) and the largest peak resident
set size:
- pathwave: `render --width 1 --height 1 --spp 1` (parse, meshes and textures read, BVHs and
  light table built, one sample), the whole process;
- Mitsuba: `mi.load_file` in the `scalar_rgb` variant (parse, shapes and BVH built), timed
  inside a process that has already imported Mitsuba; its peak RSS minus the RSS after the
  import is reported beside the whole process's.
"""

import argparse
import json
import resource
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
    with tempfile.TemporaryDirectory() as d:
        t = time.perf_counter()
        subprocess.run(
            [binary, "render", scene, "--width", "1", "--height", "1", "--spp", "1", "-q", "-o", str(Path(d) / "x.exr")],
            check=True,
        )
        dt = time.perf_counter() - t
    return {"time": dt, "peak_kb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss}


def mitsuba(scene: str) -> dict:
    out = subprocess.run([sys.executable, "-c", MITSUBA, scene], check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pathwave", required=True)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("scenes", nargs="+")
    a = ap.parse_args()
    print("| scene | renderer | load s (best of reps) | peak RSS MB | note |")
    print("|---|---|---|---|---|")
    for s in a.scenes:
        name = Path(s).parent.name
        # Mitsuba first: RUSAGE_CHILDREN's peak is the largest child so far, so pathwave's runs
        # come after it would be wrong; measure pathwave in a clean interpreter instead.
        runs = [mitsuba(s) for _ in range(a.reps)]
        t = min(r["time"] for r in runs)
        peak = max(r["peak_kb"] for r in runs) / 1024
        extra = max(r["peak_kb"] - r["base_kb"] for r in runs) / 1024
        print(f"| {name} | Mitsuba 3 | {t:.3f} | {peak:.0f} | {extra:.0f} MB above the import |", flush=True)
        code = (
            "import sys; sys.path.insert(0, %r); import load_cost as l, json; "
            "print(json.dumps([l.pathwave(%r, %r) for _ in range(%d)]))"
        ) % (str(Path(__file__).parent), a.pathwave, s, a.reps)
        runs = json.loads(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout)
        t = min(r["time"] for r in runs)
        peak = max(r["peak_kb"] for r in runs) / 1024
        print(f"| {name} | pathwave | {t:.3f} | {peak:.0f} | whole process, 1x1 render |", flush=True)


if __name__ == "__main__":
    main()
