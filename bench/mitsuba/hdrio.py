"""Radiance RGBE (.hdr) reading and writing with numpy, matching the renderer.

The renderer writes `--hdr-out` with the `image` crate (0.25) `HdrEncoder`:
each pixel's largest channel sets the exponent e = floor(log2 max) + 1 and every
channel is stored as trunc(v / 2^e * 256) -- truncation, not rounding -- and the
crate decodes c * 2^(e - 136). Truncation makes every decoded value low by half a
step on average: 0.2-0.4 % for the pixel's largest channel, but a channel at 1/10
of the largest loses 2-4 %. So

* `read_hdr(..., centre=True)` (the default here) decodes at the bucket centre,
  (c + 0.5) * 2^(e - 136) as Radiance itself does, which removes that bias;
* `quantize_like_renderer` runs a float image through the same truncating
  encoder, so a float reference (Mitsuba) can be put through exactly what the
  renderer's output went through before the two are compared;
* `write_hdr` writes what the image crate would write (same truncation, new-style
  RLE scanlines), so `hybrid-rt compare` reads both files alike.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np


def _encode_rgbe(img: np.ndarray) -> np.ndarray:
    """float32 HxWx3 -> uint8 HxWx4, the image crate's `to_rgbe8` (truncating)."""
    img = np.nan_to_num(np.asarray(img, dtype=np.float32)[..., :3], nan=0.0, posinf=0.0, neginf=0.0)
    img = np.maximum(img, 0.0)  # the renderer clamps negatives before encoding
    mx = img.max(axis=-1)
    out = np.zeros(img.shape[:-1] + (4,), dtype=np.uint8)
    pos = mx > 0.0
    # exp = floor(log2(mx)) + 1 in f32, as the crate computes it.
    with np.errstate(divide="ignore"):
        exp = np.floor(np.log2(mx.astype(np.float32), where=pos, out=np.zeros_like(mx))).astype(np.int32) + 1
    exp = np.clip(exp, -127, 127)
    mul = np.ldexp(np.float32(1.0), exp).astype(np.float32)
    c = np.trunc(img / mul[..., None] * np.float32(256.0))
    c = np.clip(c, 0, 255).astype(np.uint8)
    out[..., :3] = np.where(pos[..., None], c, 0)
    out[..., 3] = np.where(pos, (exp + 128).astype(np.uint8), 0)
    return out


def _decode_rgbe(rgbe: np.ndarray, centre: bool) -> np.ndarray:
    c = rgbe[..., :3].astype(np.float64)
    e = rgbe[..., 3].astype(np.int32)
    scale = np.ldexp(1.0, e - 136)
    if centre:
        c = c + 0.5
    v = c * scale[..., None]
    v[e == 0] = 0.0
    return v.astype(np.float32)


def quantize_like_renderer(img: np.ndarray, centre: bool = True) -> np.ndarray:
    """The float image as the renderer's .hdr output would hold it, decoded."""
    return _decode_rgbe(_encode_rgbe(img), centre)


def write_hdr(path: str | Path, img: np.ndarray) -> None:
    """Writes HxWx3 linear float RGB as Radiance RGBE, rows top first."""
    rgbe = _encode_rgbe(img)
    h, w = rgbe.shape[:2]
    parts = [b"#?RADIANCE\n# bench/mitsuba/hdrio.py (image crate encoding)\nFORMAT=32-bit_rle_rgbe\n\n",
             f"-Y {h} +X {w}\n".encode()]
    if 8 <= w <= 32767:
        head = bytes([2, 2, w >> 8, w & 255])
        for y in range(h):
            parts.append(head)
            for ch in range(4):
                data = rgbe[y, :, ch].tobytes()
                # literal runs of at most 128 bytes: valid new-style RLE
                for i in range(0, w, 128):
                    chunk = data[i:i + 128]
                    parts.append(bytes([len(chunk)]))
                    parts.append(chunk)
    else:
        parts.append(rgbe.tobytes())
    Path(path).write_bytes(b"".join(parts))


def read_hdr(path: str | Path, centre: bool = True) -> np.ndarray:
    """Reads a Radiance RGBE file (-Y H +X W, flat or new-style RLE) -> HxWx3 float32."""
    data = Path(path).read_bytes()
    pos = 0
    # header: lines up to an empty line
    while True:
        end = data.index(b"\n", pos)
        line = data[pos:end]
        pos = end + 1
        if line.strip() == b"":
            break
        if line.startswith(b"FORMAT=") and b"32-bit_rle_rgbe" not in line:
            raise ValueError(f"{path}: unsupported {line.decode(errors='replace')}")
    end = data.index(b"\n", pos)
    res = data[pos:end].decode()
    pos = end + 1
    m = re.fullmatch(r"\s*-Y\s+(\d+)\s+\+X\s+(\d+)\s*", res)
    if not m:
        raise ValueError(f"{path}: unsupported resolution line '{res}' (only -Y H +X W)")
    h, w = int(m.group(1)), int(m.group(2))
    buf = np.frombuffer(data, dtype=np.uint8, offset=pos)
    out = np.zeros((h, w, 4), dtype=np.uint8)
    i = 0
    for y in range(h):
        if 8 <= w <= 32767 and buf[i] == 2 and buf[i + 1] == 2 and (buf[i + 2] & 0x80) == 0:
            if (int(buf[i + 2]) << 8 | int(buf[i + 3])) != w:
                raise ValueError(f"{path}: scanline {y} width mismatch")
            i += 4
            for ch in range(4):
                x = 0
                while x < w:
                    n = int(buf[i])
                    i += 1
                    if n > 128:
                        n -= 128
                        out[y, x:x + n, ch] = buf[i]
                        i += 1
                    else:
                        out[y, x:x + n, ch] = buf[i:i + n]
                        i += n
                    x += n
        else:
            # flat pixels (old-style RLE repeat markers are not produced by the
            # image crate or by write_hdr and are not supported)
            out[y] = buf[i:i + 4 * w].reshape(w, 4)
            i += 4 * w
    return _decode_rgbe(out, centre)
