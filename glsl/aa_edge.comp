#version 460
// Pass `edge aa`: geometric edge anti-aliasing of the tone-mapped frame.
// Which pixels change is the document's edge detection (Shishkovtsov,
// "Deferred Shading in S.T.A.L.K.E.R.", GPU Gems 2 ch. 9; Sabino's
// Eq. 4.2): the squared depth and normal differences to the 8 neighbours,
// summed, give the blur factor B; B = 0 copies the input bits unchanged.
//
// How much of each neighbour an edge pixel takes is not a plain mean of
// the 8 neighbours (Eq. 4.2's blend): that softens every edge by a pixel on
// both sides and raised ꟻLIP against a 4x4 supersampled reference on
// assets/aa_edges.toml (0.0062 -> 0.0105 at full strength, still 0.0073 at
// B/20) although PSNR rose. The G-buffer knows each pixel's triangle, so
// the weight is that neighbour's surface's coverage of this pixel: where
// the triangle seen here, or the neighbour's, ends between the two pixel
// centres (exact screen-space edges, as in Persson's geometry-buffer AA).
// The result is (1 - B sum w_k) c + B sum w_k c_k over the 4 edge-sharing
// neighbours, in linear display values like a supersampled pixel.
#include "common/primary_hit.glsl"
#include "common/srgb.glsl"
#include "common/gbuffer_pack.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = SET_PASS, binding = GB_NORMAL) uniform usampler2D gb_normal;
layout(set = SET_PASS, binding = GB_HIT) uniform usampler2D gb_hit;
layout(set = SET_PASS, binding = AA_IN, rgba8) uniform readonly image2D ldr_in;
layout(set = SET_PASS, binding = AA_OUT, rgba8) uniform writeonly image2D ldr_out;

// Edge strength E (the weighted sum below) where blurring starts, and
// where it is full (B = 1). Measured on the test scenes: curved,
// smooth-shaded surfaces stay below 0.05 except within a pixel or two of
// their silhouettes; a crease of 30 degrees on one side of a pixel gives
// 3 x 0.27 = 0.8, a silhouette against the sky >= 3.
const float EDGE_START = 0.05;
const float EDGE_FULL = 0.5;
// Weight of the relative depth term against the normal term: a normal
// flip counts 4, one neighbour at half or twice the distance 8 x 2 x 0.25 = 4.
const float DEPTH_WEIGHT = 8.0;

const ivec2 NEIGHBOURS[8] = ivec2[](
    ivec2(-1, -1), ivec2(0, -1), ivec2(1, -1), ivec2(-1, 0),
    ivec2(1, 0), ivec2(-1, 1), ivec2(0, 1), ivec2(1, 1));
// NEIGHBOURS[7 - k] is the opposite of NEIGHBOURS[k].

// Reversed-Z depth (znear / view depth) where the camera ray through `px`
// meets its primary hit's triangle plane; 0 where it missed (the sky is
// at infinity). On a plane this is affine in screen space, which the
// depth term relies on.
float hit_depth(ivec2 px) {
    uvec2 hit = texelFetch(gb_hit, px, 0).xy;
    if (hit.x == 0u) return 0.0;
    TriangleWorld t = triangle_world(hit.x - 1u, hit.y);
    vec3 d = camera_ray_dir(vec2(px) + 0.5);
    vec3 n = cross(t.p1 - t.p0, t.p2 - t.p0);
    float dn = dot(d, n);
    // Ray distance to the plane; a degenerate or edge-on triangle has none
    // and counts as a hit at the triangle's first vertex.
    float dist = abs(dn) > 0.0 ? dot(t.p0 - frame.camera_pos, n) / dn : length(t.p0 - frame.camera_pos);
    vec3 forward = -transpose(mat3(frame.view))[2];
    float z = dist * dot(d, forward);
    return z > 0.0 && !isinf(z) ? frame.znear / z : 0.0;
}

// Unnormalized direction of the camera ray through `pixel`: affine in
// screen space (unlike camera_ray_dir, which is normalized).
vec3 ray_dir_affine(vec2 pixel) {
    vec2 ndc = pixel / vec2(frame.resolution) * 2.0 - 1.0;
    return transpose(mat3(frame.view)) * vec3(ndc.x / frame.proj[0][0], ndc.y / frame.proj[1][1], -1.0);
}

// Homogeneous barycentrics (n0, n1, n2) and their sum `det` of the camera
// ray through `pixel` on triangle t's plane (Moller-Trumbore with the
// unnormalized direction): each is affine in screen space, so where an
// edge's barycentric reaches 0 along a segment is found by linear
// interpolation, perspective-exact.
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

