#!/usr/bin/env python3
"""Compares two 8-bit RGB(A) PNGs as linear images: RMSE and largest channel difference
(on 0..1) and the ratio of their mean radiance. A PNG tagged sRGB is decoded with the sRGB
curve; one tagged gAMA 1.0, or untagged (vdb_render's), is taken as linear.

Usage: tools/bench/png_diff.py A.png B.png   (prints "rmse R max M mean A B ratio A/B")
Pure Python (zlib), no image library needed."""
import struct
import sys
import zlib


def read_png(path):
    data = open(path, 'rb').read()
    if data[:8] != b'\x89PNG\r\n\x1a\n':
        sys.exit(f'{path}: not a PNG')
    pos, idat, srgb = 8, b'', False
    width = height = depth = ctype = None
    while pos < len(data):
        (n,) = struct.unpack('>I', data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b'IHDR':
            width, height, depth, ctype = struct.unpack('>IIBB', body[:10])
        elif kind == b'IDAT':
            idat += body
        elif kind == b'sRGB':
            srgb = True
    if depth != 8 or ctype not in (2, 6):
        sys.exit(f'{path}: expected 8-bit RGB or RGBA')
    channels = 3 if ctype == 2 else 4
    raw, stride = zlib.decompress(idat), width * channels
    prev, rows, i = bytearray(stride), [], 0
    for _ in range(height):
        kind, line = raw[i], bytearray(raw[i + 1:i + 1 + stride])
        i += 1 + stride
        for x in range(stride):
            a = line[x - channels] if x >= channels else 0
            b = prev[x]
            c = prev[x - channels] if x >= channels else 0
            if kind == 1:
                line[x] = (line[x] + a) & 255
            elif kind == 2:
                line[x] = (line[x] + b) & 255
            elif kind == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line

    def linear(v):
        s = v / 255.0
        if not srgb:
            return s
        return s / 12.92 if s <= 0.04045 else ((s + 0.055) / 1.055) ** 2.4

    values = [linear(r[x * channels + k]) for r in rows for x in range(width) for k in range(3)]
    return (width, height), values


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    (size_a, a), (size_b, b) = read_png(sys.argv[1]), read_png(sys.argv[2])
    if size_a != size_b:
        sys.exit(f'sizes differ: {size_a} vs {size_b}')
    n = len(a)
    rmse = (sum((x - y) ** 2 for x, y in zip(a, b)) / n) ** 0.5
    largest = max(abs(x - y) for x, y in zip(a, b))
    mean_a, mean_b = sum(a) / n, sum(b) / n
    ratio = mean_a / mean_b if mean_b > 0 else float('nan')
    print(f'rmse {rmse:.4f} max {largest:.4f} mean {mean_a:.4f} {mean_b:.4f} ratio {ratio:.3f}')


if __name__ == '__main__':
    main()
