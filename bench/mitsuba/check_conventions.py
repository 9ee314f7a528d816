"""Measures the conventions compare.py relies on, without the renderer.

1. camera: Mitsuba's `perspective` (fov_axis y, look_at) ray through each pixel
   centre against the renderer's camera_ray_dir (glsl/common/primary_hit.glsl,
   src/scene/camera.rs: look_at_rh, reversed-Z projection with -f in [1][1]):
   row 0 = top, +x = right, same field of view;
2. environment map: Mitsuba `envmap` radiance for random directions against a
   numpy bilinear lookup of the same file with the renderer's env_uv
   (glsl/common/env.glsl: u = atan2(x, -z)/2pi + 0.5, v = acos(y)/pi; u repeats,
   v clamps), for to_world rotations of 0/90/180/270 degrees about +Y;
3. light units on Mitsuba's side: `directional` irradiance E on a Lambert plane
   gives a E cos/pi, `point` intensity I gives a I cos/(pi d^2), `constant`
   radiance L on a Lambert sphere gives a L (the renderer's KHR_lights_punctual
   lux / candela and sky radiance, glsl/common/lights.glsl);
4. hdrio.py reads RGBE files exactly as Mitsuba's Bitmap does (the shipped map).

  nice -n 19 python3 bench/mitsuba/check_conventions.py
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import hdrio  # noqa: E402
from scenes import ENV_MAP  # noqa: E402

import mitsuba as mi  # noqa: E402

mi.set_variant("scalar_rgb")
T = mi.ScalarTransform4f
failures = []


def check(ok: bool, what: str) -> None:
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def renderer_ray(eye, target, up, yfov_deg, w, h, px, py):
    """glsl camera_ray_dir(vec2(px, py)) for pixel coordinates (centre = i + 0.5)."""
    eye, target, up = (np.asarray(v, float) for v in (eye, target, up))
    f = target - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, up / np.linalg.norm(up))
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    view = np.array([s, u, -f])  # rows of glam's look_at_rh rotation
    fy = 1.0 / math.tan(math.radians(yfov_deg) / 2)
    aspect = w / h
    proj00, proj11 = fy / aspect, -fy
    ndc = np.array([px / w * 2 - 1, py / h * 2 - 1])
    dv = np.array([ndc[0] / proj00, ndc[1] / proj11, -1.0])
    d = view.T @ dv
    return d / np.linalg.norm(d)


def check_camera() -> None:
    w, h = 64, 36
    for eye, target, up, fov in [((0, 1.6, 5), (0, 0.45, 0), (0, 1, 0), 40.0),
                                 ((3, 2, -1), (-1, 0.5, 2), (0, 1, 0), 70.0),
                                 ((0, 1.2, 1.45), (0, 1.05, -1.5), (0.2, 1, 0), 55.0)]:
        s = mi.load_dict({"type": "scene", "sensor": {
            "type": "perspective", "fov_axis": "y", "fov": fov,
            "to_world": T().look_at(origin=list(eye), target=list(target), up=list(up)),
            "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"}}}})
        sensor = s.sensors()[0]
        worst = 0.0
        for py in (0, 7, 18, 35):
            for px in (0, 13, 32, 63):
                ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f((px + 0.5) / w, (py + 0.5) / h), mi.Point2f(0.5, 0.5))
                dm = np.array([ray.d[0], ray.d[1], ray.d[2]])
                dr_ = renderer_ray(eye, target, up, fov, w, h, px + 0.5, py + 0.5)
                dm /= np.linalg.norm(dm)
                worst = max(worst, math.degrees(math.atan2(np.linalg.norm(np.cross(dm, dr_)), float(dm @ dr_))))
        check(worst < 1e-4, f"camera eye {eye} fov {fov}: Mitsuba pixel-centre rays = renderer's "
                            f"(worst angle {worst:.2e} deg; row 0 top, +x right)")


def env_lookup(img: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The renderer's environment(dir): bilinear, u repeat, v clamp to edge."""
    h, w = img.shape[:2]
    u = math.atan2(d[0], -d[2]) / (2 * math.pi) + 0.5
    v = math.acos(max(-1.0, min(1.0, d[1]))) / math.pi
    x, y = u * w - 0.5, v * h - 0.5
    x0, y0 = math.floor(x), math.floor(y)
    fx, fy = x - x0, y - y0
    out = np.zeros(3)
    for dy, wy in ((0, 1 - fy), (1, fy)):
        for dx, wx in ((0, 1 - fx), (1, fx)):
            yy = min(max(y0 + dy, 0), h - 1)
            out += wy * wx * img[yy, (x0 + dx) % w]
    return out


