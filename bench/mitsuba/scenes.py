"""Test scenes for checking hybrid-rt's path tracer against Mitsuba 3.

Every scene is defined once here and emitted twice: as the renderer's TOML scene
(assets/SCENE_FORMAT.md) and as a Mitsuba 3 scene dict. All geometry goes to
both as the same Wavefront OBJ files, written in world space (no object
transforms on either side), so the triangles are identical:

* spheres are the renderer's own UV sphere (src/scene/primitives.rs `uv_sphere`,
  64 slices x 32 stacks by default: same vertices, smooth normals, uv, and the
  same triangles with the degenerate pole ones left out);
* planes, walls and boxes are quads (two triangles) with flat normals.

Usage:  python3 scenes.py [--out DIR] [SCENE ...]   writes DIR/<scene>/scene.toml
        python3 scenes.py --list
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
ENV_MAP = REPO / "assets" / "potsdamer_platz_512.hdr"

# ---------------------------------------------------------------- geometry


@dataclass
class Mesh:
    positions: np.ndarray  # Nx3
    normals: np.ndarray  # Nx3
    uvs: np.ndarray  # Nx2 (glTF convention: v down)
    triangles: np.ndarray  # Mx3, counter-clockwise seen from the side the normals point to


def uv_sphere(radius: float, center=(0.0, 0.0, 0.0), slices: int = 64, stacks: int = 32) -> Mesh:
    """The renderer's `uv_sphere`, moved to `center`."""
    slices, stacks = max(slices, 3), max(stacks, 2)
    pos, nor, uv = [], [], []
    for i in range(stacks + 1):
        v = i / stacks
        theta = v * math.pi
        for j in range(slices + 1):
            u = j / slices
            phi = u * 2.0 * math.pi
            st, ct, sp, cp = math.sin(theta), math.cos(theta), math.sin(phi), math.cos(phi)
            n = (st * cp, ct, -st * sp)
            nor.append(n)
            pos.append(tuple(center[k] + radius * n[k] for k in range(3)))
            uv.append((u, v))
    row = slices + 1
    tris = []
    for i in range(stacks):
        for j in range(slices):
            a = i * row + j
            b, c, d = a + row, a + row + 1, a + 1
            if i != stacks - 1:
                tris.append((a, b, c))
            if i != 0:
                tris.append((a, c, d))
    return Mesh(np.array(pos), np.array(nor), np.array(uv), np.array(tris))


def quad(p0, p1, p2, p3) -> Mesh:
    """A flat quad with corners counter-clockwise seen from its front."""
    p = np.array([p0, p1, p2, p3], dtype=float)
    n = np.cross(p[1] - p[0], p[2] - p[0])
    n /= np.linalg.norm(n)
    return Mesh(p, np.tile(n, (4, 1)), np.array([[0, 1], [1, 1], [1, 0], [0, 0]], float),
                np.array([[0, 1, 2], [0, 2, 3]]))


def merge(*meshes: Mesh) -> Mesh:
    off, tris = 0, []
    for m in meshes:
        tris.append(m.triangles + off)
        off += len(m.positions)
    return Mesh(np.concatenate([m.positions for m in meshes]), np.concatenate([m.normals for m in meshes]),
                np.concatenate([m.uvs for m in meshes]), np.concatenate(tris))


def floor_plane(size: float, y: float = 0.0) -> Mesh:
    """The renderer's `plane` (XZ, facing +Y), size x size, at height y."""
    h = size / 2
    return quad((-h, y, h), (h, y, h), (h, y, -h), (-h, y, -h))


