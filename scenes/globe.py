"""Writes scenes/globe.png, the equirectangular map of the globe in textures.ron.

Deterministic: ocean, land masses from a sum of sines, polar caps, a graticule every 30
degrees, the equator in yellow and the meridian at u = 0.5 in red, so that the orientation of
the sphere's uv mapping can be read off a render. Row 0 is the north (v = 1).
Run: python3 scenes/globe.py (needs Pillow).
"""
import math
from PIL import Image

W, H = 512, 256
img = Image.new("RGB", (W, H))
px = img.load()
for j in range(H):
    lat = math.pi * (0.5 - (j + 0.5) / H)  # +pi/2 at the top row
    for i in range(W):
        lon = 2 * math.pi * ((i + 0.5) / W) - math.pi
        h = (math.sin(2 * lon + 1.0) * math.cos(3 * lat) + 0.6 * math.sin(5 * lon - 2 * lat + 0.5)
             + 0.4 * math.cos(7 * lon + 4 * lat) + 0.3 * math.sin(11 * lat))
        c = (30, 80, 160) if h < 0.35 else (60, 140, 60) if h < 1.0 else (150, 120, 70)
        if abs(lat) > math.radians(70):
            c = (235, 240, 245)
        deg_lat, deg_lon = math.degrees(lat), math.degrees(lon)
        if min(deg_lat % 30, -deg_lat % 30) < 0.6 or min(deg_lon % 30, -deg_lon % 30) < 0.6:
            c = tuple(v // 2 for v in c)
        if abs(deg_lat) < 0.8:
            c = (240, 210, 40)
        if abs(deg_lon) < 0.8:
            c = (220, 40, 30)
        px[i, j] = c
img.save(__file__.replace("globe.py", "globe.png"))
