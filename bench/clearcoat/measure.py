#!/usr/bin/env python3
"""KHR_materials_clearcoat against the path-traced truth (issue 40 item 6).

Renders bench/scenes/clearcoat_spheres.toml with the default hybrid frame and with the path tracer
(`--mode path`), labels the spheres with `--debug-view object`, and prints per sphere the mean
radiance of both and their ratio, the frame's ꟻLIP (`hybrid-rt compare`), and the same for the
scene with every coat removed, so the coat's own error stands beside the base's. Then `bench` on
both scenes: the frame's GPU ms with and without the coats.

    python3 bench/clearcoat/measure.py [--bin target/debug/hybrid-rt] [--width 160 --height 90]
        [--spp 256] [--out bench/clearcoat/out]
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench" / "mitsuba"))
from hdrio import read_hdr  # noqa: E402

SCENE = ROOT / "bench" / "scenes" / "clearcoat_spheres.toml"


def run(args: list[str]) -> str:
    done = subprocess.run(args, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(args)} failed:\n{done.stderr[-3000:]}")
    return done.stdout + done.stderr


def labels(img: np.ndarray) -> dict[tuple, np.ndarray]:
    """Pixel masks per distinct `--debug-view object` colour."""
    keys = np.round(img[..., :3], 3)
    flat = keys.reshape(-1, 3)
    out = {}
    for colour in np.unique(flat, axis=0):
        mask = np.all(keys == colour, axis=-1)
        if mask.sum() > 20:
            out[tuple(colour)] = mask
    return out


def measure(o: argparse.Namespace, scene: Path, tag: str) -> list[str]:
    size = ["--width", str(o.width), "--height", str(o.height)]
    base = [o.bin, "render", "--scene", str(scene), *size]
    files = {k: o.out / f"{tag}_{k}" for k in ("hybrid", "path", "labels")}
    run([*base, "--out", f"{files['hybrid']}.png", "--hdr-out", f"{files['hybrid']}.hdr"])
    run([*base, "--mode", "path", "--samples", str(o.spp), "--out", f"{files['path']}.png",
         "--hdr-out", f"{files['path']}.hdr"])
    run([*base, "--debug-view", "object", "--aa", "none", "--out", f"{files['labels']}.png",
         "--hdr-out", f"{files['labels']}.hdr"])
    hybrid, path = read_hdr(f"{files['hybrid']}.hdr"), read_hdr(f"{files['path']}.hdr")
    compared = run([o.bin, "compare", f"{files['path']}.png", f"{files['hybrid']}.png"]).splitlines()
    flip = next(line for line in compared if line.startswith("ꟻLIP mean"))
    rows = [f"### {tag}", "", f"frame against the truth: {flip}", "",
            "| object (left to right) | truth | hybrid | hybrid / truth |", "|---|---|---|---|"]
    found = []
    for mask in labels(read_hdr(f"{files['labels']}.hdr")).values():
        # Off the silhouette: the path tracer's jittered samples there see what is behind.
        mask = mask & np.roll(mask, 1, 0) & np.roll(mask, -1, 0) & np.roll(mask, 1, 1) & np.roll(mask, -1, 1)
        if mask.sum() == 0:
            continue
        ys, xs = np.nonzero(mask)
        # Spheres only: the floor spans the frame.
        if xs.max() - xs.min() > o.width / 3:
            continue
        t = path[mask][:, :3].mean()
        h = hybrid[mask][:, :3].mean()
        found.append((xs.mean(), t, h))
    names = ["paint (smooth coat)", "satin paint (coat 0.3)", "coated gold (coat 0.5, 0.05)", "coat only",
             "bare paint"]
    for name, (_, t, h) in zip(names, sorted(found)):
        rows.append(f"| {name} | {t:.4f} | {h:.4f} | {h / t:.3f} |")
    return rows + [""]


def gpu_ms(o: argparse.Namespace, scene: Path) -> str:
    """The median GPU ms of the frame and of the passes a coat touches, 640 x 360."""
    out = run([o.bin, "bench", "--scene", str(scene), "--width", "640", "--height", "360",
               "--frames", "8", "--warmup", "2"])
    medians = {}
    for line in out.splitlines():
        m = re.match(r"^(frame|direct|specular|composite|glossy)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)$", line)
        if m:
            medians[m.group(1)] = m.group(3)
    return ", ".join(f"{k} {v} ms" for k, v in medians.items())


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bin", default=str(ROOT / "target" / "debug" / "hybrid-rt"))
    p.add_argument("--width", type=int, default=160)
    p.add_argument("--height", type=int, default=90)
    p.add_argument("--spp", type=int, default=256)
    p.add_argument("--out", type=Path, default=ROOT / "bench" / "clearcoat" / "out")
    o = p.parse_args()
    o.out.mkdir(parents=True, exist_ok=True)
    bare = o.out / "clearcoat_spheres_bare.toml"
    text = SCENE.read_text().replace('hdr = "../../assets/', f'hdr = "{ROOT / "assets"}/')
    bare.write_text(re.sub(r"(?m)^clearcoat(_roughness)? = .*\n", "", text))
    print("\n".join(measure(o, SCENE, "coated") + measure(o, bare, "bare")))
    print(f"GPU frame, coated: {gpu_ms(o, SCENE)}")
    print(f"GPU frame, bare:   {gpu_ms(o, bare)}")


if __name__ == "__main__":
    main()