def box(center, size, yaw_deg: float = 0.0, inward: bool = False) -> Mesh:
    """An axis-aligned box of extents `size` turned by `yaw_deg` about +Y
    (positive turns +X towards -Z, the renderer's rotation_deg convention),
    24 vertices, flat faces. `inward` flips it (a room seen from inside)."""
    hx, hy, hz = (s / 2 for s in size)
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))

    def tr(x, y, z):  # rotation about +Y by yaw: x' = c x + s z, z' = -s x + c z
        return (center[0] + c * x + s * z, center[1] + y, center[2] - s * x + c * z)

    faces = [  # corners CCW seen from outside
        [(hx, -hy, hz), (hx, -hy, -hz), (hx, hy, -hz), (hx, hy, hz)],  # +X
        [(-hx, -hy, -hz), (-hx, -hy, hz), (-hx, hy, hz), (-hx, hy, -hz)],  # -X
        [(-hx, hy, hz), (hx, hy, hz), (hx, hy, -hz), (-hx, hy, -hz)],  # +Y
        [(-hx, -hy, -hz), (hx, -hy, -hz), (hx, -hy, hz), (-hx, -hy, hz)],  # -Y
        [(-hx, -hy, hz), (hx, -hy, hz), (hx, hy, hz), (-hx, hy, hz)],  # +Z
        [(hx, -hy, -hz), (-hx, -hy, -hz), (-hx, hy, -hz), (hx, hy, -hz)],  # -Z
    ]
    quads = []
    for f in faces:
        pts = [tr(*p) for p in f]
        if inward:
            pts = pts[::-1]
        quads.append(quad(*pts))
    return merge(*quads)


def mitsuba_env_map(src: Path, out_dir: Path, factor: int = 2) -> Path:
    """The equirect map resampled so that Mitsuba's `envmap` returns what the
    renderer's GPU sampler returns.

    Both put texel centres at u = (i + 0.5) / w (after the 180 degree turn), but
    Mitsuba puts row j at v = j / (h - 1) (first and last rows on the poles)
    where the renderer's bilinear sampler has it at v = (j + 0.5) / h (clamp to
    edge): up to half a texel apart near the poles (check_conventions.py). This
    writes factor * h + 1 rows, row k holding the renderer's lookup at
    v = k / (factor * h). With an even factor every kink of the renderer's
    piecewise-linear profile, v = (j + 0.5) / h, is one of those rows, so
    Mitsuba's bilinear lookup equals the renderer's (measured: 6e-5 relative at
    worst). Values are the file decoded as the renderer decodes it (image crate:
    no half-step offset); the renderer's half-float upload (maps <= 65504) is
    not modelled (2^-11 relative)."""
    import hdrio

    dst = out_dir / f"{src.stem}_mitsuba_x{factor}.exr"
    if dst.exists() and dst.stat().st_mtime >= src.stat().st_mtime:
        return dst
    img = hdrio.read_hdr(src, centre=False).astype(np.float64)
    h = img.shape[0]
    n = factor * h + 1
    y = np.arange(n) / (factor * h) * h - 0.5
    y0 = np.floor(y).astype(int)
    f = (y - y0)[:, None, None]
    a, b = np.clip(y0, 0, h - 1), np.clip(y0 + 1, 0, h - 1)
    out = ((1 - f) * img[a] + f * img[b]).astype(np.float32)
    import mitsuba as mi

    mi.Bitmap(out).write(str(dst))
    return dst


def write_obj(path: Path, mesh: Mesh) -> None:
    lines = [f"# bench/mitsuba/scenes.py: {len(mesh.positions)} vertices, {len(mesh.triangles)} triangles"]
    lines += [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in mesh.positions]
    lines += [f"vt {u:.9g} {1.0 - v:.9g}" for u, v in mesh.uvs]  # OBJ's v points up
    lines += [f"vn {x:.9g} {y:.9g} {z:.9g}" for x, y, z in mesh.normals]
    lines += ["f " + " ".join(f"{i + 1}/{i + 1}/{i + 1}" for i in t) for t in mesh.triangles]
    path.write_text("\n".join(lines) + "\n")


# ---------------------------------------------------------------- materials


