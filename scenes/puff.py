"""Writes scenes/assets/puff/puff_0000.vol to puff_0003.vol, the four frames of the puff of
smoke of smoke-frames.ron: Mitsuba `.vol` grids (version 3, float32, one channel; see
pathwave's engine/src/format/vol.rs) of 16 x 16 x 16 densities in [0, 1], 16 KB each.

Deterministic: a ball of smoke that rises through the grid from frame to frame, swelling and
thinning as it goes, broken up by a sum of sines that turns with the frame, fading to zero at
the grid's faces. A simulation would write such a sequence, a file per frame.
Run: python3 scenes/puff.py (standard library only).
"""
import math
import struct

N = 16
FRAMES = 4
for frame in range(FRAMES):
    s = frame / (FRAMES - 1)
    # Centre, radius and peak density of the ball in grid coordinates [0, 1].
    cy, radius, peak = 0.3 + 0.4 * s, 0.2 + 0.12 * s, 1.0 - 0.45 * s
    values = []
    for z in range(N):
        for y in range(N):
            for x in range(N):
                u, v, w = (x + 0.5) / N, (y + 0.5) / N, (z + 0.5) / N
                r = math.sqrt((u - 0.5) ** 2 + (v - cy) ** 2 + (w - 0.5) ** 2) / radius
                core = max(0.0, 1.0 - r * r)
                swirl = 0.6 + 0.4 * math.sin(11.0 * u + 2.0 * frame) * math.cos(9.0 * w - 7.0 * v + frame)
                edge = min(1.0, 8.0 * min(u, v, w, 1.0 - u, 1.0 - v, 1.0 - w))
                values.append(max(0.0, min(1.0, peak * core * swirl * edge)))
    with open(f"scenes/assets/puff/puff_{frame:04}.vol", "wb") as f:
        f.write(b"VOL" + bytes([3]))
        f.write(struct.pack("<5i", 1, N, N, N, 1))
        f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        f.write(struct.pack(f"<{len(values)}f", *values))
