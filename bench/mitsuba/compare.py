"""Check hybrid-rt's path tracer (`render --mode path`) against Mitsuba 3.

For each scene of scenes.py (or those named): write the renderer's TOML and the
OBJ files; render Mitsuba (scalar_rgb, `path` integrator, box-filtered pixels,
independent samples) as two halves of --spp with different seeds; render the
renderer with `--mode path --samples N` at the same size and sample count;
label every pixel centre with the object Mitsuba's camera ray hits; and report,
per object and for the background, the mean linear radiance of both images over
the pixels whose 3x3 neighbourhood is that one object, the ratio
renderer/Mitsuba per channel with its standard error, and the whole frame's
ꟻLIP / PSNR / relMSE from `hybrid-rt compare`. Tables go to stdout and to
results/<scene>.md.

  nice -n 19 python3 bench/mitsuba/compare.py                     # every scene, 320x180, 1024 spp
  nice -n 19 python3 bench/mitsuba/compare.py furnace --spp 64 --width 64 --height 36
  python3 bench/mitsuba/compare.py --no-renderer orient           # Mitsuba side only
"""

from __future__ import annotations

import argparse
import datetime as _dt
import hashlib
import json
import os
import platform
import re
import shlex
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import hdrio  # noqa: E402
import scenes as scenes_mod  # noqa: E402

REPO = HERE.parent.parent


def default_bin() -> Path:
    for kind in ("release", "debug"):
        p = REPO / "target" / kind / "hybrid-rt"
        if p.exists():
            return p
    return REPO / "target" / "release" / "hybrid-rt"


# ---------------------------------------------------------------- Mitsuba


def mitsuba():
    import mitsuba as mi

    if mi.variant() != "scalar_rgb":
        mi.set_variant("scalar_rgb")
    return mi


def scene_key(scene_dict: dict, toml_text: str) -> str:
    """A short hash of what determines the Mitsuba image (cache key)."""
    h = hashlib.sha256(toml_text.encode())
    h.update(repr(sorted((k, repr(v)) for k, v in scene_dict.items())).encode())
    return h.hexdigest()[:10]


def render_mitsuba(scene, out_dir: Path, args) -> tuple[np.ndarray, np.ndarray, float, bool]:
    """Two half-spp Mitsuba renders (seeds 0 and 1), cached as EXR; returns
    (half0, half1, seconds, cached)."""
    mi = mitsuba()
    half = max(args.spp // 2, 1)
    d = scene.mitsuba_dict(out_dir, args.width, args.height, half, args.mi_max_depth, args.rr_depth,
                           args.dielectric_model)
    key = scene_key(d, (out_dir / "scene.toml").read_text())
    stem = f"mitsuba_{args.width}x{args.height}_{2 * half}spp_d{args.mi_max_depth}_{key}"
    paths = [out_dir / f"{stem}_half{i}.exr" for i in (0, 1)]
    meta_path = out_dir / f"{stem}.json"
    if not args.force and meta_path.exists() and all(p.exists() for p in paths):
        try:
            meta = json.loads(meta_path.read_text())
            return (*[np.array(mi.Bitmap(str(p)), dtype=np.float32)[..., :3] for p in paths],
                    float(meta.get("seconds", float("nan"))), True)
        except (RuntimeError, ValueError) as e:
            print(f"   Mitsuba cache unreadable ({e}): rendering again", flush=True)
    meta_path.unlink(missing_ok=True)
    s = mi.load_dict(d)
    t0 = time.time()
    halves = []
    for i, p in enumerate(paths):
        img = np.array(mi.render(s, spp=half, seed=i), dtype=np.float32)[..., :3]
        tmp = p.with_name(p.stem + ".tmp.exr")
        mi.Bitmap(img).write(str(tmp))
        tmp.replace(p)  # atomic: an interrupted run leaves no half-written cache
        halves.append(img)
    secs = time.time() - t0
    meta_path.write_text(json.dumps({"seconds": secs}))  # written last: marks the cache complete
    return halves[0], halves[1], secs, False


def object_labels(scene, out_dir: Path, width: int, height: int) -> tuple[np.ndarray, list[str]]:
    """Label of the surface each pixel centre's camera ray hits first (Mitsuba's
    camera, the same OBJ shapes): 0 = background, i = names[i]."""
    mi = mitsuba()
    d = scene.mitsuba_dict(out_dir, width, height, 1)
    s = mi.load_dict(d, optimize=False)  # optimize merges meshes that share a BSDF: keep each object
    sensor = s.sensors()[0]
    names = ["background"] + [o.name for o in scene.objects]
    index = {n: i for i, n in enumerate(names)}
    lab = np.zeros((height, width), np.int32)
    for y in range(height):
        for x in range(width):
            ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f((x + 0.5) / width, (y + 0.5) / height),
                                       mi.Point2f(0.5, 0.5))
            si = s.ray_intersect(ray)
            if si.is_valid():
                lab[y, x] = index[si.shape.id()]
    return lab, names


