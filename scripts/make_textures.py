#!/usr/bin/env python3
"""Writes the textures of the spatially varying presets into assets/textures/.

    python3 scripts/make_textures.py

Standard library only (zlib and struct write the PNGs); a fixed seed makes the output the same
byte for byte on every run, so the committed files are what this script writes.
"""

import math
import random
import struct
import zlib
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "assets" / "textures"
SIZE = 256


def png(path, width, height, channels, depth, rows):
    """A PNG of `rows` (lists of samples), grey (1) or RGB (3), 8 or 16 bits."""
    colour = {1: 0, 3: 2}[channels]
    fmt = ">%d%s" % (width * channels, "H" if depth == 16 else "B")
    raw = b"".join(b"\x00" + struct.pack(fmt, *row) for row in rows)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
    data += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    path.write_bytes(data)


def periodic_noise(rng, period):
    """1-D value noise of `period` lattice cells over [0, 1), smoothstep-interpolated."""
    lattice = [rng.random() for _ in range(period)]

    def at(t):
        x = t * period
        i = math.floor(x)
        f = x - i
        s = f * f * (3 - 2 * f)
        a, b = lattice[i % period], lattice[(i + 1) % period]
        return a + (b - a) * s

    return at


def brushed(rng):
    """Brushing streaks: fine noise across the rows (v), almost constant along them (u), as
    a 16-bit linear grey map of roughness in [0, 1] (the material's range scales it)."""
    across = [periodic_noise(rng, p) for p in (128, 64, 16)]
    along = periodic_noise(rng, 4)
    rows = []
    for y in range(SIZE):
        v = y / SIZE
        streak = 0.55 * across[0](v) + 0.3 * across[1](v) + 0.15 * across[2](v)
        row = []
        for x in range(SIZE):
            value = 0.85 * streak + 0.15 * along(x / SIZE)
            row.append(round(max(0.0, min(1.0, value)) * 65535))
        rows.append(row)
    return rows


def mottled_bronze(rng):
    """A bronze F0 colour that wanders between a warmer and a duller alloy: 8-bit sRGB."""
    noise_u = [periodic_noise(rng, p) for p in (8, 32)]
    noise_v = [periodic_noise(rng, p) for p in (8, 32)]
    warm, dull = (0.86, 0.60, 0.36), (0.70, 0.52, 0.34)

    def srgb(c):
        c = max(0.0, min(1.0, c))
        return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055

    rows = []
    for y in range(SIZE):
        v = y / SIZE
        row = []
        for x in range(SIZE):
            u = x / SIZE
            t = 0.5 * (0.7 * noise_u[0](u) + 0.3 * noise_u[1](u)) + 0.5 * (
                0.7 * noise_v[0](v) + 0.3 * noise_v[1](v)
            )
            for c in range(3):
                row.append(round(srgb(dull[c] + (warm[c] - dull[c]) * t) * 255))
        rows.append(row)
    return rows


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    rng = random.Random(20261125)
    png(OUT / "brushed-streaks.png", SIZE, SIZE, 1, 16, brushed(rng))
    png(OUT / "bronze-mottle.png", SIZE, SIZE, 3, 8, mottled_bronze(rng))
    print("wrote", OUT / "brushed-streaks.png", "and", OUT / "bronze-mottle.png")


if __name__ == "__main__":
    main()
