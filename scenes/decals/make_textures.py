#!/usr/bin/env python3
"""Writes the default scene's decal textures (256 x 256 RGBA PNGs) with the
standard library alone: python3 scenes/decals/make_textures.py"""
import math, os, struct, zlib

N = 256
HERE = os.path.dirname(os.path.abspath(__file__))


def noise(x, y, seed):
    h = (x * 374761393 + y * 668265263 + seed * 2147483647) & 0xFFFFFFFF
    h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
    return ((h ^ (h >> 16)) & 0xFFFF) / 65535.0 - 0.5


def smooth(e0, e1, x):
    t = min(max((x - e0) / (e1 - e0), 0.0), 1.0)
    return t * t * (3 - 2 * t)


def write(name, texel):
    rows = b"".join(b"\0" + bytes(c for x in range(N) for c in texel(x, y)) for y in range(N))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", N, N, 8, 6, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b"")
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(png)


def road(x, y):
    # u across (x), v along (y): asphalt, white edge lines, a dashed yellow centre line.
    u, v = (x + 0.5) / N, (y + 0.5) / N
    g = 62 + 10 * noise(x, y, 1) + 6 * noise(x // 4, y // 4, 2)
    c = (g, g, g + 3)
    if 0.07 < u < 0.11 or 0.89 < u < 0.93:
        c = (215, 215, 210)
    if 0.485 < u < 0.515 and v % 0.5 < 0.3:
        c = (220, 170, 40)
    a = smooth(0.0, 0.04, u) * smooth(1.0, 0.96, u)
    return [int(min(max(k, 0), 255)) for k in c] + [int(255 * a)]


def helipad(x, y):
    # A concrete disc with a white ring and an H: shows orientation and scale.
    px, py = (x + 0.5) / N - 0.5, (y + 0.5) / N - 0.5
    r = math.hypot(px, py)
    g = 150 + 12 * noise(x, y, 3)
    c = (g, g, g - 6)
    if 0.38 < r < 0.42:
        c = (230, 230, 225)
    if (abs(px) < 0.2 and abs(py) < 0.035) or (0.14 < abs(px) < 0.2 and abs(py) < 0.22):
        c = (230, 230, 225)
    a = smooth(0.49, 0.47, r)
    return [int(min(max(k, 0), 255)) for k in c] + [int(255 * a)]


def mud(x, y):
    # A muddy patch with a ragged edge.
    px, py = (x + 0.5) / N - 0.5, (y + 0.5) / N - 0.5
    ang = math.atan2(py, px)
    edge = 0.36 + 0.05 * math.sin(5 * ang) + 0.03 * math.sin(11 * ang + 1.0)
    r = math.hypot(px, py)
    t = 8 * noise(x, y, 4) + 10 * noise(x // 8, y // 8, 5)
    c = (92 + t, 70 + t, 50 + t * 0.8)
    a = smooth(edge + 0.06, edge - 0.04, r) * 0.9
    return [int(min(max(k, 0), 255)) for k in c] + [int(255 * a)]


for name, f in [("road.png", road), ("helipad.png", helipad), ("mud.png", mud)]:
    write(name, f)
