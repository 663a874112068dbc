"""Writes scenes/assets/plume.vol, the smoke plume of smoke-plume.ron: a Mitsuba `.vol` grid
(version 3, float32, one channel; see pathwave's engine/src/format/vol.rs) of 24 x 40 x 24
densities in [0, 1].

Deterministic: a column rising from a source near the bottom, widening and thinning with
height, bent by a slow sway and broken up by a sum of sines, fading to zero at the grid's faces.
Run: python3 scenes/plume.py (standard library only).
"""
import math
import struct

NX, NY, NZ = 24, 40, 24
values = []
for z in range(NZ):
    for y in range(NY):
        for x in range(NX):
            # Grid coordinates of the voxel centre in [0, 1].
            u, v, w = (x + 0.5) / NX, (y + 0.5) / NY, (z + 0.5) / NZ
            cx = 0.5 + 0.12 * math.sin(3.0 * v + 0.5) * v
            cz = 0.5 + 0.08 * math.cos(4.0 * v) * v
            radius = 0.08 + 0.28 * v
            r = math.hypot(u - cx, w - cz) / radius
            core = max(0.0, 1.0 - r * r)
            swirl = 0.55 + 0.45 * math.sin(9.0 * u + 7.0 * v) * math.cos(8.0 * w - 5.0 * v + 1.3)
            fade = min(1.0, 6.0 * v) * min(1.0, 5.0 * (1.0 - v)) * (1.0 - 0.6 * v)
            values.append(max(0.0, min(1.0, core * swirl * fade)))

with open("scenes/assets/plume.vol", "wb") as f:
    f.write(b"VOL" + bytes([3]))
    f.write(struct.pack("<5i", 1, NX, NY, NZ, 1))
    f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
    f.write(struct.pack(f"<{len(values)}f", *values))