// How far, from a (0) towards b (1), the surface of `instance` seen
// through a continues: the exit from triangle `primitive` along the
// segment, walking on across an edge it shares (by vertex index) with one
// of the nearby primitives (a quad's other half, the next quad of a ring),
// so a mesh's inner edges do not pass for its outline. >= 1 when it covers
// b too (or a plane is edge-on, or crosses the horizon in between).
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
        // Signs as if det > 0: inside is all three >= 0; each is affine in
        // the segment's parameter, so the inside part is an interval.
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
        // Past the edge it entered by (rounding aside).
        t_exit = max(hi, t_exit);
        // The exit edge is opposite vertex `edge`; is it shared?
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

// The primary hit's shading normal; 0 where the camera ray missed.
vec3 hit_normal(ivec2 px) {
    if (texelFetch(gb_hit, px, 0).x == 0u) return vec3(0.0);
    return oct_decode(texelFetch(gb_normal, px, 0).x);
}

bool inside(ivec2 p) {
    return all(greaterThanEqual(p, ivec2(0))) && all(lessThan(uvec2(p), frame.resolution));
}

// The workgroup's 8x8 pixels and a one-pixel border around them (TILE x
// TILE) share what their neighbours need: each pixel's hit, depth and
// normal are computed once instead of by all 9 pixels around it, and each
// surface's exit towards an edge neighbour once instead of by both pixels
// of the pair (the pass got 1.35-1.6x faster on lavapipe:
// bench/results/lavapipe-2core-vm-frame-passes.md). Same values, same
// arithmetic: the image is that of the per-pixel version, bit for bit,
// which EDGE_AA_TILED = false runs (tests/render/antialias.rs compares the two).
layout(constant_id = SPEC_EDGE_AA_TILED) const bool EDGE_AA_TILED = true;
const int TILE = 10;
shared uvec2 s_hit[TILE * TILE];
shared float s_depth[TILE * TILE];
shared vec3 s_normal[TILE * TILE];
// Blur factor B of the workgroup's own pixels (0 outside the frame).
shared float s_blur[64];
// exit_along from a pixel's centre towards its edge-sharing neighbour in
// direction d (EDGE_DIRS), where a coverage needs it; else unset.
shared float s_exit[TILE * TILE][4];

// The 4 edge-sharing directions; EDGE_DIRS[3 - d] is the opposite of d.
const ivec2 EDGE_DIRS[4] = ivec2[](ivec2(0, -1), ivec2(-1, 0), ivec2(1, 0), ivec2(0, 1));

int tile_index(ivec2 t) {
    return t.x + TILE * t.y;
}

// The blur factor of the workgroup's pixel at `t` (1..8 in the tile).
float blur_at(ivec2 t) {
    return s_blur[(t.x - 1) + 8 * (t.y - 1)];
}

// How far the surface seen through `p` continues towards `q` (0..1+;
// exit_along), from the pixel centres.
float exit_towards(uvec2 hit, ivec2 p, ivec2 q) {
    return exit_along(hit.x - 1u, hit.y, vec2(p) + 0.5, vec2(q) + 0.5);
}

// What pixel `q` (at `t` in the tile) shows and its exit towards
// EDGE_DIRS[d]: from the tile, or computed here (per-pixel version).
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
    // 1. Hit, depth and normal of every tile pixel in the frame.
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
        // Depth: a slanted plane changes depth by the same step every pixel,
        // so the plain difference to a neighbour would blur every floor. Each
        // neighbour is compared with the depth the centre's plane predicts for
        // it from the opposite neighbour, 2 dc - d_opposite (exact on a plane,
        // see hit_depth): (d_k + d_opposite - 2 dc)^2, relative to the largest
        // of the three so the measure does not depend on the scene's scale.
        // Both neighbours of a pair count; a pair leaving the frame counts 0.
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

    // 2. The exits the coverages below need: this pixel's towards each edge
    // neighbour where either of the two blurs (a neighbour in the border
    // blurs in its own workgroup, which computes this exit itself); and
    // one border pixel's towards the tile, per invocation of the first 32.
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
        // Border pixel `lid` (8 per side: top, left, right, bottom, as
        // EDGE_DIRS) and the tile pixel it faces, in direction 3 - side.
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
    // The edge-sharing neighbours, weighted by the coverage of this pixel by
    // what they show (0..0.5): the edge between them lies where this
    // pixel's triangle ends (its exit t), or where the neighbour's begins
    // (its exit s reaches past the pixel border at 0.5), between the two
    // centres. s >= 1 means it lies behind what this pixel shows there.
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
    // Corners covered from two sides: the weights are shares of one pixel.
    float scale = blur / max(total, 1.0);
    vec3 col = (1.0 - scale * total) * srgb_decode(centre.rgb) + scale * sum;
    imageStore(ldr_out, px, vec4(srgb_encode(col), centre.a));
}
