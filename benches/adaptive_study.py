#!/usr/bin/env python3
"""What adaptive sample allocation could buy at equal time, before building it.

  adaptive_study.py --pathwave target/release/pathwave [--scenes cornell,mesh] [--pilot 64]
                    [--unit 16] [--units 12]

Run from the project root with a Python that has numpy and Mitsuba (the anchor's venv: its
`metrics.load` reads EXRs). For each scene it renders a pilot of PILOT spp with the per-pixel
variance AOV and UNITS independent renders of UNIT spp (other seeds), then simulates a renderer
that gives each pixel the pilot plus a number of extra units proportional to
sqrt(sum over channels of variance / (mean^2 + 0.01)), the allocation that minimises the
relMSE of ANCHORS.md (`(x - r)^2 / (r^2 + 0.01)`) for a fixed total, clamped to [lo, hi] times
the mean and renormalised. It prints the uniform render's relMSE against the reference, the
adaptive one's, and the gain at equal samples (relMSE ratio times the sample ratio: errors fall
as 1/samples), for two clamps and with or without a 3x3 box filter of the weights.

The simulation combines whole renders per pixel, so the uniform baseline loses the Sobol
sequence's stratification across units (its relMSE is above that of one render of as many spp);
the gains are ratios within the simulation. The allocation uses each pixel's own pilot, so the
estimate it simulates is biased where the pilot's variance estimate correlates with its mean
(an allocation from the neighbours' pilots would not be).
Its gains did not survive being built: a real adaptive renderer gained 0-10% at equal time at 64
spp and nothing at 256 (benches/RESULTS.md, "Adaptive sampling built and measured"), because this
simulation counts samples rather than time and gives the uniform baseline no stratification.
"""
import argparse, os, subprocess, sys

import numpy as np

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument('--pathwave', required=True)
ap.add_argument('--scenes', default='cornell,cornell-diffuse,spheres-sky,mesh')
ap.add_argument('--pilot', type=int, default=64)
ap.add_argument('--unit', type=int, default=16)
ap.add_argument('--units', type=int, default=12)
ap.add_argument('--refs', default=os.path.join('..', 'shared', 'refs'))
ap.add_argument('--anchor', default=os.path.join('..', 'shared', 'anchors', 'mitsuba'))
ap.add_argument('--tmp', default='/tmp/adaptive_study')
a = ap.parse_args()
sys.path.insert(0, a.anchor)
import metrics  # noqa: E402
import mitsuba as mi  # noqa: E402

os.makedirs(a.tmp, exist_ok=True)


def relmse(x, ref):
    return float((((x - ref) ** 2) / (ref * ref + 0.01)).mean())


def box(v):
    p = np.pad(v, 1, mode='edge')
    h, w = v.shape
    return sum(p[i:i + h, j:j + w] for i in range(3) for j in range(3)) / 9


def render(scene, spp, seed, out, *extra):
    cmd = [a.pathwave, 'render', os.path.join('scenes', scene + '.ron'), '--spp', str(spp), '--seed', str(seed),
           '-o', out, *extra]
    subprocess.run(cmd, check=True, capture_output=True)


for name in a.scenes.split(','):
    ref = metrics.load(os.path.join(a.refs, name + '.exr'))
    units = []
    for k in range(a.units):
        out = os.path.join(a.tmp, '%s-unit%d.exr' % (name, k))
        render(name, a.unit, 200 + k, out)
        units.append(metrics.load(out))
    cs = np.cumsum(np.array(units), 0)
    out = os.path.join(a.tmp, '%s-pilot.exr' % name)
    render(name, a.pilot, 77, out, '--aov', 'variance')
    px = np.array(mi.Bitmap(out), dtype=np.float64)
    mean, var = px[..., :3], px[..., 4:7] * a.pilot  # the AOV is the variance of the mean
    pu = a.pilot // a.unit  # the pilot, in units
    total = pu + a.units
    uniform = (mean * pu + cs[-1]) / total
    print('%s: uniform %d spp relMSE %.6f' % (name, a.unit * total, relmse(uniform, ref)))
    for blur in (False, True):
        v = (var / (mean * mean + 0.01)).sum(-1)
        w = np.sqrt(box(v) if blur else v)
        for lo, hi in ((0.25, 4.0), (0.5, 2.0)):
            n = np.clip(w / w.mean(), lo, hi)
            for _ in range(50):
                n = np.clip(n / n.mean(), lo, hi)
            units_px = np.clip(np.round(n * total).astype(int), pu, total)
            extra = units_px - pu
            idx = np.maximum(extra - 1, 0)[None, :, :, None].repeat(3, -1)
            summed = np.where(extra[..., None] > 0, np.take_along_axis(cs, idx, 0)[0], 0.0)
            est = (mean * pu + summed) / units_px[..., None]
            gain = relmse(uniform, ref) / relmse(est, ref) * total / units_px.mean()
            print('  weights %s, clamp [%g, %g]: %.2f of %d units per pixel, relMSE %.6f, gain at equal samples %.2f'
                  % ('3x3 box' if blur else 'per pixel', lo, hi, units_px.mean(), total, relmse(est, ref), gain))