def check_env() -> None:
    img = hdrio.read_hdr(ENV_MAP, centre=False)  # what both renderers load
    ref = np.array(mi.Bitmap(str(ENV_MAP)), dtype=np.float32)[..., :3]
    check(np.array_equal(img, ref), "hdrio.read_hdr(centre=False) == mi.Bitmap on the shipped map")
    rng = np.random.default_rng(1)
    dirs = rng.normal(size=(400, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    want = np.array([env_lookup(img, d) for d in dirs])
    errs = {}
    for rot in (0, 90, 180, 270):
        s = mi.load_dict({"type": "scene", "env": {"type": "envmap", "filename": str(ENV_MAP),
                                                   "to_world": T().rotate([0, 1, 0], float(rot))}})
        em = s.environment()
        got = []
        for d in dirs:
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(-d[0], -d[1], -d[2])  # eval looks along -wi
            v = em.eval(si)
            got.append([v[0], v[1], v[2]])
        got = np.array(got)
        errs[rot] = float(np.median(np.abs(got - want).sum(1) / (want.sum(1) + 1e-3)))
    best = min(errs, key=errs.get)
    print("     median relative |Mitsuba - renderer lookup| by to_world rotation: "
          + ", ".join(f"{r}: {e:.3f}" for r, e in errs.items()))
    check(best == 180 and errs[180] < 0.02, f"envmap to_world = rotate +Y 180 matches the renderer's equirect "
                                           f"(median relative difference {errs[180]:.4f})")

    def mitsuba_env(path):
        s = mi.load_dict({"type": "scene", "env": {"type": "envmap", "filename": str(path),
                                                   "to_world": T().rotate([0, 1, 0], 180.0)}})
        em = s.environment()
        got = []
        for d in dirs:
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(-d[0], -d[1], -d[2])
            v = em.eval(si)
            got.append([v[0], v[1], v[2]])
        return np.array(got)

    def rel(got, want):
        r = np.abs(got - want).sum(1) / (want.sum(1) + 1e-3)
        return float(np.median(r)), float(r.max())

    # Mitsuba's own row convention: v = j / (h - 1), u as the renderer's
    h, w = img.shape[:2]

    def corner_rows(d):
        u = math.atan2(d[0], -d[2]) / (2 * math.pi) + 0.5
        v = math.acos(max(-1.0, min(1.0, d[1]))) / math.pi
        x, y = u * w - 0.5, v * (h - 1)
        x0, y0 = math.floor(x), math.floor(y)
        fx, fy = x - x0, y - y0
        out = np.zeros(3)
        for dy, wy in ((0, 1 - fy), (1, fy)):
            for dx, wx in ((0, 1 - fx), (1, fx)):
                out += wy * wx * img[min(y0 + dy, h - 1), (x0 + dx) % w]
        return out

    raw = mitsuba_env(ENV_MAP)
    med, mx = rel(raw, np.array([corner_rows(d) for d in dirs]))
    check(mx < 1e-3, f"Mitsuba envmap rows sit at v = j/(h-1), not the GPU's (j+0.5)/h (model fits to {mx:.1e}); "
                     f"raw map vs renderer lookup: median {errs[180]:.4f}, up to half a texel off near the poles")
    import tempfile
    from scenes import mitsuba_env_map

    with tempfile.TemporaryDirectory() as t:
        fixed = mitsuba_env(mitsuba_env_map(ENV_MAP, Path(t)))
    med, mx = rel(fixed, want)
    check(med < 2e-3, f"resampled map (scenes.mitsuba_env_map) vs renderer lookup: median {med:.1e}, max {mx:.1e}")


def lambert_plane_radiance(emitter: dict, albedo: float, probe=(0.0, 0.0)) -> float:
    """Radiance leaving a Lambert plane y = 0 at the probe point, seen from straight above."""
    s = mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 0.5, "fov_axis": "y",
                   "to_world": T().look_at(origin=[probe[0], 3.0, probe[1]], target=[probe[0], 0.0, probe[1]],
                                           up=[0, 0, -1]),
                   "sampler": {"type": "independent", "sample_count": 16},
                   "film": {"type": "hdrfilm", "width": 4, "height": 4, "rfilter": {"type": "box"}}},
        "plane": {"type": "rectangle", "to_world": T().rotate([1, 0, 0], -90.0).scale(50.0),
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [albedo] * 3}}},
        "light": emitter})
    return float(np.array(mi.render(s))[..., 0].mean())


def check_lights() -> None:
    a = 0.5
    d = np.array([0.3, -1.0, 0.2])
    cos = 1.0 / np.linalg.norm(d)
    got = lambert_plane_radiance({"type": "directional", "direction": d.tolist(),
                                  "irradiance": {"type": "rgb", "value": [2.0] * 3}}, a)
    want = a * 2.0 * cos / math.pi
    check(abs(got / want - 1) < 1e-3, f"directional irradiance 2 on albedo {a}: {got:.5f} vs a E cos/pi = {want:.5f}")
    # point light 2 m above, probe 0.5 m off its foot: cos = 2/d, d^2 = 4.25
    got = lambert_plane_radiance({"type": "point", "position": [0.0, 2.0, 0.0],
                                  "intensity": {"type": "rgb", "value": [3.0] * 3}}, a, probe=(0.5, 0.0))
    d2 = 4.25
    want = a * 3.0 * (2.0 / math.sqrt(d2)) / (math.pi * d2)
    check(abs(got / want - 1) < 3e-3, f"point intensity 3 at 2 m, 0.5 m off: {got:.5f} vs a I cos/(pi d^2) = {want:.5f}")
    s = mi.load_dict({
        "type": "scene", "integrator": {"type": "path"},
        "sensor": {"type": "perspective", "fov": 5, "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
                   "sampler": {"type": "independent", "sample_count": 256},
                   "film": {"type": "hdrfilm", "width": 4, "height": 4, "rfilter": {"type": "box"}}},
        "ball": {"type": "sphere", "radius": 1.0, "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8] * 3}}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1.0] * 3}}})
    got = float(np.array(mi.render(s))[..., :3].mean())
    check(abs(got - 0.8) < 0.01, f"constant sky 1 on a Lambert sphere of albedo 0.8: {got:.4f} vs 0.8")


if __name__ == "__main__":
    print(f"Mitsuba {mi.__version__}, variant {mi.variant()}")
    check_camera()
    check_env()
    check_lights()
    print("all conventions as assumed" if not failures else f"{len(failures)} FAILED")
    sys.exit(1 if failures else 0)
