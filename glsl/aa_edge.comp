#version 460
// Pass `edge aa`: edge detection as in Shishkovtsov (GPU Gems 2 ch. 9; Sabino Eq. 4.2): squared
// depth and normal differences to the 8 neighbours give the blur factor B; B = 0 copies the input bits.
// The blend is not Eq. 4.2's plain neighbour mean: that softens every edge by a pixel and raised ꟻLIP vs
// a 4x4 supersampled reference on assets/aa_edges.toml (0.0062 -> 0.0105). Instead each of the 4
// edge-sharing neighbours weighs by its surface's exact screen-space coverage of this pixel (as in
// Persson's geometry-buffer AA), blended in linear display values.
#include "common/primary_hit.glsl"
#include "common/srgb.glsl"
#include "common/gbuffer_pack.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = GB_NORMAL) uniform usampler2D gb_normal;
layout(set = SET_PASS, binding = GB_HIT) uniform usampler2D gb_hit;
layout(set = SET_PASS, binding = AA_IN, rgba8) uniform readonly image2D ldr_in;
layout(set = SET_PASS, binding = AA_OUT, rgba8) uniform writeonly image2D ldr_out;

// Measured on the test scenes: smooth curved surfaces stay below 0.05 away from silhouettes; a
// 30-degree crease gives 0.8, a silhouette against the sky >= 3.
const float EDGE_START = 0.05;
const float EDGE_FULL = 0.5;
// A normal flip counts 4, as does one neighbour at half or twice the distance (8 x 2 x 0.25).
const float DEPTH_WEIGHT = 8.0;

const ivec2 NEIGHBOURS[8] = ivec2[](
    ivec2(-1, -1), ivec2(0, -1), ivec2(1, -1), ivec2(-1, 0),
    ivec2(1, 0), ivec2(-1, 1), ivec2(0, 1), ivec2(1, 1));
// NEIGHBOURS[7 - k] is the opposite of NEIGHBOURS[k].

// Reversed-Z depth (znear / view depth) of the hit's triangle plane; 0 on a miss (sky at infinity).
// Affine in screen space on a plane, which the depth term relies on.
float hit_depth(ivec2 px) {
    uvec2 hit = texelFetch(gb_hit, px, 0).xy;
    if (hit.x == 0u) return 0.0;
    TriangleWorld t = triangle_world(hit.x - 1u, hit.y);
    vec3 d = camera_ray_dir(vec2(px) + 0.5);
    vec3 n = cross(t.p1 - t.p0, t.p2 - t.p0);
    float dn = dot(d, n);
    // Degenerate or edge-on triangle: take the first vertex.
    float dist = abs(dn) > 0.0 ? dot(t.p0 - frame.camera_pos, n) / dn : length(t.p0 - frame.camera_pos);
    vec3 forward = -transpose(mat3(frame.view))[2];
    float z = dist * dot(d, forward);
    return z > 0.0 && !isinf(z) ? frame.znear / z : 0.0;
}

// Affine in screen space, unlike the normalized camera_ray_dir.
vec3 ray_dir_affine(vec2 pixel) {
    vec2 ndc = pixel / vec2(frame.resolution) * 2.0 - 1.0;
    return transpose(mat3(frame.view)) * vec3(ndc.x / frame.proj[0][0], ndc.y / frame.proj[1][1], -1.0);
}

// Homogeneous barycentrics (n0, n1, n2, det) via Moller-Trumbore with the unnormalized direction:
// affine in screen space, so an edge crossing is found by perspective-exact linear interpolation.
vec4 homogeneous_barycentrics(TriangleWorld t, vec2 pixel) {
    vec3 d = ray_dir_affine(pixel);
    vec3 e1 = t.p1 - t.p0;
    vec3 e2 = t.p2 - t.p0;
    vec3 tv = frame.camera_pos - t.p0;
    float det = dot(e1, cross(d, e2));
    float n1 = dot(tv, cross(d, e2));
    float n2 = dot(d, cross(tv, e1));
    return vec4(det - n1 - n2, n1, n2, det);
}

