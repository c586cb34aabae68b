"""A small decoder of 16-bit greyscale PNGs (what pgvol's 3MF image stacks hold), written from the
PNG specification so that the checks read the sheets without pgvol's own code."""

from __future__ import annotations

import struct
import zlib

import numpy as np


def decode_png16(blob: bytes) -> np.ndarray:
    """A one-channel 16-bit PNG as a (rows, columns) uint16 array (filters 0-4, no interlace)."""
    assert blob[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    at, idat, ihdr = 8, b"", None
    while at < len(blob):
        (length,) = struct.unpack(">I", blob[at : at + 4])
        kind = blob[at + 4 : at + 8]
        body = blob[at + 8 : at + 8 + length]
        assert zlib.crc32(kind + body) == struct.unpack(">I", blob[at + 8 + length : at + 12 + length])[0]
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        at += 12 + length
    width, height, depth, color, _, _, interlace = ihdr
    assert (depth, color, interlace) == (16, 0, 0), ihdr
    bpp, stride = 2, 2 * width
    raw = zlib.decompress(idat)
    assert len(raw) == height * (stride + 1)
    out = np.zeros((height, stride), dtype=np.int64)
    prev = np.zeros(stride, dtype=np.int64)
    for r in range(height):
        ftype = raw[r * (stride + 1)]
        line = np.frombuffer(raw, np.uint8, stride, r * (stride + 1) + 1).astype(np.int64)
        cur = np.zeros(stride, dtype=np.int64)
        for x in range(stride):
            a = cur[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if ftype == 0:
                pred = 0
            elif ftype == 1:
                pred = a
            elif ftype == 2:
                pred = b
            elif ftype == 3:
                pred = (a + b) // 2
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            else:
                raise AssertionError(f"bad PNG filter {ftype}")
            cur[x] = (line[x] + pred) & 0xFF
        out[r] = cur
        prev = cur
    return (out[:, 0::2] * 256 + out[:, 1::2]).astype(np.uint16)
