// The path tracer's BSDF: the raster's opaque metallic-roughness model (brdf.glsl) plus the
// transmissive share as a dielectric interface with exact Fresnel (fresnel.glsl), rough by GGX
// (Walter et al. 2007) or, below DELTA_ALPHA, perfectly specular as in integrator.glsl's branches.
// A clearcoat adds its own GGX lobe (brdf.glsl's coat: Schlick from 0.04, the layer under it weighted
// by 1 - coat_weight), sampled in its own frame.
// Sampled by visible normals (Heitz 2018) and cosine; every non-delta lobe enters the MIS mixture pdf.
// Local frame: shading normal +z, viewer above it (face_viewer).
#ifndef PATH_BSDF_GLSL
#define PATH_BSDF_GLSL
#include "../common/brdf.glsl"
#include "../common/split_sum.glsl"
#include "../common/fresnel.glsl"
#include "../common/sampling.glsl"

// Below this alpha (roughness ~0.03) specular lobes are deltas, never met by a light sample. Equals
// the raster's alpha floor (brdf.glsl), above which both evaluate the same lobe.
const float DELTA_ALPHA = 1e-3;

struct Bsdf {
    vec3 t, b, n;
    vec3 f0;         // Schlick reflectance of the opaque part (surface_f0)
    float f90;       // and its grazing reflectance (surface_f90)
    vec3 ms;         // its lobe's multiple-scattering compensation (split_sum.glsl), as the raster's
    float alpha;     // GGX alpha (roughness^2, at least DELTA_ALPHA)
    bool delta;      // perfect specular lobes
    float spec_w;    // weight of the opaque part's specular lobe: 1 - tm
    vec3 diffuse;    // Lambert albedo before 1 - F: (1 - metallic)(1 - transmission) base
    float tm;        // weight of the dielectric interface: transmission (1 - metallic)
    float eta;       // n on v's side / n on the other side
    vec3 tint;       // transmitted light's tint (base colour, per crossing)
    // KHR_materials_clearcoat: the coat's weight (0: none), unit normal (world), GGX alpha and whether
    // it is a delta; the lobes above already carry the 1 - coat_weight it lets through.
    float coat;
    vec3 coat_n;
    float coat_alpha;
    bool coat_delta;
    float p_coat, p_spec, p_diff;  // lobe choice; the interface gets the rest
};

struct BsdfSample {
    vec3 l;          // local
    vec3 weight;     // f |cos| / pdf
    float pdf;       // mixture pdf (0 for a delta lobe)
    bool delta;
};

Bsdf bsdf_at(Surface s, vec3 v, bool back_face) {
    Bsdf m;
    m.n = s.normal;
    basis_of(m.n, m.t, m.b);
    float a = s.roughness * s.roughness;
    m.delta = a < DELTA_ALPHA;
    m.alpha = max(a, DELTA_ALPHA);
    m.f0 = surface_f0(s);
    m.f90 = surface_f90(s);
    m.ms = ms_compensation(m.f0, max(dot(m.n, v), 1e-4), s.roughness);
    float cw = coat_weight(s, v), keep = 1.0 - cw;
    m.tm = s.transmission * (1.0 - s.metallic);
    m.spec_w = (1.0 - m.tm) * keep;
    m.diffuse = (1.0 - s.metallic) * (1.0 - s.transmission) * s.base_color * keep;
    m.tm *= keep;
    m.coat = s.clearcoat;
    m.coat_n = s.clearcoat_normal;
    float ca = s.clearcoat_roughness * s.clearcoat_roughness;
    m.coat_delta = ca < DELTA_ALPHA;
    m.coat_alpha = max(ca, DELTA_ALPHA);
    m.eta = back_face ? s.ior : 1.0 / max(s.ior, 1e-3);
    m.tint = s.base_color;
    // In proportion to each lobe's albedo estimate at n.v.
    vec3 fv = f_schlick(m.f0, m.f90, max(dot(m.n, v), 1e-4));
    float ws = m.spec_w * max3(fv), wd = max3(m.diffuse * (1.0 - fv)), wg = m.tm;
    float sum = ws + wd + wg + cw;
    m.p_coat = sum > 0.0 ? cw / sum : 0.0;
    m.p_spec = sum > 0.0 ? ws / sum : 0.0;
    m.p_diff = sum > 0.0 ? wd / sum : 0.0;
    return m;
}

