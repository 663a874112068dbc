"""Writes the brick maps of maps.ron: scenes/assets/bricks-height.png, an 8-bit grey image of
heights (bricks 1, mortar 0, a rounded edge between), and scenes/assets/bricks-normals.png, the
normal map of the same surface, (n + 1) / 2 per channel, for a unit square of uv carrying
`RELIEF` units of height per unit of value.

Deterministic: a 128 x 128 texel tile of four courses of two bricks each, every other course
shifted by half a brick, each brick's face tilted slightly by its own hash.
Run: python3 scenes/maps.py (standard library only).
"""
import math
import struct
import zlib

N = 128
COURSES, BRICKS = 4, 2
MORTAR = 0.06  # Mortar half-width, in brick heights.
EDGE = 0.10  # Rounding of a brick's edge, in brick heights.
RELIEF = 0.02  # Height of a unit value, in units of uv, for the normals.


def height(u, v):
    """The height in [0, 1] at (u, v) of the tile, v up."""
    row = v * COURSES
    course = int(math.floor(row)) % COURSES
    col = u * BRICKS + 0.5 * (course % 2)
    brick = int(math.floor(col)) % BRICKS
    # Distances to the nearest joint, in brick heights (a brick is 2 heights long per unit col).
    fy = row - math.floor(row)
    fx = col - math.floor(col)
    d = min(fy, 1.0 - fy, (COURSES / BRICKS) * min(fx, 1.0 - fx))
    face = max(0.0, min(1.0, (d - MORTAR) / EDGE))
    face = face * face * (3.0 - 2.0 * face)
    seed = (course * 7 + brick * 13) % 17
    tilt = 0.08 * math.sin(seed * 2.1 + 6.0 * fx) * math.cos(seed * 1.3 + 4.0 * fy)
    return max(0.0, min(1.0, face * (0.9 + tilt)))


def png(path, width, height, channels, rows):
    """Writes 8-bit rows (lists of ints, `channels` per texel) as a PNG."""
    kind = {1: 0, 3: 2}[channels]
    raw = b"".join(b"\0" + bytes(r) for r in rows)

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, kind, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


# Texel centres; image row 0 is the top (v = 1).
h = [[height((i + 0.5) / N, 1.0 - (j + 0.5) / N) for i in range(N)] for j in range(N)]
png("scenes/assets/bricks-height.png", N, N, 1, [[round(255 * x) for x in row] for row in h])
normals = []
for j in range(N):
    row = []
    for i in range(N):
        # Central differences (wrapping), per unit of uv; v grows up, rows down.
        dhdu = (h[j][(i + 1) % N] - h[j][(i - 1) % N]) * N / 2.0 * RELIEF
        dhdv = (h[(j - 1) % N][i] - h[(j + 1) % N][i]) * N / 2.0 * RELIEF
        n = (-dhdu, -dhdv, 1.0)
        length = math.sqrt(sum(c * c for c in n))
        row.extend(round(255 * (0.5 + 0.5 * c / length)) for c in n)
    normals.append(row)
png("scenes/assets/bricks-normals.png", N, N, 3, normals)