def interior(lab: np.ndarray) -> np.ndarray:
    """True where the whole 3x3 neighbourhood has the pixel's label (image
    border pixels excluded)."""
    h, w = lab.shape
    ok = np.zeros_like(lab, dtype=bool)
    c = lab[1:-1, 1:-1]
    m = np.ones_like(c, dtype=bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            m &= lab[1 + dy:h - 1 + dy, 1 + dx:w - 1 + dx] == c
    ok[1:-1, 1:-1] = m
    return ok


# ---------------------------------------------------------------- statistics


def halves_stats(a: np.ndarray, b: np.ndarray, sel: np.ndarray):
    """Mean of (a+b)/2 over sel and its standard error from the halves'
    per-pixel difference: var((a-b)/2) = var((a+b)/2) for independent halves."""
    n = int(sel.sum())
    m = 0.5 * (a[sel] + b[sel])
    dd = 0.5 * (a[sel].astype(np.float64) - b[sel])
    return m.mean(axis=0), np.sqrt((dd ** 2).sum(axis=0)) / n


def spatial_stats(img: np.ndarray, sel: np.ndarray):
    """Mean over sel and a standard error estimated from one image: the
    residual r = I - mean of the 4 neighbours has variance 1.25 sigma^2 for
    independent pixel noise (sel pixels have same-object neighbours). Shading
    curvature (shadow edges, highlights) adds to it: an upper bound."""
    n = int(sel.sum())
    f = img.astype(np.float64)
    r = np.zeros_like(f)
    r[1:-1, 1:-1] = f[1:-1, 1:-1] - 0.25 * (f[:-2, 1:-1] + f[2:, 1:-1] + f[1:-1, :-2] + f[1:-1, 2:])
    var = (r[sel] ** 2).mean(axis=0) / 1.25
    return f[sel].mean(axis=0), np.sqrt(var / n)


# ---------------------------------------------------------------- renderer


def run_renderer(bin_path: Path, toml: Path, out_dir: Path, args, samples: int, tag: str,
                 seed: int | None) -> tuple[Path, float, str]:
    hdr = out_dir / f"renderer_{args.width}x{args.height}_{samples}spp{tag}.hdr"
    png = hdr.with_suffix(".tonemapped.png")  # the renderer's own PNG
    cmd = [str(bin_path), "render", "--scene", str(toml), "--width", str(args.width), "--height",
           str(args.height), "--mode", "path", "--samples", str(samples), "--hdr-out", str(hdr), "--out", str(png)]
    if seed is not None:
        cmd += [args.renderer_seed_flag, str(seed)]
    cmd += shlex.split(args.renderer_args)
    log = hdr.with_suffix(".log")
    t0 = time.time()
    with open(log, "w") as f:
        f.write("$ " + shlex.join(cmd) + "\n")
        f.flush()
        rc = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT).returncode
    secs = time.time() - t0
    if rc != 0 or not hdr.exists():
        tail = "".join(log.read_text().splitlines(keepends=True)[-15:])
        raise RuntimeError(f"renderer failed (exit {rc}), log {log}:\n{tail}")
    return hdr, secs, shlex.join(cmd)


def renderer_device(log_text: str) -> str:
    """The device named in the renderer's log ('hybrid_rt::vk] using NAME (...), Vulkan ...')."""
    for line in log_text.splitlines():
        m = re.search(r"\]\s+using (.+?)(?:, Vulkan|$)", line)
        if m:
            return m.group(1).strip()
    return "?"


