#!/usr/bin/env python3
"""An X window dump (xwd, 32 bits a pixel, as Xvfb's 24-bit screen gives) as an RGB PNG, with
the standard library only: xwd_png.py IN.xwd OUT.png. The PNG is written beside OUT and renamed
into place."""
import os
import struct
import sys
import zlib

sys.dont_write_bytecode = True


def main(src, dst):
    d = open(src, 'rb').read()
    if len(d) < 100:
        sys.exit(f"{src}: not an X window dump (too short)")
    h = struct.unpack('>25I', d[:100])  # XWDFileHeader, big-endian CARD32s
    hsize, width, height, order, bpp, bpl, ncolors = h[0], h[4], h[5], h[7], h[11], h[12], h[19]
    masks = h[14:17]
    if bpp != 32 or not all(masks):
        sys.exit(f"{src}: {bpp} bits a pixel; only 32-bit TrueColor dumps are read")
    shifts = [(m & -m).bit_length() - 1 for m in masks]
    start = hsize + 12 * ncolors
    if len(d) < start + bpl * height:
        sys.exit(f"{src}: truncated ({len(d)} bytes, {start + bpl * height} expected)")
    fmt = ('<' if order == 0 else '>') + f'{width}I'
    raw = bytearray()
    for y in range(height):
        raw.append(0)  # PNG filter: none
        for p in struct.unpack(fmt, d[start + y * bpl:start + y * bpl + 4 * width]):
            raw += bytes((p & m) >> s for m, s in zip(masks, shifts))

    def chunk(kind, body):
        return (struct.pack('>I', len(body)) + kind + body +
                struct.pack('>I', zlib.crc32(kind + body) & 0xffffffff))

    png = (b'\x89PNG\r\n\x1a\n' +
           chunk(b'IHDR', struct.pack('>IIBBBBB', width, height, 8, 2, 0, 0, 0)) +
           chunk(b'IDAT', zlib.compress(bytes(raw), 9)) + chunk(b'IEND', b''))
    tmp = dst + '.tmp'
    with open(tmp, 'wb') as f:
        f.write(png)
    os.replace(tmp, dst)


if __name__ == '__main__':
    if len(sys.argv) != 3:
        sys.exit("usage: xwd_png.py IN.xwd OUT.png")
    main(sys.argv[1], sys.argv[2])