// How far from a (0) towards b (1) the surface of `instance` seen through a continues, walking across
// edges shared with nearby primitives so a mesh's inner edges don't pass for its outline.
// >= 1 when it covers b too (or a plane is edge-on or crosses the horizon).
float exit_along(uint instance, uint primitive, vec2 a, vec2 b) {
    Instance inst = instances[instance];
    uint count = inst.index_count / 3u;
    uint cur = primitive;
    float t_exit = 0.0;
    for (int walk = 0; walk < 4; walk++) {
        TriangleWorld t = triangle_world(instance, cur);
        vec4 ha = homogeneous_barycentrics(t, a);
        vec4 hb = homogeneous_barycentrics(t, b);
        if (!(ha.w * hb.w > 0.0)) return 1.0;
        // Inside is all three >= 0 (det > 0); each is affine along the segment, so inside is an interval.
        vec3 na = ha.xyz * sign(ha.w);
        vec3 nb = hb.xyz * sign(hb.w);
        float hi = 2.0;
        int edge = -1;
        for (int i = 0; i < 3; i++) {
            if (nb[i] < na[i]) {
                float ti = na[i] / (na[i] - nb[i]);
                if (ti < hi) {
                    hi = ti;
                    edge = i;
                }
            }
        }
        if (hi >= 1.0 || edge < 0) return 1.0;
        // Monotonic: rounding could put this exit before the edge it entered by.
        t_exit = max(hi, t_exit);
        uint base = inst.first_index + 3u * cur;
        uint ia = indices[base + uint(edge + 1) % 3u];
        uint ib = indices[base + uint(edge + 2) % 3u];
        uint next = cur;
        for (int d = -3; d <= 3; d++) {
            int cand = int(cur) + d;
            if (d == 0 || cand < 0 || uint(cand) >= count) continue;
            uint cb = inst.first_index + 3u * uint(cand);
            uvec3 ci = uvec3(indices[cb], indices[cb + 1u], indices[cb + 2u]);
            if (any(equal(ci, uvec3(ia))) && any(equal(ci, uvec3(ib)))) {
                next = uint(cand);
                break;
            }
        }
        if (next == cur) return t_exit;
        cur = next;
    }
    return t_exit;
}

vec3 hit_normal(ivec2 px) {
    if (texelFetch(gb_hit, px, 0).x == 0u) return vec3(0.0);
    return oct_decode(texelFetch(gb_normal, px, 0).x);
}

bool inside(ivec2 p) {
    return all(greaterThanEqual(p, ivec2(0))) && all(lessThan(uvec2(p), frame.resolution));
}

// The 8x8 group and its one-pixel border share hits, depths, normals and exits so each is computed
// once (1.35-1.6x faster on lavapipe: bench/results/lavapipe-2core-vm-frame-passes.md). Bit-identical
// to the per-pixel EDGE_AA_TILED = false path; tests/render/antialias.rs compares the two.
layout(constant_id = SPEC_EDGE_AA_TILED) const bool EDGE_AA_TILED = true;
const int TILE = 10;
shared uvec2 s_hit[TILE * TILE];
shared float s_depth[TILE * TILE];
shared vec3 s_normal[TILE * TILE];
shared float s_blur[64];
// Exit from a pixel towards EDGE_DIRS[d], only where a coverage needs it; else unset.
shared float s_exit[TILE * TILE][4];

// The 4 edge-sharing directions; EDGE_DIRS[3 - d] is the opposite of d.
const ivec2 EDGE_DIRS[4] = ivec2[](ivec2(0, -1), ivec2(-1, 0), ivec2(1, 0), ivec2(0, 1));

int tile_index(ivec2 t) {
    return t.x + TILE * t.y;
}

float blur_at(ivec2 t) {
    return s_blur[(t.x - 1) + 8 * (t.y - 1)];
}

float exit_towards(uvec2 hit, ivec2 p, ivec2 q) {
    return exit_along(hit.x - 1u, hit.y, vec2(p) + 0.5, vec2(q) + 0.5);
}

// Tile lookups, or recomputed per pixel when !EDGE_AA_TILED.
uvec2 hit_at(ivec2 t, ivec2 q) {
    return EDGE_AA_TILED ? s_hit[tile_index(t)] : texelFetch(gb_hit, q, 0).xy;
}

float depth_at(ivec2 t, ivec2 q) {
    return EDGE_AA_TILED ? s_depth[tile_index(t)] : hit_depth(q);
}

vec3 normal_at(ivec2 t, ivec2 q) {
    return EDGE_AA_TILED ? s_normal[tile_index(t)] : hit_normal(q);
}

float exit_at(ivec2 t, ivec2 q, int d) {
    return EDGE_AA_TILED ? s_exit[tile_index(t)][d] : exit_towards(hit_at(t, q), q, q + EDGE_DIRS[d]);
}