def flip_compare(bin_path: Path | None, ref: Path, test: Path, exposure: float, map_png: Path | None) -> dict:
    """ꟻLIP mean, PSNR, relMSE of test against ref via `hybrid-rt compare`
    (or the flip-evaluator package when there is no binary)."""
    if bin_path is not None and bin_path.exists():
        cmd = [str(bin_path), "compare", str(ref), str(test), "--exposure", repr(float(exposure))]
        if map_png is not None:
            cmd += ["--out", str(map_png)]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode == 0:
            r = {"tool": "hybrid-rt compare"}
            for key, pat in (("flip", r"LIP mean\s+([0-9.eE+-]+)"), ("psnr", r"PSNR\s+([0-9.eE+-]+|inf)"),
                             ("relmse", r"relMSE\s+([0-9.eE+-]+)")):
                m = re.search(pat, p.stdout)
                r[key] = float(m.group(1)) if m else float("nan")
            return r
        err = (p.stderr or p.stdout).strip().splitlines()[-1:]
        return {"tool": f"hybrid-rt compare failed: {' '.join(err)}"}
    try:
        import flip_evaluator as flip  # optional

        a, b = hdrio.read_hdr(ref), hdrio.read_hdr(test)
        _, mean, _ = flip.evaluate(a, b, "HDR")
        return {"tool": "flip-evaluator (HDR-FLIP)", "flip": float(mean)}
    except ImportError:
        return {"tool": "none (no renderer binary, no flip-evaluator)"}


# ---------------------------------------------------------------- output


def to_png(path: Path, img: np.ndarray, exposure: float) -> None:
    mi = mitsuba()
    x = np.clip(img * exposure, 0.0, 1.0)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    mi.Bitmap((x * 255 + 0.5).astype(np.uint8), mi.Bitmap.PixelFormat.RGB).write(str(path))


def label_png(path: Path, lab: np.ndarray, clean: np.ndarray) -> None:
    rng = np.random.default_rng(7)
    pal = (rng.uniform(60, 255, (lab.max() + 1, 3))).astype(np.uint8)
    pal[0] = (30, 30, 30)
    img = pal[lab]
    img[~clean] //= 3
    mitsuba().Bitmap(np.ascontiguousarray(img), mitsuba().Bitmap.PixelFormat.RGB).write(str(path))


def fmt3(v, digits=4) -> str:
    return " ".join(f"{x:.{digits}g}" for x in v)


def machine() -> str:
    cpu = "?"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{platform.node()}: {cpu}, {os.cpu_count()} logical CPUs, {platform.system()} {platform.release()}"


def git_head() -> str:
    """HEAD, marked when the work tree has changes outside bench/mitsuba."""
    try:
        head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True).stdout.strip() or "?"
        st = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--", ".", ":!bench/mitsuba"],
                            capture_output=True, text=True).stdout.strip()
        return head + (" + uncommitted changes" if st else "")
    except OSError:
        return "?"


