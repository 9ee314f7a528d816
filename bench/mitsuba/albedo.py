"""How far apart are the renderer's material model and its Mitsuba stand-in?

For each mapped material that is not exact (glossy dielectrics, metals), the
directional albedo -- the radiance a surface sends towards a viewer at angle
theta_o under a uniform white sky of radiance 1 -- of

* the renderer's BRDF, glsl/common/brdf.glsl `brdf_eval` re-implemented in
  numpy (GGX, height-correlated Smith, Schlick F with f90 from f0, diffuse
  (1 - F(v.h)) (1 - metallic) base / pi; roughness 0 metals as a perfect mirror
  with Schlick F at n.v, the assumption for the path tracer's delta case), and
* the Mitsuba BSDF that scenes.py maps it to (importance-sampled by Mitsuba),

and their ratio. The last row, "sphere", is the albedo averaged over a sphere's
visible disc (weight 2 cos theta_o d cos theta_o): the ratio compare.py should
find for an isolated sphere of that material under a uniform sky, if the model
were the only difference. Real scenes (sun, floor, map) weigh angles and
lighting directions differently, so take it as the size and sign to expect,
not an exact prediction.

  nice -n 19 python3 bench/mitsuba/albedo.py [--samples N]   -> results/albedo.md
"""

from __future__ import annotations

import argparse
import datetime as _dt
import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from scenes import Material, scene_list  # noqa: E402

ANGLES = [0, 30, 45, 60, 75, 85]


# ---------------------------------------------------------------- renderer BRDF (numpy)


def schlick(f0: np.ndarray, v_h: np.ndarray) -> np.ndarray:
    f = np.clip(1.0 - v_h, 0.0, 1.0) ** 5
    f90 = np.clip((f0 * (50.0 / 3.0)).sum(-1, keepdims=True), 0.0, 1.0)
    return f0 + (f90 - f0) * f[..., None]


def renderer_brdf_cos(m: Material, v: np.ndarray, l: np.ndarray) -> np.ndarray:
    """brdf_eval(s, v, l, e = 1): (diffuse + spec) * n.l, n = +z. Nx3."""
    base = np.array(m.base_color[:3])
    n_l = l[:, 2]
    n_v = np.maximum(v[:, 2], 1e-4)
    h = l + v
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    n_h = np.maximum(h[:, 2], 0.0)
    v_h = np.maximum((v * h).sum(1), 0.0)
    a = max(m.roughness ** 2, 1e-3)
    a2 = a * a
    fr = (m.ior - 1.0) / (m.ior + 1.0)
    f0 = np.full(3, fr * fr) * (1 - m.metallic) + base * m.metallic
    F = schlick(f0[None, :], v_h)
    d = n_h * n_h * (a2 - 1.0) + 1.0
    D = a2 / np.maximum(math.pi * d * d, 1e-12)
    gv = n_l * np.sqrt(n_v * n_v * (1.0 - a2) + a2)
    gl = n_v * np.sqrt(np.maximum(n_l, 0) ** 2 * (1.0 - a2) + a2)
    V = 0.5 / np.maximum(gv + gl, 1e-12)
    spec = F * (D * V)[:, None]
    diffuse = (1.0 - F) * (1.0 - m.metallic) * (1.0 - m.transmission) * base / math.pi
    out = (diffuse + spec) * n_l[:, None]
    out[n_l <= 0.0] = 0.0
    return out


def renderer_albedo(m: Material, theta_deg: float, n: int, rng) -> np.ndarray:
    th = math.radians(theta_deg)
    v1 = np.array([math.sin(th), 0.0, math.cos(th)])
    if m.roughness == 0.0 and m.metallic == 1.0:
        f0 = np.array(m.base_color[:3])
        return schlick(f0[None, :], np.array([v1[2]]))[0]
    v = np.tile(v1, (n, 1))
    a = max(m.roughness ** 2, 1e-3)
    a2 = a * a
    # one-sample MIS mixture: half cosine-weighted, half GGX normals reflected about
    u1, u2, pick = rng.random(n), rng.random(n), rng.random(n) < 0.5
    r, phi = np.sqrt(u1), 2 * math.pi * u2
    l_cos = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(1 - u1, 0))], 1)
    ct = np.sqrt((1 - u1) / (1 + (a2 - 1) * u1))
    st = np.sqrt(np.maximum(1 - ct * ct, 0))
    hh = np.stack([st * np.cos(phi), st * np.sin(phi), ct], 1)
    l_ggx = 2 * (v * hh).sum(1, keepdims=True) * hh - v
    l = np.where(pick[:, None], l_cos, l_ggx)
    l /= np.linalg.norm(l, axis=1, keepdims=True)
    h = l + v
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    n_h = np.clip(h[:, 2], 0, 1)
    v_h = np.maximum((v * h).sum(1), 1e-8)
    d = n_h * n_h * (a2 - 1.0) + 1.0
    D = a2 / (math.pi * d * d)
    pdf = 0.5 * np.maximum(l[:, 2], 0) / math.pi + 0.5 * D * n_h / (4 * v_h)
    f = renderer_brdf_cos(m, v, l)
    w = np.where((l[:, 2] > 0)[:, None] & (pdf > 0)[:, None], f / np.maximum(pdf, 1e-30)[:, None], 0.0)
    return w.mean(0)


