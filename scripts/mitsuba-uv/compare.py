#!/usr/bin/env python3
"""pathwave's uv of converted Mitsuba shapes against Mitsuba 3's own.

    python compare.py PATHWAVE [--spp 256]

Run with a Python that imports Mitsuba 3 (tested with 3.9.1) and numpy. In a temporary folder,
writes grid.png (8 x 4 texels, all different), uv.xml and uv-path.xml (with a path integrator
instead of the aov one), then renders uv.xml's albedo with Mitsuba (its aov integrator) and with
pathwave (`--aov albedo`), for the bitmap and for the checkerboard, and prints per texture the
pixels whose albedo differs by more than 0.05 and, for scale, the same count between two
Mitsuba renders of other seeds. Texel edges make pixels noisy: a wrong uv (a flipped v, a
turned face) shows as whole faces or bands of differing pixels, many more than Mitsuba's own."""
import argparse, os, subprocess, tempfile
import numpy as np
import mitsuba as mi

mi.set_variant('scalar_rgb')
ap = argparse.ArgumentParser()
ap.add_argument('pathwave')
ap.add_argument('--spp', default='256')
a = ap.parse_args()
here, pathwave = os.path.dirname(os.path.abspath(__file__)), os.path.abspath(a.pathwave)
os.chdir(tempfile.mkdtemp())
grid = np.zeros((4, 8, 3), dtype=np.uint8)
for j in range(4):
    for i in range(8):
        grid[j, i] = [20 + 30 * i, 30 + 60 * j, 200 if (i + j) % 2 else 40]
mi.Bitmap(grid, pixel_format=mi.Bitmap.PixelFormat.RGB).write('grid.png')
aov = '<integrator type="aov"><string name="aovs" value="alb:albedo"/></integrator>'
xml = open(os.path.join(here, 'uv.xml')).read()
assert aov in xml
for name, text in [('uv.xml', xml), ('uv-path.xml', xml.replace(aov, '<integrator type="path"/>'))]:
    with open(name, 'w') as f:
        f.write(text)
for tex in ['grid', 'checker']:
    scene = mi.load_file('uv.xml', tex=tex, spp=a.spp)
    ref = np.array(mi.render(scene, seed=0))
    other = np.array(mi.render(scene, seed=7))
    out = tex + '.exr'
    subprocess.run([pathwave, 'render', 'uv-path.xml', '-D', 'tex=' + tex, '--spp', a.spp, '--aov', 'albedo', '-o', out,
                    '-q'], check=True)
    albedo = np.array(dict(mi.Bitmap(out).split())['albedo'])
    count = lambda x: int((np.abs(x - ref).max(axis=2) > 0.05).sum())
    print(f'{tex}: pathwave differs from Mitsuba in {count(albedo)} of {ref.shape[0] * ref.shape[1]} pixels; '
          f'Mitsuba of another seed in {count(other)}')