vec3 bsdf_local(Bsdf m, vec3 w) {
    return vec3(dot(w, m.t), dot(w, m.b), dot(w, m.n));
}

vec3 bsdf_world(Bsdf m, vec3 w) {
    return m.t * w.x + m.b * w.y + m.n * w.z;
}

float bsdf_p_glass(Bsdf m) {
    return max(1.0 - m.p_coat - m.p_spec - m.p_diff, 0.0);
}

// The coat's normal in the local frame.
vec3 coat_local(Bsdf m) {
    return normalize(bsdf_local(m, m.coat_n));
}


// An IOR-1 interface does not bend or reflect: a straight passthrough.
bool ior_one(Bsdf m) {
    return abs(m.eta - 1.0) < 1e-6;
}

// Written with sin^2 from x, y: 1 - cos^2 loses precision near the normal at tiny alpha.
float ggx_d(vec3 h, float a2) {
    float d = h.z * h.z * a2 + (h.x * h.x + h.y * h.y);
    return a2 / max(PI * d * d, 1e-30);
}

// Smith's Lambda for GGX at |cos| c.
float ggx_lambda(float c, float a2) {
    float c2 = max(c * c, 1e-12);
    return 0.5 * (sqrt(1.0 + a2 * (1.0 - c2) / c2) - 1.0);
}

// The coat's lobe: f |n_c.l| (its own cosine, as brdf.glsl's), and its pdf (unweighted by p_coat).
vec3 coat_eval(Bsdf m, vec3 v, vec3 l, out float pdf) {
    pdf = 0.0;
    vec3 nc = coat_local(m);
    float cv = dot(nc, v), cl = dot(nc, l);
    if (m.coat_delta || cv <= 0.0 || cl <= 0.0) return vec3(0.0);
    vec3 h = normalize(v + l);
    float a2 = m.coat_alpha * m.coat_alpha;
    float d = d_ggx(dot(nc, h), a2);
    float lv = ggx_lambda(cv, a2);
    float fc = f_schlick(vec3(COAT_F0), 1.0, max(dot(v, h), 0.0)).x;
    pdf = d / ((1.0 + lv) * 4.0 * cv);
    return vec3(m.coat * fc * d / ((1.0 + lv + ggx_lambda(cl, a2)) * 4.0 * cv));
}

// f(v, l) |l.z| of the non-delta lobes (the coat's with its own cosine), and their mixture pdf of l.
vec3 bsdf_eval(Bsdf m, vec3 v, vec3 l, out float pdf) {
    pdf = 0.0;
    vec3 f = vec3(0.0);
    float vz = max(v.z, 1e-4);
    float a2 = m.alpha * m.alpha;
    float p_glass = bsdf_p_glass(m);
    bool has_interface = p_glass > 0.0 && !m.delta && !ior_one(m);
    if (l.z > 0.0) {
        vec3 h = normalize(v + l);
        float vh = max(dot(v, h), 0.0);
        vec3 fs = f_schlick(m.f0, m.f90, vh);
        if (m.p_diff > 0.0) {
            f += (1.0 - fs) * m.diffuse * (l.z / PI);
            pdf += m.p_diff * l.z / PI;
        }
        if (!m.delta && (m.p_spec > 0.0 || has_interface)) {
            float d = ggx_d(h, a2);
            float lv = ggx_lambda(vz, a2);
            float g1 = 1.0 / (1.0 + lv), g2 = 1.0 / (1.0 + lv + ggx_lambda(l.z, a2));
            float lobe = d * g2 / (4.0 * vz);
            float lobe_pdf = g1 * d / (4.0 * vz);
            f += m.spec_w * m.ms * fs * lobe;
            pdf += m.p_spec * lobe_pdf;
            if (has_interface) {
                float fr = fresnel_dielectric(vh, m.eta);
                f += vec3(m.tm * fr * lobe);
                pdf += p_glass * fr * lobe_pdf;
            }
        }
    } else if (l.z < 0.0 && has_interface) {
        // Refraction's half vector (Walter et al. 2007, eq. 16), on v's side.
        vec3 h = normalize(m.eta * v + l);
        if (h.z < 0.0) h = -h;
        float vh = dot(v, h), lh = dot(l, h);
        if (vh > 0.0 && lh < 0.0) {
            float fr = fresnel_dielectric(vh, m.eta);
            float denom = m.eta * vh + lh;
            float jac = -lh / max(denom * denom, 1e-12);  // dh/dl, over eta_t^2
            float d = ggx_d(h, a2);
            float lv = ggx_lambda(vz, a2);
            float g1 = 1.0 / (1.0 + lv), g2 = 1.0 / (1.0 + lv + ggx_lambda(-l.z, a2));
            f += m.tm * m.tint * ((1.0 - fr) * d * g2 * vh * jac / vz);
            pdf += p_glass * (1.0 - fr) * g1 * d * vh * jac / vz;
        }
    }
    if (m.p_coat > 0.0) {
        float coat_pdf;
        f += coat_eval(m, v, l, coat_pdf);
        pdf += m.p_coat * coat_pdf;
    }
    return f;
}