def binary_stamp(p: Path) -> str:
    try:
        t = _dt.datetime.fromtimestamp(p.stat().st_mtime, _dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        return f"{p.relative_to(REPO) if p.is_relative_to(REPO) else p} built {t}"
    except OSError:
        return str(p)


# ---------------------------------------------------------------- main


def compare_scene(scene, args) -> str:
    mi = mitsuba()
    import drjit as dr

    out_dir = args.out / scene.name
    toml = scene.write(out_dir)
    W, H = args.width, args.height
    exposure = args.exposure if args.exposure is not None else scene.exposure
    print(f"== {scene.name}: {W}x{H}, {args.spp} spp ({toml})", flush=True)

    lab, names = object_labels(scene, out_dir, W, H)
    clean = interior(lab)
    label_png(out_dir / f"labels_{W}x{H}.png", lab, clean)

    m0, m1, mi_secs, cached = render_mitsuba(scene, out_dir, args)
    # what the renderer's .hdr would hold: the same truncating RGBE, decoded at bucket centres
    q0, q1 = hdrio.quantize_like_renderer(m0), hdrio.quantize_like_renderer(m1)
    mref = 0.5 * (m0 + m1)
    mref_hdr = out_dir / f"mitsuba_{W}x{H}_{args.spp}spp.hdr"
    hdrio.write_hdr(mref_hdr, mref)
    mi.Bitmap(mref).write(str(mref_hdr.with_suffix(".exr")))
    for i, m in enumerate((m0, m1)):
        hdrio.write_hdr(out_dir / f"mitsuba_{W}x{H}_{args.spp}spp_half{i}.hdr", m)
    to_png(out_dir / f"mitsuba_{W}x{H}_{args.spp}spp.png", mref, exposure)
    print(f"   Mitsuba: {'cached' if cached else f'{mi_secs:.1f} s'}", flush=True)

    # ---- renderer
    r_err, r_cmd, r_secs, r_dev, r_hdr, r_noise = None, "", float("nan"), "?", None, "?"
    r0 = r1 = rimg = None
    bin_path = Path(args.bin) if args.bin else default_bin()
    if args.renderer_hdr:
        r_hdr = Path(args.renderer_hdr)
        r_cmd = f"(given: {r_hdr})"
    elif not args.no_renderer:
        try:
            if not bin_path.exists():
                raise RuntimeError(f"no renderer binary at {bin_path}")
            if args.renderer_seed_flag:
                half = max(args.spp // 2, 1)
                h0, s0, r_cmd = run_renderer(bin_path, toml, out_dir, args, half, "_seed1", 1)
                h1, s1, _ = run_renderer(bin_path, toml, out_dir, args, half, "_seed2", 2)
                r0, r1 = hdrio.read_hdr(h0), hdrio.read_hdr(h1)
                r_secs = s0 + s1
                rimg = 0.5 * (r0 + r1)
                r_hdr = out_dir / f"renderer_{W}x{H}_{2 * half}spp.hdr"
                hdrio.write_hdr(r_hdr, rimg)
                r_dev = renderer_device(h0.with_suffix(".log").read_text())
            else:
                r_hdr, r_secs, r_cmd = run_renderer(bin_path, toml, out_dir, args, args.spp, "", None)
                r_dev = renderer_device(r_hdr.with_suffix(".log").read_text())
                if args.renderer_noise == "prefix" and args.spp % 8 == 0:
                    # The path tracer seeds each frame of PATH_SAMPLES_PER_FRAME (4) paths by
                    # pixel and frame index (glsl/path/path.glsl), so a run of N/2 samples is
                    # exactly the first half of the N run: first = that run, second =
                    # 2 full - first, two independent halves from 1.5x the render time.
                    hp, sp, _ = run_renderer(bin_path, toml, out_dir, args, args.spp // 2, "_prefix", None)
                    r_secs += sp
                    full = hdrio.read_hdr(r_hdr)
                    r0 = hdrio.read_hdr(hp)
                    r1 = 2.0 * full - r0
                    rimg = full
                    # guard: two independent halves agree over the frame within their noise
                    d = (r0.astype(np.float64) - r1).reshape(-1, 3)
                    z = np.abs(d.mean(0)) / (d.std(0) / np.sqrt(len(d)) + 1e-12)
                    if np.any(z > 6.0) or (r1 < -0.05 * np.abs(full).max()).mean() > 0.01:
                        print(f"   renderer: the {args.spp // 2}-sample run is not the first half of the "
                              f"{args.spp}-sample one (z {z.round(1)}): spatial noise estimate", flush=True)
                        r0 = r1 = None
        except RuntimeError as e:
            r_err = str(e)
            print(f"   renderer: {r_err}", flush=True)
    if r_hdr is not None and rimg is None:
        rimg = hdrio.read_hdr(r_hdr)
        if rimg.shape[:2] != (H, W):
            r_err, rimg = f"renderer image is {rimg.shape[1]}x{rimg.shape[0]}, expected {W}x{H}", None
    if rimg is not None:
        r_noise = ("spatial (one image; an upper bound)" if r0 is None else
                   "two seeds (halves)" if args.renderer_seed_flag else
                   f"halves: the {args.spp // 2}-sample run and 2 x the {args.spp}-sample one minus it "
                   "(RGBE rounding of both adds a little: an upper bound)")
        to_png(out_dir / f"renderer_{W}x{H}_{args.spp}spp.png", rimg, exposure)
        if np.isfinite(r_secs):
            print(f"   renderer: {r_secs:.1f} s", flush=True)

    # ---- per-object table
    rows = []
    for i, name in enumerate(names):
        sel = (lab == i) & clean
        n = int(sel.sum())
        if n < 4:
            continue
        mm, mse = halves_stats(q0, q1, sel)
        _, msp = spatial_stats(0.5 * (q0 + q1), sel)
        mf, _ = halves_stats(m0, m1, sel)  # float, unquantized: for the exact values
        row = {"name": name, "n": n, "mi": mm, "mi_se": mse, "mi_se_spatial": msp, "mi_float": mf}
        if name != "background":
            obj = next(o for o in scene.objects if o.name == name)
            _, model, _ = scene.material(obj.material).mitsuba(args.dielectric_model)
            row["model"] = f"{obj.material} → {model}"
        else:
            row["model"] = "environment" if (scene.env_hdr is not None or any(scene.env_color or ())) else "black"
        if rimg is not None:
            if r0 is not None:
                rm, rse = halves_stats(r0, r1, sel)
            else:
                rm, rse = spatial_stats(rimg, sel)
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = rm / mm
                rse_ratio = np.abs(ratio) * np.sqrt((rse / rm) ** 2 + (mse / mm) ** 2)
                z = np.where(rse_ratio > 0, (ratio - 1.0) / rse_ratio,
                             np.where(np.abs(ratio - 1.0) < 1e-6, 0.0, np.inf))
            row.update(r=rm, r_se=rse, ratio=ratio, ratio_se=rse_ratio, z=z)
        if name in scene.expected:
            row["expected"] = np.array(scene.expected[name])
        rows.append(row)

    # ---- whole frame
    frame = {}
    noise_flip = {}
    if rimg is not None:
        frame = flip_compare(bin_path if bin_path.exists() else None, mref_hdr, r_hdr, exposure,
                             out_dir / f"flip_{W}x{H}_{args.spp}spp.png")
    noise_flip = flip_compare(bin_path if bin_path.exists() else None,
                              out_dir / f"mitsuba_{W}x{H}_{args.spp}spp_half0.hdr",
                              out_dir / f"mitsuba_{W}x{H}_{args.spp}spp_half1.hdr", exposure, None)

    # ---- markdown
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    md = [f"# {scene.name}: renderer path tracer vs Mitsuba 3\n",
          f"{scene.summary}.\n", f"Checks: {scene.checks}.\n",
          "| | |", "|---|---|",
          f"| date | {now} |",
          f"| machine | {machine()} |",
          f"| Mitsuba | {mi.__version__} (drjit {dr.__version__}), variant scalar_rgb, `path` max_depth "
          f"{args.mi_max_depth} rr_depth {args.rr_depth}, independent sampler, box filter; "
          f"{'cached' if cached else f'{mi_secs:.0f} s'} |",
          f"| size, samples | {W}x{H}, {args.spp} spp per pixel on both sides (Mitsuba: 2 x {max(args.spp // 2, 1)}, seeds 0 and 1) |",
          f"| renderer | {git_head()}, {binary_stamp(bin_path) if not args.renderer_hdr else 'given image'}: "
          f"`{r_cmd or '-'}`"
          + (f"; {r_secs:.0f} s (with the noise run); device: {r_dev}" if rimg is not None and np.isfinite(r_secs)
             else "") + " |",
          f"| renderer noise estimate | {r_noise} |",
          f"| exposure (ꟻLIP tone mapping, PNGs) | {exposure:g} |"]
    if r_err:
        md.append(f"| renderer error | {r_err.splitlines()[0]} |")
    md.append("")
    md.append("Per object: mean linear radiance (R G B) over the pixels whose 3x3 neighbourhood is that object "
              "(pixel-centre ray cast in Mitsuba's camera), ± its standard error; ratio = renderer / Mitsuba "
              "± standard error; z = (ratio − 1) / se: |z| > 4 is bias, not noise. Mitsuba's image went "
              "through the renderer's RGBE encoding first and both are decoded at bucket centres "
              "(hdrio.py).\n")
    head = "| object | material → Mitsuba model | px | Mitsuba | ± se |"
    sep = "|---|---|---:|---|---|"
    if rimg is not None:
        head += " renderer | ± se | ratio R G B | ± se | z R G B |"
        sep += "---|---|---|---|---|"
    if any("expected" in r for r in rows):
        head += " exact | Mitsuba (float) / exact |"
        sep += "---|---|"
    md += [head, sep]
    for r in rows:
        line = f"| {r['name']} | {r['model']} | {r['n']} | {fmt3(r['mi'])} | {fmt3(r['mi_se'], 2)} |"
        if rimg is not None:
            line += (f" {fmt3(r['r'])} | {fmt3(r['r_se'], 2)} | **{fmt3(r['ratio'])}** | {fmt3(r['ratio_se'], 2)} |"
                     f" {' '.join(f'{v:+.1f}' for v in r['z'])} |")
        if any("expected" in x for x in rows):
            if "expected" in r:
                line += f" {fmt3(r['expected'])} | {fmt3(r['mi_float'] / r['expected'], 5)} |"
            else:
                line += " | |"
        md.append(line)
    md.append("")
    notes = []
    for o in scene.objects:
        m = scene.material(o.material)
        _, model, residual = m.mitsuba(args.dielectric_model)
        line = f"- {m.name} → {model}: {residual}"
        if line not in notes:
            notes.append(line)
    md.append("Expected model differences (README, results/albedo.md):\n")
    md += notes
    md.append("")
    cal = [float(np.median(r["mi_se_spatial"] / r["mi_se"])) for r in rows if np.all(r["mi_se"] > 0)]
    if cal:
        md.append(f"Noise-estimate calibration (Mitsuba, where both are known): the one-image spatial estimate is "
                  f"{min(cal):.2f}–{max(cal):.2f} x the two-seed one per object (median over channels).\n")
    md.append("Whole frame (`compare` A = Mitsuba, B = renderer):\n")
    md.append("| pair | tool | ꟻLIP mean | PSNR dB | relMSE |")
    md.append("|---|---|---:|---:|---:|")

    def frow(label, f):
        return (f"| {label} | {f.get('tool', '-')} | {f.get('flip', float('nan')):.4f} | "
                f"{f.get('psnr', float('nan')):.2f} | {f.get('relmse', float('nan')):.4g} |")

    if frame:
        md.append(frow(f"renderer vs Mitsuba, {args.spp} spp each", frame))
    md.append(frow(f"Mitsuba half 0 vs half 1 ({max(args.spp // 2, 1)} spp each: the noise floor; "
                   f"noise alone between two {args.spp}-spp images is about 1/√2 of its error)", noise_flip))
    md.append("")
    md.append(f"Images in `{out_dir.relative_to(REPO) if out_dir.is_relative_to(REPO) else out_dir}/` "
              f"(not committed): mitsuba_*.exr/.hdr/.png, renderer_*.hdr/.png/.log, labels_*.png, flip_*.png.\n")
    text = "\n".join(md)
    args.results.mkdir(parents=True, exist_ok=True)
    (args.results / f"{scene.name}.md").write_text(text)
    print(text, flush=True)
    return text


def main() -> None:
    all_scenes = scenes_mod.scene_list()
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", help=f"scenes (default all): {', '.join(all_scenes)}")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=180)
    ap.add_argument("--spp", type=int, default=1024, help="samples per pixel, both sides (default 1024)")
    ap.add_argument("--bin", help="hybrid-rt binary (default target/release/hybrid-rt, else target/debug)")
    ap.add_argument("--renderer-args", default="", help="extra arguments for `hybrid-rt render` "
                    "(use the = form: --renderer-args='--max-bounces 64 --backend compute')")
    ap.add_argument("--renderer-seed-flag", default="", help="the renderer's seed option, if it has one "
                    "(--renderer-seed-flag=--seed): it is then run twice at spp/2 with seeds 1 and 2 for a "
                    "two-seed noise estimate; otherwise see --renderer-noise")
    ap.add_argument("--renderer-noise", choices=["prefix", "spatial"], default="prefix",
                    help="renderer noise estimate without a seed option: prefix (default; also renders "
                    "spp/2, whose samples are the first half of the full run's; needs spp %% 8 == 0) or "
                    "spatial (one image, neighbour residuals: an upper bound, loose at high spp)")
    ap.add_argument("--renderer-hdr", help="use this renderer .hdr instead of running the renderer "
                    "(one scene only)")
    ap.add_argument("--no-renderer", action="store_true", help="Mitsuba side only")
    ap.add_argument("--mi-max-depth", type=int, default=-1, help="Mitsuba path max_depth (-1: unbounded, "
                    "the converged answer; 1 = emitters seen directly, 2 = direct light only, ...)")
    ap.add_argument("--rr-depth", type=int, default=5, help="Mitsuba Russian roulette start depth")
    ap.add_argument("--dielectric-model", choices=["blend", "roughplastic", "diffuse"], default="blend",
                    help="Mitsuba stand-in for opaque dielectrics with ior > 1 (README, albedo.py)")
    ap.add_argument("--exposure", type=float, help="override the scene's exposure for ꟻLIP and PNGs")
    ap.add_argument("--force", action="store_true", help="re-render Mitsuba even if cached")
    ap.add_argument("--out", type=Path, default=HERE / "out", help="work folder (default bench/mitsuba/out)")
    ap.add_argument("--results", type=Path, default=HERE / "results", help="markdown tables (default "
                    "bench/mitsuba/results)")
    args = ap.parse_args()
    names = args.scenes or list(all_scenes)
    for n in names:
        if n not in all_scenes:
            ap.error(f"unknown scene {n!r}; known: {', '.join(all_scenes)}")
    if args.renderer_hdr and len(names) != 1:
        ap.error("--renderer-hdr needs exactly one scene")
    mitsuba()
    for n in names:
        compare_scene(all_scenes[n], args)


if __name__ == "__main__":
    main()