@dataclass
class Material:
    """A renderer (glTF metal/rough) material; `mitsuba()` gives the closest
    Mitsuba BSDF and says how close it is."""

    name: str
    base_color: tuple = (1.0, 1.0, 1.0)
    metallic: float = 0.0
    roughness: float = 0.5
    ior: float = 1.5
    transmission: float = 0.0
    emissive: tuple = (0.0, 0.0, 0.0)
    emissive_strength: float = 1.0

    def toml(self) -> str:
        s = [f'[[material]]\nname = "{self.name}"', f"base_color = {_vec(self.base_color)}",
             f"metallic = {_f(self.metallic)}", f"roughness = {_f(self.roughness)}", f"ior = {_f(self.ior)}"]
        if self.transmission:
            s.append(f"transmission = {_f(self.transmission)}")
        if any(self.emissive):
            s.append(f"emissive = {_vec(self.emissive)}")
            s.append(f"emissive_strength = {_f(self.emissive_strength)}")
        return "\n".join(s) + "\n"

    def mitsuba(self, dielectric: str = "blend") -> tuple[dict, str, str]:
        """(bsdf dict, model name, expected residual against the renderer).
        `dielectric` picks the stand-in for opaque dielectrics with ior > 1:
        "blend" (default), "roughplastic" or "diffuse"."""
        rgb = {"type": "rgb", "value": list(self.base_color[:3])}
        r = self.roughness
        alpha = max(r * r, 1e-3)  # the renderer clamps alpha = roughness^2 at 1e-3 too
        if self.transmission >= 1.0:
            if self.metallic != 0.0:
                raise ValueError(f"{self.name}: transmissive metal is not mapped")
            if r == 0.0:
                return ({"type": "dielectric", "int_ior": self.ior, "ext_ior": 1.0},
                        f"dielectric (ior {self.ior:g})",
                        "exact Fresnel on both sides: none expected. Both treat glass as opaque to shadow "
                        "rays (renderer: FRAME_OPAQUE_OCCLUDERS), so neither has the sun's caustic; "
                        "Mitsuba scales radiance by 1/eta^2 inside (cancels for closed objects)")
            return ({"type": "roughdielectric", "distribution": "ggx", "alpha": alpha,
                     "int_ior": self.ior, "ext_ior": 1.0},
                    f"roughdielectric (ggx, alpha {alpha:.4g})", "model-dependent (not characterised)")
        if self.transmission != 0.0:
            raise ValueError(f"{self.name}: partial transmission is not mapped")
        if self.metallic == 1.0:
            if r == 0.0:
                return (_twosided({"type": "conductor", "material": "none", "specular_reflectance": rgb}),
                        "conductor (material none, F = base colour)",
                        "renderer: Schlick F rising to 1 at grazing; Mitsuba: constant F = base colour "
                        "(renderer +0.3 % on a sphere under a uniform sky, +3 % at 85°); both are delta "
                        "mirrors, so neither shows the sun in it")
            return (_twosided({"type": "roughconductor", "distribution": "ggx", "alpha": alpha,
                               "material": "none", "specular_reflectance": rgb}),
                    f"roughconductor (ggx, alpha {alpha:.4g}, F = base colour)",
                    "Schlick vs constant F (renderer brighter towards grazing) and height-correlated vs "
                    "separable Smith G: gold under a uniform sky +0.2/+0.9/+5 % (R/G/B), both "
                    "single-scattering (albedo.py)")
        if self.metallic != 0.0:
            raise ValueError(f"{self.name}: metallic must be 0 or 1 here")
        if any(self.emissive):
            # emitter shapes: black diffuse base (asserted) + an area emitter added by the scene
            if any(self.base_color[:3]) or self.ior != 1.0:
                raise ValueError(f"{self.name}: emissive materials here must be black with ior 1")
            return (_twosided({"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}),
                    "area emitter + black diffuse", "none expected (one-sided emitter; its back faces out of the room)")
        if self.ior == 1.0:
            # f0 = f90 = 0: the renderer's BRDF is exactly base/pi (brdf.glsl)
            return (_twosided({"type": "diffuse", "reflectance": rgb}), "diffuse (Lambert)",
                    "none: with ior 1 the renderer's F0 and F90 are 0, its BRDF is exactly base/pi")
        return self._dielectric(dielectric, rgb, alpha)

    def _dielectric(self, model: str, rgb: dict, alpha: float) -> tuple[dict, str, str]:
        """Opaque dielectric with ior > 1: renderer (1 - F(v.h)) base/pi + GGX spec (Schlick F, f0 from ior)."""
        f0 = ((self.ior - 1.0) / (self.ior + 1.0)) ** 2
        if model == "blend":
            # The renderer's structure, a sum without layering: diffuse scaled by
            # 1 - f0 plus a GGX lobe with the exact dielectric Fresnel (a roughconductor
            # with eta = ior, k = 0). blendbsdf is (1 - w) A + w B, and an RGB reflectance
            # must be <= 1, so A = (1 - f0) base / (1 - w) with w = 1 - (1 - f0) max(base)
            # and B's reflectance 1/w (a plain float may exceed 1).
            k = 1.0 - f0
            w = max(1.0 - k * max(self.base_color[:3]), 0.02)
            b = {"type": "blendbsdf", "weight": w,
                 "bsdf_0": {"type": "diffuse", "reflectance": {
                     "type": "rgb", "value": [k * c / (1.0 - w) for c in self.base_color[:3]]}},
                 "bsdf_1": {"type": "roughconductor", "distribution": "ggx", "alpha": alpha, "eta": self.ior,
                            "k": 0.0, "specular_reflectance": 1.0 / w}}
            return (_twosided(b), f"blend: (1-f0)·diffuse + ggx lobe (alpha {alpha:.4g}, exact F, eta {self.ior:g})",
                    "Schlick vs exact Fresnel (exact is higher at 40-70°: spec up to ~20 % apart, a few % "
                    "of the total on dark colours), (1-F(v.h)) vs constant 1-f0 on the diffuse part, "
                    "separable vs height-correlated Smith G: ~1 % on neutral colours, up to 5 % on the "
                    "weak channels of saturated ones (albedo.py)")
        if model == "roughplastic":
            return (_twosided({"type": "roughplastic", "distribution": "ggx", "alpha": alpha, "int_ior": self.ior,
                               "ext_ior": 1.0, "nonlinear": False, "diffuse_reflectance": rgb}),
                    f"roughplastic (ggx, alpha {alpha:.4g}, ior {self.ior:g}, nonlinear false)",
                    "layered: Mitsuba's albedo falls with roughness (white: 0.95 at alpha 0.06, 0.74 at 0.25, "
                    "0.34 at 1), so only close at low roughness (albedo.py)")
        if model == "diffuse":
            return (_twosided({"type": "diffuse", "reflectance": rgb}), "diffuse (Lambert, no specular lobe)",
                    "no specular lobe: ~1-4 % on white, far off on the weak channels of saturated colours "
                    "(the renderer's white highlight), albedo.py")
        raise ValueError(f"unknown dielectric model {model!r}")


def _twosided(b: dict) -> dict:
    # the renderer shades back faces with the normal flipped to the viewer's side
    return {"type": "twosided", "bsdf": b}


def _f(x: float) -> str:
    return repr(float(x))


def _vec(v) -> str:
    return "[" + ", ".join(_f(x) for x in v) + "]"


# ---------------------------------------------------------------- scenes


@dataclass
class Obj:
    name: str
    mesh: Mesh
    material: str


@dataclass
class Light:
    type: str  # "directional" | "point"
    color: tuple = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    direction: tuple | None = None  # directional: the way the light travels
    position: tuple | None = None  # point


@dataclass
class Scene:
    name: str
    summary: str
    checks: str
    camera_pos: tuple
    camera_target: tuple
    yfov_deg: float
    materials: list[Material]
    objects: list[Obj]
    env_color: tuple | None = (0.0, 0.0, 0.0)  # constant sky (None when env_hdr is set)
    env_hdr: Path | None = None
    env_intensity: float = 1.0
    lights: list[Light] = field(default_factory=list)
    camera_up: tuple = (0.0, 1.0, 0.0)
    exposure: float = 1.0  # for `hybrid-rt compare --exposure` and the PNG previews
    expected: dict = field(default_factory=dict)  # object name -> exact linear RGB radiance

    def material(self, name: str) -> Material:
        return next(m for m in self.materials if m.name == name)

    # -- renderer side
    def write(self, out_dir: Path) -> Path:
        """Writes the OBJ files and scene.toml into out_dir; returns the TOML path."""
        out_dir.mkdir(parents=True, exist_ok=True)
        t = [f"# {self.name}: {self.summary}\n# generated by bench/mitsuba/scenes.py, do not edit\n"]
        t.append("[environment]")
        if self.env_hdr is not None:
            t.append(f'hdr = "{Path(self.env_hdr).resolve()}"')
        else:
            t.append(f"color = {_vec(self.env_color)}")
        t.append(f"intensity = {_f(self.env_intensity)}\n")
        t.append(f'[[camera]]\nname = "main"\nposition = {_vec(self.camera_pos)}\ntarget = {_vec(self.camera_target)}\n'
                 f"up = {_vec(self.camera_up)}\nyfov_deg = {_f(self.yfov_deg)}\n")
        if not self.lights:
            # The renderer adds a default sun (3 lux) to a scene without lights
            # (src/scene/camera.rs add_defaults); a black light keeps it out.
            t.append('# no light: this black one stops the renderer from adding its default sun\n'
                     '[[light]]\ntype = "directional"\nname = "none"\nintensity = 0.0\n'
                     'direction = [0.0, -1.0, 0.0]\ncasts_shadows = false\n')
        for i, light in enumerate(self.lights):
            s = f'[[light]]\ntype = "{light.type}"\nname = "light{i}"\ncolor = {_vec(light.color)}\n' \
                f"intensity = {_f(light.intensity)}\n"
            if light.type == "directional":
                s += f"direction = {_vec(light.direction)}\n"
            elif light.type == "point":
                s += f"position = {_vec(light.position)}\n"  # no range: plain 1/d^2
            else:
                raise ValueError(light.type)
            t.append(s)
        for m in self.materials:
            t.append(m.toml())
        for o in self.objects:
            write_obj(out_dir / f"{o.name}.obj", o.mesh)
            t.append(f'[[object]]\nname = "{o.name}"\nobj = "{o.name}.obj"\nmaterial = "{o.material}"\n')
        path = out_dir / "scene.toml"
        path.write_text("\n".join(t))
        return path

    # -- Mitsuba side
    def mitsuba_dict(self, out_dir: Path, width: int, height: int, spp: int, max_depth: int = -1,
                     rr_depth: int = 5, dielectric: str = "blend") -> dict:
        """The Mitsuba scene (call after write(): it loads the same OBJ files)."""
        import mitsuba as mi

        T = mi.ScalarTransform4f
        d = {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth, "hide_emitters": False},
            "sensor": {
                "type": "perspective",
                "fov_axis": "y",
                "fov": self.yfov_deg,
                "near_clip": 0.01,
                "far_clip": 1e5,
                "to_world": T().look_at(origin=list(self.camera_pos), target=list(self.camera_target),
                                        up=list(self.camera_up)),
                "sampler": {"type": "independent", "sample_count": spp},
                "film": {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb",
                         "component_format": "float32", "rfilter": {"type": "box"}},
            },
        }
        if self.env_hdr is not None:
            # Mitsuba's equirect has -Z at u = 0, the renderer's (env.glsl) at u = 0.5:
            # a half turn about +Y lines them up; the rows are resampled for v
            # (mitsuba_env_map; check_conventions.py measures both).
            env_file = mitsuba_env_map(Path(self.env_hdr).resolve(), out_dir)
            d["env"] = {"type": "envmap", "filename": str(env_file),
                        "scale": self.env_intensity, "to_world": T().rotate([0, 1, 0], 180.0)}
        elif any(self.env_color):
            d["env"] = {"type": "constant", "radiance": {
                "type": "rgb", "value": [c * self.env_intensity for c in self.env_color]}}
        for i, light in enumerate(self.lights):
            val = {"type": "rgb", "value": [c * light.intensity for c in light.color]}
            if light.type == "directional":  # renderer lux = irradiance normal to the light
                d[f"light{i}"] = {"type": "directional", "direction": list(light.direction), "irradiance": val}
            else:  # candela -> W/sr: irradiance I/d^2 on both sides
                d[f"light{i}"] = {"type": "point", "position": list(light.position), "intensity": val}
        for o in self.objects:
            m = self.material(o.material)
            bsdf, _, _ = m.mitsuba(dielectric)
            shape = {"type": "obj", "filename": str((out_dir / f"{o.name}.obj").resolve()),
                     "face_normals": False, "bsdf": bsdf}
            if any(m.emissive):
                shape["emitter"] = {"type": "area", "radiance": {
                    "type": "rgb", "value": [c * m.emissive_strength for c in m.emissive]}}
            d[o.name] = shape
        return d


# ---- shared pieces

SKY = (0.6, 0.7, 0.9)
SUN = Light("directional", color=(1.0, 0.95, 0.85), intensity=3.0, direction=(-0.4, -1.0, -0.3))


def _five_sphere_materials() -> list[Material]:
    return [
        Material("floor", base_color=(0.5, 0.5, 0.5), roughness=1.0, ior=1.0),
        Material("red_diffuse", base_color=(0.8, 0.08, 0.06), roughness=1.0, ior=1.0),
        Material("mirror", base_color=(0.95, 0.95, 0.95), metallic=1.0, roughness=0.0),
        Material("glass", base_color=(1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=1.5),
        Material("gold", base_color=(1.0, 0.766, 0.336), metallic=1.0, roughness=0.45),
        Material("blue_plastic", base_color=(0.05, 0.15, 0.7), roughness=0.25, ior=1.5),
    ]


def _five_sphere_objects() -> list[Obj]:
    # radius 0.5, sunk 1 mm into the floor (SCENE_FORMAT.md: no coincident contact)
    names = ["red_diffuse", "mirror", "glass", "gold", "blue_plastic"]
    objs = [Obj("floor", floor_plane(20.0), "floor")]
    for i, n in enumerate(names):
        objs.append(Obj(f"sphere_{n}", uv_sphere(0.5, ((i - 2) * 1.15, 0.499, 0.0)), n))
    return objs


def _room(light: str) -> Scene:
    """A closed 3 x 2.4 x 3 m Cornell-like room. The ceiling has a 0.6 m square
    hole that the lamp quad fills exactly, facing down, so the lamp's back side
    faces out of the room (into black): one- or two-sided emission agree."""
    X, Y, Z, L = 1.5, 2.4, 1.5, 0.3
    walls = {
        "room_floor": quad((-X, 0, Z), (X, 0, Z), (X, 0, -Z), (-X, 0, -Z)),
        "room_back": quad((-X, 0, -Z), (X, 0, -Z), (X, Y, -Z), (-X, Y, -Z)),
        "room_front": quad((X, 0, Z), (-X, 0, Z), (-X, Y, Z), (X, Y, Z)),
        "room_left": quad((-X, 0, Z), (-X, 0, -Z), (-X, Y, -Z), (-X, Y, Z)),
        "room_right": quad((X, 0, -Z), (X, 0, Z), (X, Y, Z), (X, Y, -Z)),
    }
    if light == "area":
        ceiling = merge(  # facing down, around the lamp's hole
            quad((-X, Y, -Z), (X, Y, -Z), (X, Y, -L), (-X, Y, -L)),
            quad((-X, Y, L), (X, Y, L), (X, Y, Z), (-X, Y, Z)),
            quad((-X, Y, -L), (-L, Y, -L), (-L, Y, L), (-X, Y, L)),
            quad((L, Y, -L), (X, Y, -L), (X, Y, L), (L, Y, L)),
        )
    else:
        ceiling = quad((-X, Y, -Z), (X, Y, -Z), (X, Y, Z), (-X, Y, Z))
    mats = [
        Material("white", base_color=(0.73, 0.73, 0.73), roughness=1.0, ior=1.0),
        Material("red", base_color=(0.63, 0.065, 0.05), roughness=1.0, ior=1.0),
        Material("green", base_color=(0.14, 0.45, 0.09), roughness=1.0, ior=1.0),
    ]
    wall_mat = {"room_left": "red", "room_right": "green"}
    objs = [Obj(n, m, wall_mat.get(n, "white")) for n, m in walls.items()]
    objs.append(Obj("room_ceiling", ceiling, "white"))
    objs.append(Obj("sphere", uv_sphere(0.4, (-0.6, 0.399, -0.4)), "white"))
    objs.append(Obj("block", box((0.55, 0.599, -0.65), (0.6, 1.2, 0.6), yaw_deg=20.0), "white"))
    lights = []
    if light == "area":
        mats.append(Material("lamp", base_color=(0.0, 0.0, 0.0), roughness=1.0, ior=1.0,
                             emissive=(1.0, 0.9, 0.75), emissive_strength=15.0))
        objs.append(Obj("lamp", quad((-L, Y, -L), (L, Y, -L), (L, Y, L), (-L, Y, L)), "lamp"))
        summary = "closed room lit by a 0.6 m square emissive quad in the ceiling"
        checks = ("emissive surfaces as lights (NEE on emissive triangles, MIS), many diffuse bounces "
                  "(a converged reference: Mitsuba's path depth is unbounded, Russian roulette from depth 5)")
    else:
        lights.append(Light("point", color=(1.0, 0.9, 0.75), intensity=3.0, position=(0.0, 2.0, 0.0)))
        summary = "closed room lit by a 3 cd point light (no range)"
        checks = ("point light units (candela: irradiance I/d^2, no window), shadows, many diffuse bounces")
    return Scene(
        name=f"room_{light}", summary=summary, checks=checks,
        camera_pos=(0.0, 1.2, 1.45), camera_target=(0.0, 1.05, -1.5), yfov_deg=55.0,
        materials=mats, objects=objs, env_color=(0.0, 0.0, 0.0), lights=lights, exposure=2.0,
    )


def _furnace(albedo: float) -> Scene:
    return Scene(
        name="furnace" if albedo != 1.0 else "furnace_white",
        summary=f"one Lambert sphere (albedo {albedo:g}, ior 1) alone under a constant white sky of radiance 1",
        checks=("the estimator's normalisation: a convex Lambert object under a uniform sky has radiance "
                "albedo x sky everywhere (one bounce, no self-occlusion); exact, both sides"),
        camera_pos=(0.0, 0.0, 4.0), camera_target=(0.0, 0.0, 0.0), yfov_deg=30.0,
        materials=[Material("white", base_color=(albedo,) * 3, roughness=1.0, ior=1.0)],
        objects=[Obj("sphere", uv_sphere(0.8, (0.0, 0.0, 0.0)), "white")],
        env_color=(1.0, 1.0, 1.0), exposure=1.0,
        expected={"sphere": (albedo,) * 3, "background": (1.0, 1.0, 1.0)},
    )


def scene_list() -> dict[str, Scene]:
    five_m, five_o = _five_sphere_materials(), _five_sphere_objects()
    scenes = [
        Scene(
            name="orient",
            summary="red Lambert sphere at +X, green at +Y, blue cube at -X-Y, under a constant sky",
            checks=("image orientation and camera convention: red must be right, green top, blue bottom left; "
                    "the per-object table is nonsense if either image is mirrored or flipped"),
            camera_pos=(0.0, 0.0, 5.0), camera_target=(0.0, 0.0, 0.0), yfov_deg=40.0,
            materials=[Material("red", base_color=(0.8, 0.05, 0.05), roughness=1.0, ior=1.0),
                       Material("green", base_color=(0.05, 0.8, 0.05), roughness=1.0, ior=1.0),
                       Material("blue", base_color=(0.05, 0.05, 0.8), roughness=1.0, ior=1.0)],
            objects=[Obj("red_right", uv_sphere(0.5, (1.6, 0.0, 0.0)), "red"),
                     Obj("green_top", uv_sphere(0.5, (0.0, 1.0, 0.0)), "green"),
                     Obj("blue_bottom_left", box((-1.6, -0.9, 0.0), (0.8, 0.8, 0.8), yaw_deg=30.0), "blue")],
            env_color=(1.0, 1.0, 1.0), exposure=1.0,
        ),
        _furnace(0.8),
        _furnace(1.0),
        Scene(
            name="sun_plane",
            summary="a Lambert floor (albedo 0.5, ior 1) under a 2 lux sun from (-0.3, 1, -0.2), black sky",
            checks=("directional light units: lux is the irradiance normal to the light, so the floor's "
                    "radiance is albedo x E x cos / pi everywhere (exact, one bounce)"),
            camera_pos=(0.0, 3.0, 3.0), camera_target=(0.0, 0.0, 0.0), yfov_deg=40.0,
            materials=[Material("floor", base_color=(0.5, 0.5, 0.5), roughness=1.0, ior=1.0)],
            objects=[Obj("floor", floor_plane(20.0), "floor")],
            env_color=(0.0, 0.0, 0.0),
            lights=[Light("directional", intensity=2.0, direction=(0.3, -1.0, 0.2))],
            exposure=2.0,
            expected={"floor": (0.5 * 2.0 / math.sqrt(0.3 ** 2 + 1 + 0.2 ** 2) / math.pi,) * 3},
        ),
        Scene(
            name="spheres_sun",
            summary="five spheres (red Lambert, mirror, glass, gold rough 0.45, blue plastic rough 0.25) on a "
                    "grey Lambert floor, constant sky + sun",
            checks=("directional light units (lux = irradiance) and shadows, the sky as light, each material "
                    "model against its closest Mitsuba BSDF, glass and mirror paths"),
            camera_pos=(0.0, 1.6, 5.0), camera_target=(0.0, 0.45, 0.0), yfov_deg=40.0,
            materials=five_m, objects=five_o, env_color=SKY, lights=[SUN], exposure=1.0,
        ),
        Scene(
            name="spheres_env",
            summary="the same five spheres and floor under assets/potsdamer_platz_512.hdr, no sun",
            checks=("the environment map as light and background: equirect orientation (u = atan2(x,-z)/2pi "
                    "+ 0.5), its importance sampling, reflections and refraction of the map"),
            camera_pos=(0.0, 1.6, 5.0), camera_target=(0.0, 0.45, 0.0), yfov_deg=40.0,
            materials=five_m, objects=five_o, env_color=None, env_hdr=ENV_MAP, exposure=1.0,
        ),
        Scene(
            name="glass_caustic",
            summary="a glass sphere (ior 1.5) on a grey Lambert floor, constant sky + sun",
            checks=("refraction and the sky's caustic under the sphere (the sun's caustic is missing on both "
                    "sides by construction: a delta light seen through a delta BSDF cannot be reached by "
                    "path tracing with next-event estimation), shadow of a glass object"),
            camera_pos=(0.0, 1.8, 2.6), camera_target=(0.0, 0.3, 0.0), yfov_deg=40.0,
            materials=[five_m[0], five_m[3]],
            objects=[Obj("floor", floor_plane(20.0), "floor"), Obj("sphere_glass", uv_sphere(0.5, (0.0, 0.499, 0.0)), "glass")],
            env_color=SKY, lights=[SUN], exposure=1.0,
        ),
        _room("area"),
        _room("point"),
    ]
    return {s.name: s for s in scenes}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", help="scene names (default: all)")
    ap.add_argument("--out", type=Path, default=HERE / "out", help="output folder (default bench/mitsuba/out)")
    ap.add_argument("--list", action="store_true", help="list the scenes and what they check")
    a = ap.parse_args()
    all_scenes = scene_list()
    if a.list:
        for s in all_scenes.values():
            print(f"{s.name}: {s.summary}\n    checks: {s.checks}")
            for m in s.materials:
                _, model, residual = m.mitsuba()
                print(f"    {m.name}: -> {model}; expected: {residual}")
        return
    for name in a.scenes or all_scenes:
        if name not in all_scenes:
            raise SystemExit(f"unknown scene {name!r}; known: {', '.join(all_scenes)}")
        print(all_scenes[name].write(a.out / name))


if __name__ == "__main__":
    main()