// False when the path ends (sample below the surface, or nothing reflected).
bool bsdf_sample(Bsdf m, vec3 v, inout uint rng, out BsdfSample bs) {
    float u = next_random(rng), u1 = next_random(rng), u2 = next_random(rng);
    float p_glass = bsdf_p_glass(m);
    bs.delta = false;
    bs.pdf = 0.0;
    bs.weight = vec3(0.0);
    if (u < m.p_coat) {
        vec3 nc = coat_local(m);
        float cv = dot(nc, v);
        if (cv <= 0.0) return false;
        if (m.coat_delta) {
            bs.l = reflect(-v, nc);
            bs.weight = vec3(m.coat * f_schlick(vec3(COAT_F0), 1.0, cv).x / m.p_coat);
            bs.delta = true;
            return bs.l.z > 0.0;
        }
        // Visible normals in the coat's own frame.
        vec3 ct, cb;
        basis_of(nc, ct, cb);
        vec3 h = sample_vndf(vec3(dot(v, ct), dot(v, cb), cv), m.coat_alpha, u1, u2);
        bs.l = reflect(-v, ct * h.x + cb * h.y + nc * h.z);
        if (dot(bs.l, nc) <= 0.0) return false;
    } else if (u < m.p_coat + m.p_spec) {
        if (m.delta) {
            bs.l = vec3(-v.x, -v.y, v.z);
            bs.weight = m.spec_w * f_schlick(m.f0, m.f90, max(v.z, 1e-4)) / m.p_spec;
            bs.delta = true;
            return true;
        }
        bs.l = reflect(-v, sample_vndf(v, m.alpha, u1, u2));
        // Below the surface: killed, so the mixture pdf need not count it.
        if (bs.l.z <= 0.0) return false;
    } else if (u < m.p_coat + m.p_spec + m.p_diff) {
        float r = sqrt(u1), phi = 2.0 * PI * u2;
        bs.l = vec3(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u1, 0.0)));
    } else {
        if (p_glass <= 0.0) return false;
        if (ior_one(m)) {
            bs.l = -v;
            bs.weight = m.tm * m.tint / p_glass;
            bs.delta = true;
            return true;
        }
        vec3 h = m.delta ? vec3(0.0, 0.0, 1.0) : sample_vndf(v, m.alpha, u1, u2);
        float fr = fresnel_dielectric(max(dot(v, h), 0.0), m.eta);
        bool reflects = next_random(rng) < fr;
        bs.l = reflects ? reflect(-v, h) : refract_dir(-v, h, m.eta);
        if (m.delta) {
            bs.weight = (reflects ? vec3(m.tm) : m.tm * m.tint) / p_glass;
            bs.delta = true;
            return dot(bs.l, bs.l) > 0.0;
        }
        if (reflects ? bs.l.z <= 0.0 : bs.l.z >= 0.0) return false;
    }
    if (bs.l.z == 0.0) return false;
    vec3 f = bsdf_eval(m, v, bs.l, bs.pdf);
    if (!(bs.pdf > 0.0)) return false;
    bs.weight = f / bs.pdf;
    return true;
}

#endif
