"""Writes scenes/instances.ron (10,000 instances of one mesh) and its mesh,
scenes/assets/knot-2k.obj (the torus knot of `pathwave bench-rays` and the Embree anchor,
benches/RESULTS.md, at 40 rings of 25 vertices: 2,000 triangles). The instances stand on a
100 x 100 grid, each with its own rotation about y, scale and one of four materials: 20 million triangles drawn from one 2,000-triangle BLAS.
Deterministic. Run: python3 scenes/instances.py
"""
import math
import os
import random

HERE = os.path.dirname(os.path.abspath(__file__))


def knot(rings, segments):
    pos = []
    for i in range(rings):
        t = 2 * math.pi * i / rings
        s2, c2, s3, c3 = math.sin(2 * t), math.cos(2 * t), math.sin(3 * t), math.cos(3 * t)
        r, r1, r2 = c3 + 2, -3 * s3, -9 * c3
        c = (r * c2, r * s2, -s3)
        d1 = (r1 * c2 - 2 * r * s2, r1 * s2 + 2 * r * c2, -3 * c3)
        d2 = (r2 * c2 - 4 * r1 * s2 - 4 * r * c2, r2 * s2 + 4 * r1 * c2 - 4 * r * s2, 9 * s3)
        norm = lambda v: [x / math.sqrt(sum(y * y for y in v)) for x in v]
        tan = norm(d1)
        k = sum(a * b for a, b in zip(d2, tan))
        nrm = norm([a - k * b for a, b in zip(d2, tan)])
        bin_ = [tan[1] * nrm[2] - tan[2] * nrm[1], tan[2] * nrm[0] - tan[0] * nrm[2], tan[0] * nrm[1] - tan[1] * nrm[0]]
        for j in range(segments):
            th = 2 * math.pi * j / segments
            rad = 0.4 * (1 + 0.08 * math.sin(60 * t) * math.sin(6 * th))
            pos.append([c[a] + rad * (math.cos(th) * nrm[a] + math.sin(th) * bin_[a]) for a in range(3)])
    at = lambda i, j: (i % rings) * segments + j % segments
    tris = []
    for i in range(rings):
        for j in range(segments):
            a, b, c, d = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
            tris += [(a, b, c), (a, c, d)]
    return pos, tris


pos, tris = knot(40, 25)
with open(os.path.join(HERE, "assets", "knot-2k.obj"), "w") as f:
    f.write("# torus knot, 40 rings x 25 vertices (scenes/instances.py)\n")
    for p in pos:
        f.write("v %.6f %.6f %.6f\n" % tuple(p))
    for t in tris:
        f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))

rng = random.Random(7)
lines = []
for gx in range(100):
    for gz in range(100):
        x, z = (gx - 49.5) * 8, (gz - 49.5) * 8
        s = 0.8 + 0.6 * rng.random()
        lines.append(
            '        (shape: Mesh(file: "assets/knot-2k.obj"), material: "m%d", transform: '
            "[RotateX(90), RotateY(%.1f), UniformScale(%.3f), Translate((%.1f, %.3f, %.1f))]),"
            % (rng.randrange(4), rng.uniform(0, 360), s, x, 2.8 * s, z)
        )
with open(os.path.join(HERE, "instances.ron"), "w") as f:
    f.write("""// 10,000 instances of one 2,000-triangle mesh (one BLAS, a TLAS over 10,000 instances) on a
// ground quad under a sky. Written by scenes/instances.py; edit that, not this file.
#![enable(implicit_some)]
Scene(
    camera: (look_from: (-60, 45, -60), look_at: (0, 0, 0), vfov: 50),
    render: (width: 384, height: 216, spp: 16, max_depth: 8),
    background: Sky(bottom: (1, 1, 1), top: (0.5, 0.7, 1.0)),
    materials: {
        "ground": Lambertian(albedo: (0.5, 0.5, 0.5)),
        "m0": Lambertian(albedo: (0.7, 0.3, 0.2)),
        "m1": Lambertian(albedo: (0.2, 0.5, 0.7)),
        "m2": Metal(albedo: (0.8, 0.8, 0.7), fuzz: 0.2),
        "m3": Lambertian(albedo: (0.8, 0.8, 0.8)),
    },
    objects: [
        (shape: Quad(q: (-500, 0, -500), u: (0, 0, 1000), v: (1000, 0, 0)), material: "ground"),
""")
    f.write("\n".join(lines) + "\n    ],\n)\n")