void main() {
    ivec2 origin = ivec2(gl_WorkGroupID.xy) * 8 - 1;
    uint lid = gl_LocalInvocationIndex;
    for (uint i = lid; EDGE_AA_TILED && i < uint(TILE * TILE); i += 64u) {
        ivec2 q = origin + ivec2(int(i) % TILE, int(i) / TILE);
        bool in_frame = inside(q);
        s_hit[i] = in_frame ? texelFetch(gb_hit, q, 0).xy : uvec2(0u);
        s_depth[i] = in_frame ? hit_depth(q) : 0.0;
        s_normal[i] = in_frame ? hit_normal(q) : vec3(0.0);
    }
    barrier();

    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 t = ivec2(gl_LocalInvocationID.xy) + 1;
    int c = tile_index(t);
    float blur = 0.0;
    if (inside(px)) {
        bool in_frame[8];
        float dc = depth_at(t, px);
        vec3 nc = normal_at(t, px);
        float depth[8];
        float normal_sum = 0.0;
        for (int k = 0; k < 8; k++) {
            ivec2 q = px + NEIGHBOURS[k], qt = t + NEIGHBOURS[k];
            in_frame[k] = inside(q);
            depth[k] = in_frame[k] ? depth_at(qt, q) : dc;
            vec3 dn = in_frame[k] ? normal_at(qt, q) - nc : vec3(0.0);
            normal_sum += dot(dn, dn);
        }
        // A slanted plane changes depth by a constant step, so compare each neighbour with the centre plane's
        // prediction 2 dc - d_opposite, relative to the largest depth (scale-free). Off-frame pairs count 0.
        float depth_sum = 0.0;
        for (int k = 0; k < 4; k++) {
            if (!in_frame[k] || !in_frame[7 - k]) continue;
            float scale = max(max(depth[k], depth[7 - k]), dc);
            float e = scale > 0.0 ? (depth[k] + depth[7 - k] - 2.0 * dc) / scale : 0.0;
            depth_sum += 2.0 * e * e;
        }
        float edge = DEPTH_WEIGHT * depth_sum + normal_sum;
        blur = clamp((edge - EDGE_START) / (EDGE_FULL - EDGE_START), 0.0, 1.0);
    }
    s_blur[lid] = blur;
    barrier();

    // Exits the coverages need: this pixel's towards each neighbour where either blurs (a border
    // pixel blurs in its own workgroup, which computes that exit); plus one border pixel's towards the tile.
    if (EDGE_AA_TILED && inside(px)) {
        for (int d = 0; d < 4; d++) {
            ivec2 nt = t + EDGE_DIRS[d];
            bool in_tile = all(greaterThanEqual(nt, ivec2(1))) && all(lessThanEqual(nt, ivec2(8)));
            bool needed = blur > 0.0 || (in_tile && blur_at(nt) > 0.0);
            uvec2 h = s_hit[c];
            if (needed && h.x != 0u && inside(px + EDGE_DIRS[d]) && h != s_hit[tile_index(nt)]) {
                s_exit[c][d] = exit_towards(h, px, px + EDGE_DIRS[d]);
            }
        }
    }
    if (EDGE_AA_TILED && lid < 32u) {
        // Border pixel `lid` (8 per side, in EDGE_DIRS order) faces its tile pixel in direction 3 - side.
        int side = int(lid) / 8, j = int(lid) % 8;
        ivec2 inner = side == 0 ? ivec2(j + 1, 1) : side == 1 ? ivec2(1, j + 1) : side == 2 ? ivec2(8, j + 1) : ivec2(j + 1, 8);
        ivec2 b = inner + EDGE_DIRS[side];
        ivec2 bp = origin + b, ip = origin + inner;
        uvec2 h = s_hit[tile_index(b)];
        if (inside(bp) && inside(ip) && blur_at(inner) > 0.0 && h.x != 0u
            && h != s_hit[tile_index(inner)]) {
            s_exit[tile_index(b)][3 - side] = exit_towards(h, bp, ip);
        }
    }
    barrier();

    if (!inside(px)) return;
    vec4 centre = imageLoad(ldr_in, px);
    if (!(blur > 0.0)) {
        imageStore(ldr_out, px, centre);  // bit-identical away from edges
        return;
    }
    // Weight = coverage of this pixel (0..0.5) by the neighbour's surface: the edge lies where this
    // triangle ends (exit t) or the neighbour's begins (exit s past the border at 0.5); s >= 1: hidden here.
    vec3 sum = vec3(0.0);
    float total = 0.0;
    uvec2 hp = hit_at(t, px);
    for (int d = 0; d < 4; d++) {
        ivec2 q = px + EDGE_DIRS[d], qt = t + EDGE_DIRS[d];
        if (!inside(q)) continue;
        uvec2 hq = hit_at(qt, q);
        float w = 0.0;
        if (hp != hq) {  // one triangle (or both sky): no edge between
            float tp = hp.x != 0u ? exit_at(t, px, d) : 1.0;
            float sq = hq.x != 0u ? exit_at(qt, q, 3 - d) : 1.0;
            if (tp < 1.0) w = max(w, 0.5 - tp);
            if (sq < 1.0) w = max(w, sq - 0.5);
        }
        sum += w * srgb_decode(imageLoad(ldr_in, q).rgb);
        total += w;
    }
    if (!(total > 0.0)) {
        imageStore(ldr_out, px, centre);
        return;
    }
    // Corners covered from two sides: weights are shares of one pixel.
    float scale = blur / max(total, 1.0);
    vec3 col = (1.0 - scale * total) * srgb_decode(centre.rgb) + scale * sum;
    imageStore(ldr_out, px, vec4(srgb_encode(col), centre.a));
}