# ---------------------------------------------------------------- Mitsuba


def mitsuba_albedo(bsdf, theta_deg: float, n: int, rng) -> np.ndarray:
    import mitsuba as mi

    th = math.radians(theta_deg)
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(math.sin(th), 0.0, math.cos(th))
    u = rng.random((n, 3))
    acc = np.zeros(3)
    for i in range(n):
        _, w = bsdf.sample(ctx, si, float(u[i, 0]), mi.Point2f(float(u[i, 1]), float(u[i, 2])))
        acc += (w[0], w[1], w[2])
    return acc / n


def sphere_average(fn, n_mu: int = 24) -> np.ndarray:
    """integral_0^1 albedo(mu) 2 mu dmu by Gauss-Legendre in mu."""
    x, wts = np.polynomial.legendre.leggauss(n_mu)
    mu = 0.5 * (x + 1)
    return sum(w * 0.5 * 2 * m * fn(math.degrees(math.acos(m))) for m, w in zip(mu, wts))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=100_000, help="samples per angle per side")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "albedo.md")
    a = ap.parse_args()
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    entries: list[tuple[str, Material, str]] = []
    seen = set()
    for sc in scene_list().values():
        for m in sc.materials:
            if m.name in seen or m.transmission or any(m.emissive) or (m.metallic == 0 and m.ior == 1.0):
                continue
            seen.add(m.name)
            models = ["blend", "roughplastic", "diffuse"] if m.metallic == 0 else ["conductor"]
            entries += [(m.name, m, model) for model in models]
    # reference rows: the renderer's default material (white dielectric, roughness 0.5) and rough grey
    for m in (Material("default white (unset keys)", roughness=0.5, ior=1.5),
              Material("grey rough dielectric", base_color=(0.5,) * 3, roughness=1.0, ior=1.5)):
        entries += [(m.name, m, model) for model in ("blend", "roughplastic", "diffuse")]
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    md = ["# Material models: renderer BRDF vs its Mitsuba stand-in (directional albedo)\n",
          f"{now}, Mitsuba {mi.__version__} scalar_rgb, {a.samples} samples per angle and side "
          f"(Monte-Carlo noise about 0.1-0.5 %; the roughness-0 mirror rows are exact). Made by albedo.py: "
          "albedo(θo) = radiance towards a viewer at θo from the normal under a uniform white sky of "
          "radiance 1, single scattering. 'sphere' = the average over a sphere's visible disc: the ratio "
          "compare.py should find for an isolated sphere of that material under a uniform sky if the model "
          "were the only difference. compare.py uses the `blend` stand-in for opaque dielectrics unless told "
          "otherwise (`--dielectric-model`).\n",
          "| material | Mitsuba stand-in | sphere: renderer / Mitsuba (R G B) |", "|---|---|---|"]
    summary_at = len(md)
    rng = np.random.default_rng(1)
    for label, m, which in entries:
        bd, model, _ = m.mitsuba(which if which != "conductor" else "blend")
        bsdf = mi.load_dict(bd)
        md.append(f"## {label} → {which}: base {list(m.base_color[:3])}, metallic {m.metallic:g}, roughness "
                  f"{m.roughness:g}, ior {m.ior:g} → {model}\n")
        md.append("| θo | renderer R G B | Mitsuba R G B | renderer / Mitsuba |")
        md.append("|---|---|---|---|")
        cache_r, cache_m = {}, {}

        def fr(t):
            if t not in cache_r:
                cache_r[t] = renderer_albedo(m, t, a.samples, rng)
            return cache_r[t]

        def fm(t):
            if t not in cache_m:
                cache_m[t] = mitsuba_albedo(bsdf, t, a.samples, rng)
            return cache_m[t]

        for t in ANGLES:
            r, mm = fr(t), fm(t)
            md.append(f"| {t}° | {' '.join(f'{x:.4f}' for x in r)} | {' '.join(f'{x:.4f}' for x in mm)} | "
                      f"{' '.join(f'{x:.3f}' for x in r / mm)} |")
        rs, ms = sphere_average(fr), sphere_average(fm)
        ratio = " ".join(f"{x:.3f}" for x in rs / ms)
        md.append(f"| sphere | {' '.join(f'{x:.4f}' for x in rs)} | {' '.join(f'{x:.4f}' for x in ms)} | "
                  f"**{ratio}** |\n")
        md.insert(summary_at, f"| {label} (metallic {m.metallic:g}, roughness {m.roughness:g}) | {which} | {ratio} |")
        summary_at += 1
        print(f"{label} as {which}: sphere ratio {ratio}", flush=True)
    md.insert(summary_at, "")
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text("\n".join(md))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
