"""Writes a Mitsuba 3 XML scene of many OBJ files, for load_cost.py (issue 47's big scenes).

    python benches/load/many_meshes.py OUT_DIR [--meshes 200] [--segments 64]

OUT_DIR/scene.xml names OUT_DIR/mesh-NNN.obj, each its own file: a UV sphere of `segments` x
2 `segments` quads (two triangles each; 8 192 triangles at 64), its radius rippled differently
in each file so that no two files are alike, placed on a grid. Nothing but the standard
library is needed.
"""

import argparse
import math
from pathlib import Path


def sphere(seed, segments):
    rows, cols = segments, 2 * segments
    lines = []
    for j in range(rows + 1):
        theta = math.pi * j / rows
        for i in range(cols):
            phi = 2 * math.pi * i / cols
            r = 1 + 0.05 * math.sin(seed + 7 * theta) * math.cos(3 * phi + seed)
            lines.append("v %.6f %.6f %.6f" % (r * math.sin(theta) * math.cos(phi), r * math.cos(theta), r * math.sin(theta) * math.sin(phi)))
    for j in range(rows):
        for i in range(cols):
            a = j * cols + i + 1
            b = j * cols + (i + 1) % cols + 1
            c, d = a + cols, b + cols
            # Counter-clockwise seen from outside: the normals face out.
            lines.append("f %d %d %d" % (a, b, c))
            lines.append("f %d %d %d" % (b, d, c))
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--meshes", type=int, default=200)
    ap.add_argument("--segments", type=int, default=64)
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    side = math.ceil(math.sqrt(a.meshes))
    shapes = []
    for k in range(a.meshes):
        name = "mesh-%03d.obj" % k
        (out / name).write_text(sphere(k, a.segments))
        x, z = 2.5 * (k % side - side / 2), 2.5 * (k // side)
        shapes.append(
            '    <shape type="obj">\n        <string name="filename" value="%s"/>\n'
            '        <transform name="to_world"><translate x="%g" y="1" z="%g"/></transform>\n'
            '        <bsdf type="diffuse"/>\n    </shape>' % (name, x, z)
        )
    (out / "scene.xml").write_text(
        '<scene version="3.0.0">\n'
        '    <sensor type="perspective">\n        <float name="fov" value="60"/>\n'
        '        <transform name="to_world"><lookat origin="0, %g, -12" target="0, 0, %g" up="0, 1, 0"/></transform>\n'
        '        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/></film>\n'
        '    </sensor>\n'
        '    <emitter type="constant"/>\n%s\n</scene>\n' % (side, side, "\n".join(shapes))
    )


if __name__ == "__main__":
    main()
