// Values shared by host and shaders, defined once: build.rs writes them to `generated/shared.glsl`,
// src/gpu/shared.rs to Rust constants. Kinds: `id` (set/binding/spec-constant numbers, plain GLSL
// integers usable in layout qualifiers), `uint`, `float`.
shared! {
    // Descriptor sets: 0 the scene (every pass), 1 the pass's own images,
    // 2 the tracer's acceleration data.
    id SET_SCENE = 0;
    id SET_PASS = 1;
    id SET_TRACE = 2;

    // Set 0 (gpu/scene.rs): the scene.
    id SCENE_FRAME = 0;
    id SCENE_VERTICES = 1;
    id SCENE_INDICES = 2;
    id SCENE_MATERIALS = 3;
    id SCENE_INSTANCES = 4;
    id SCENE_LIGHTS = 5;
    id SCENE_ENV_MAP = 6;
    id SCENE_RAY_COUNTERS = 7;
    // Auto-exposure state, kept across frames (render/passes/luminance.rs).
    id SCENE_EXPOSURE = 8;
    // Budget (render/budget): per object BUDGET_STAT_WORDS of `heuristic` statistics (covered pixels,
    // min x, min y, max x, max y, then rays per effect at BUDGET_STAT_RAYS + EFFECT_BIT_*) and one
    // selection word (EFFECT_* bits), honoured where Frame.flags has FRAME_BUDGET.
    id SCENE_BUDGET_STATS = 9;
    id SCENE_BUDGET_MASK = 10;
    // The budget's raster shadow fallback (gpu/shadow_map.rs): a depth layer per light and its
    // view-projection.
    id SCENE_SHADOW_MAPS = 11;
    id SCENE_SHADOW_VIEWS = 12;
    // Diffuse PRT (prt/pack.rs, glsl/common/prt.glsl): PRT_HEADER_WORDS (coefficients, channels,
    // instance count, 0), per instance its first transfer vertex (PRT_NO_VERTEX: SH irradiance instead),
    // then per-vertex transfer floats. A 4-word placeholder without a prt ambient mode.
    id SCENE_PRT = 13;
    // Environment importance-sampling table (gpu/env_sampling.rs): ENV_CDF_HEADER floats (width, height,
    // 1 with a table), the row marginal CDF (height + 1), each row's CDF (width + 1). Header only
    // without a map (constant environments are sampled uniformly).
    id SCENE_ENV_CDF = 14;
    uint ENV_CDF_HEADER = 4;
    // Emissive triangles as lights (gpu/emitters.rs): EMITTER_HEADER_WORDS (emitter count, instance
    // count), per instance its first emitter (NO_EMITTER: none), per emitter (instance, primitive), CDF.
    id SCENE_EMITTERS = 15;
    uint EMITTER_HEADER_WORDS = 2;
    uint NO_EMITTER = 2147483647;
    // The environment prefiltered by GGX (gpu/env_prefilter.rs): mip k for perceptual roughness
    // k / (ENV_SPECULAR_LEVELS - 1); and the split-sum table (gpu/split_sum.rs): DFG_LUT_SIZE² cells of
    // (A, B) by (n.v, roughness).
    id SCENE_ENV_SPECULAR = 16;
    id SCENE_DFG = 17;
    uint ENV_SPECULAR_LEVELS = 5;
    uint DFG_LUT_SIZE = 32;
    // Bindless textures: variable-count, so the last binding.
    id SCENE_TEXTURES = 18;
    // At 1024 a directional light fitted to a 40 m scene has 4 cm texels, under a Sponza column's detail,
    // for 4 MiB a light (2048 quadruples memory and raster time).
    uint SHADOW_MAP_SIZE = 1024;
    // The receiver moves this many shadow-map texels along its normal
    // before the lookup (normal-offset bias against acne at grazing light).
    float SHADOW_NORMAL_OFFSET = 1.5;
    // Ray-origin offset (glsl/common/offset.glsl, PRT visibility rays): covers interpolation (3 terms),
    // the instance transform (4 terms) and the traversal's own triangle test.
    float OFFSET_ULPS = 16.0;
    uint BUDGET_STAT_WORDS = 8;
    // Pixels one `heuristic` invocation reduces in registers (glsl/heuristic.comp); its 8x8
    // workgroups cover 8 times that, which the pass's dispatch counts.
    id HEURISTIC_BLOCK_W = 2;
    id HEURISTIC_BLOCK_H = 4;
    uint BUDGET_STAT_RAYS = 5;
    // Bits of the budget's selection: shadow rays at the primary hit; the reflection chain; the refraction
    // chain (a chain includes everything traced beyond its first ray, shadow rays too).
    uint EFFECT_BIT_SHADOWS = 0;
    uint EFFECT_BIT_REFLECTIONS = 1;
    uint EFFECT_BIT_REFRACTIONS = 2;
    uint EFFECT_COUNT = 3;
    uint EFFECT_ALL = 7;
    // Partial effects (effects mode meets its budget continuously): bits EFFECT_PARTIAL_SHIFT +
    // EFFECT_BIT_* trace where a pixel's rank in the BUDGET_LATTICE² ordered-dither (Bayer) matrix is
    // below the count in the top bits (EFFECT_FRACTION_SHIFT; 0..BUDGET_LATTICE²). Ranks below 4^k lie
    // on a lattice of period BUDGET_LATTICE / 2^k, which `composite` interpolates the untraced pixels
    // from (common/budget_fill.glsl); a growing count adds pixels without dropping traced ones.
    uint EFFECT_PARTIAL_SHIFT = 4;
    uint EFFECT_FRACTION_SHIFT = 16;
    uint BUDGET_LATTICE = 8;
    // Frame.flags. FRAME_FALLBACK_RASTER (with FRAME_BUDGET): `--fallback raster` instead of `none`.
    uint FRAME_BUDGET = 1;
    // The ambient term is the environment's SH irradiance
    // (Frame.sh_irradiance) instead of the constant Frame.env_ambient.
    uint FRAME_AMBIENT_SH = 2;
    // 3 bands (l <= 2) hold all but ~1% of a clamped-cosine convolution (Ramamoorthi & Hanrahan 2001;
    // Â_3 = 0, |Â_4| = pi/24).
    uint SH_IRRADIANCE_COEFFS = 9;
    uint FRAME_FALLBACK_RASTER = 4;
    // Static instances' primary-hit ambient is PRT transfer · Frame.sh_radiance (with FRAME_AMBIENT_SH
    // too, for everything else).
    uint FRAME_AMBIENT_PRT = 8;
    // Radiance coefficients in Frame.sh_radiance: up to 8 bands.
    uint SH_PRT_MAX_COEFFS = 64;
    // Shadow rays treat transmissive occluders as opaque (the path tracer:
    // light through glass comes along refracted paths, not straight rays).
    uint FRAME_OPAQUE_OCCLUDERS = 16;
    // Glossy reflections reuse samples across frames (render/passes/glossy_temporal.rs): new samples
    // each frame (FRAME_GLOSSY_TEMPORAL), and a history of the last frame's to reproject into.
    uint FRAME_GLOSSY_HISTORY = 32;
    uint FRAME_GLOSSY_TEMPORAL = 64;
    // Count rays by kind into the benchmark counters (Effects::count_rays: a flag, not a
    // specialization constant, so counting compiles no new pipeline).
    uint FRAME_COUNT_RAYS = 128;
    // The raster fallback's shadow maps rendered this frame (pass `shadow_map`): left-out shadows of
    // directional and spot lights read them; without it they stay unshadowed (the budget found the
    // maps too dear).
    uint FRAME_SHADOW_MAPS = 256;
    // `--ambient traced` (passes/ao.glsl, ao_filter.comp): its rays that hit bring the hit's direct
    // light and its environment light (the one indirect bounce; `--no-indirect` clears both); the
    // environment's light shades by the visible share; emissive surfaces light the pixel directly
    // (FRAME_AO_EMITTERS: light samples and the rays that hit them, MIS-weighted). The report's
    // attribution clears the parts its terms supply.
    uint FRAME_AO_BOUNCE_LIGHTS = 512;
    uint FRAME_AO_EMITTERS = 1024;
    uint FRAME_AO_SKY = 2048;
    uint FRAME_AO_BOUNCE_SKY = 4096;
    uint PRT_HEADER_WORDS = 4;
    uint PRT_NO_VERTEX = 2147483647;

    // Set 1 of the passes that read the primary hit (render/passes): the
    // G-buffer targets first, then each pass's own images.
    id GB_ALBEDO = 0;
    id GB_NORMAL = 1;
    id GB_MATERIAL = 2;
    id GB_HIT = 4;
    id DIRECT_OUT = 5;
    id SPECULAR_OUT = 5;
    id DIRECT_IN = 5;
    id SPECULAR_IN = 6;
    id HDR_OUT = 7;
    // A pass's compacted work list (glsl/common/work_list.glsl,
    // render/passes/compacted.rs): its header (indirect commands and count)
    // and the list of pixels; WORK_GROUP_SIZE invocations a workgroup.
    id WORK_HEADER = 12;
    id WORK_LIST = 13;
    uint WORK_GROUPS_X = 0;
    uint WORK_COUNT = 3;
    uint WORK_HEADER_WORDS = 6;
    uint WORK_GROUP_SIZE = 64;
    // The ray-traced ambient reference (render/passes/reference.rs): its
    // accumulation (rgb: radiance sum, a: samples) written by `reference`,
    // read by `composite`; samples per pixel per frame.
    id REFERENCE_OUT = 5;
    // Glossy reflections (render/passes/glossy.rs, glossy_filter.rs): the one-sample correction
    // written by `glossy`, read by `glossy_filter` beside the specular chain (SPECULAR_IN), which writes
    // the frame's reflected radiance; the sample stream's seed; the filter's taps, radius (times alpha
    // over the pixel's angle) and its cap in pixels.
    id GLOSSY_OUT = 5;
    id GLOSSY_IN = 5;
    id REFLECTED_OUT = 7;
    id GLOSSY_HISTORY = 8;
    id GLOSSY_ACCUM = 9;
    uint GLOSSY_SEED = 1729;
    uint GLOSSY_FILTER_TAPS = 16;
    // Weight of a frame's sample in the reprojected history (an exponential average of about
    // 2 / GLOSSY_TEMPORAL_BLEND frames) and the relative distance mismatch that rejects the history.
    float GLOSSY_TEMPORAL_BLEND = 0.1;
    float GLOSSY_TEMPORAL_DEPTH = 0.02;
    float GLOSSY_FILTER_SCALE = 0.5;
    float GLOSSY_FILTER_MAX_PX = 16.0;
    id REFERENCE_IN = 8;
    // Traced ambient (`--ambient traced`; render/passes/ao.rs, ao_filter.rs): `ao` writes per pixel the
    // share of the environment's diffuse light its AO_SAMPLES cosine rays find unoccluded (rgb) with the
    // camera distance (a; 0: no sample), and the irradiance their hits bounce (rgb); `ao filter`
    // averages both over the (2 AO_FILTER_RADIUS_PX)² window, guided by the G-buffer, into the diffuse
    // ambient radiance `composite` shades with (rgb) and the mean share (a, the specular occlusion).
    id AO_OUT = 5;
    id AO_IN = 5;
    id AO_BOUNCE_OUT = 6;
    id AO_BOUNCE_IN = 6;
    id AO_VISIBILITY_OUT = 7;
    id AO_VISIBILITY_IN = 10;
    // The emitters' light on a specular lobe no glossy ray samples (rougher than GLOSSY_ROUGHNESS): `ao`
    // writes its light samples' radiance over the lobe's albedo (demodulated, so neighbours of another
    // material average fairly), `ao filter` averages it with the share's weights, `composite` scales it
    // by the pixel's own albedo.
    id AO_SPECULAR_OUT = 7;
    id AO_SPECULAR_IN = 8;
    id AO_EMITTER_SPECULAR_OUT = 9;
    id AO_EMITTER_SPECULAR_IN = 11;
    uint AO_SEED = 40503;
    uint AO_SAMPLES = 4;
    // Light samples a pixel on the emissive triangles (gpu/emitters.rs), beside the AO_SAMPLES cosine
    // rays (passes/ao.glsl); one more at each ray's hit for the bounce.
    uint AO_EMITTER_SAMPLES = 1;
    // The level of the prefiltered environment (ENV_SPECULAR_LEVELS) that weighs each ray.
    uint AO_WEIGHT_LEVEL = 1;
    // sqrt(16 AO_SAMPLES): the strata per axis of a 4x4 tile's rays (passes/ao.glsl).
    uint AO_GRID = 8;
    // A whole number of 4x4 tiles across: each tile's rays are one stratified set.
    uint AO_FILTER_RADIUS_PX = 4;
    uint REFERENCE_SAMPLES_PER_FRAME = 4;
    // The path tracer (render/passes/path.rs, glsl/path/path.glsl): its
    // accumulation (rgb: radiance sum, a: samples), kept across frames, and
    // the frame's radiance (the mean); camera paths per pixel per frame;
    // the bounce from which Russian roulette may end a path.
    id PATH_ACCUM = 0;
    id PATH_OUT = 1;
    uint PATH_SAMPLES_PER_FRAME = 4;
    uint PATH_RR_START = 3;
    // The report's attribution (render/passes/terms.rs): per pixel the selected terms' path-traced
    // estimate (rgb) and the sample count (a), which `composite` adds in place of its own terms;
    // the terms (selected via Frame.accum_bounces); samples per pixel per frame; longest glass/mirror chain.
    id TERMS_OUT = 6;
    id TERMS_IN = 9;
    uint TERM_ENV_SPECULAR = 1;
    uint TERM_VISIBILITY = 2;
    uint TERM_INDIRECT = 4;
    uint TERM_EMITTERS = 8;
    uint TERM_CAUSTICS = 16;
    uint TERMS_SAMPLES_PER_FRAME = 4;
    uint TERMS_CHAIN = 8;
    // Set 1 of the tone-mapping pass and of the luminance reduction.
    id TONEMAP_IN = 0;
    id TONEMAP_OUT = 1;
    id LUMINANCE_IN = 0;

    // Tone mapping (Frame.tonemap, Frame.auto_exposure).
    uint TONEMAP_REINHARD = 0;
    uint TONEMAP_REINHARD_WHITE = 1;
    uint TONEMAP_ACES = 2;
    uint TONEMAP_NONE = 3;
    uint AUTO_EXPOSURE_OFF = 0;
    uint AUTO_EXPOSURE_LOG_AVERAGE = 1;
    uint AUTO_EXPOSURE_HISTOGRAM = 2;
    // A fixed grid striding over the image, so the partial sums have a fixed size.
    uint LUMINANCE_GROUPS = 64;
    uint LUMINANCE_THREADS = 256;
    // Log-luminance histogram: bins over [HIST_MIN_LOG2, HIST_MAX_LOG2]
    // (log2 of luminance; darker pixels land in bin 0, brighter in the last).
    // 48 EV in 0.1875-EV bins: from starlight to a 1e7 sun texel.
    uint HIST_BINS = 256;
    float HIST_MIN_LOG2 = -24.0;
    float HIST_MAX_LOG2 = 24.0;
    // delta in exp(mean(log(delta + L))): guards log 0 on black pixels.
    float LOG_AVERAGE_DELTA = 0.0001;
    // Eye adaptation (the PRT document): adapted += (target - adapted) *
    // (1 - ADAPT_BASE^(ADAPT_FPS * dt)), frame-rate independent.
    float ADAPT_BASE = 0.98;
    float ADAPT_FPS = 60.0;
    // Set 1 of the anti-aliasing passes (render/passes/edge_aa.rs, fxaa.rs):
    // the edge filter also reads GB_NORMAL and GB_HIT.
    id AA_IN = 5;
    id AA_OUT = 6;

    // Set 2: the ray-query and RT-pipeline tracers bind the TLAS ...
    id TRACE_TLAS = 0;
    // ... the compute tracer its own two-level BVH (accel/compute_bvh.rs).
    id BVH_BLAS_NODES = 0;
    id BVH_BLAS_PRIMS = 1;
    id BVH_TLAS_NODES = 2;
    id BVH_TLAS_PRIMS = 3;
    id BVH_INSTANCES = 4;
    id BVH_FLAT_TRIS = 5;
    id BVH_FLAT_MEMBERS = 6;
    // A flat-tree triangle's id word (accel/flat.rs `FlatTriangle`): its
    // number in the tree below FLAT_ID_INDEX (2^29 - 1), its instance's opacity and
    // ray mask above. The members table maps the number to (instance,
    // primitive).
    uint FLAT_ID_INDEX = 536870911;
    uint FLAT_ID_OPAQUE_SHIFT = 29;
    uint FLAT_ID_MASK_SHIFT = 30;

    // The animation compute passes' own single set (SET_ANIM): skinning
    // (render/skinning.rs), BLAS refit (accel/compute_refit.rs) and the
    // top-level fit (accel/compute_top_level.rs) of the compute BVH.
    id SET_ANIM = 0;
    id SKIN_SOURCE = 0;
    id SKIN_JOINTS = 1;
    id SKIN_DEST = 2;
    id SKIN_BOUNDS = 3;
    id REFIT_NODES = 0;
    id REFIT_PRIMS = 1;
    id REFIT_VERTICES = 2;
    id REFIT_INDICES = 3;
    id REFIT_JOBS = 4;
    id REFIT_ORDER = 5;
    id REFIT_ROOTS = 6;
    id TOP_FIT_NODES = 0;
    id TOP_FIT_PRIMS = 1;
    id TOP_FIT_INSTANCES = 2;
    id TOP_FIT_BLAS_NODES = 3;
    id TOP_FIT_ORDER = 4;

    // The device-side LBVH builder's single set (accel/lbvh.rs, glsl/lbvh/): triangles, Morton keys and
    // triangle numbers (sorted in place through the _OUT pair: the two sets swap them), radix
    // histogram, the hierarchy (children per internal node, parent per node), node boxes and the
    // bottom-up visit counters. Radix sort by LBVH_RADIX_BITS per pass over blocks of
    // LBVH_RADIX_BLOCK keys per invocation.
    id SET_LBVH = 0;
    id LBVH_TRIANGLES = 0;
    id LBVH_KEYS = 1;
    id LBVH_VALUES = 2;
    id LBVH_KEYS_OUT = 3;
    id LBVH_VALUES_OUT = 4;
    id LBVH_HISTOGRAM = 5;
    id LBVH_CHILDREN = 6;
    id LBVH_PARENTS = 7;
    id LBVH_BOXES = 8;
    id LBVH_FLAGS = 9;
    uint LBVH_RADIX_BITS = 4;
    uint LBVH_RADIX_BLOCK = 256;
    uint LBVH_GROUP = 64;

    // Set 1 of the ray microbenchmark (glsl/rays.comp, render/rays/): the rays, what each hit, and
    // (stats variant) nodes visited and triangles tested per ray.
    id RAYS_IN = 0;
    id RAYS_OUT = 1;
    id RAYS_STATS = 2;
    // Bytes per ray and per result (scalar layout).
    uint BENCH_RAY_STRIDE = 32;
    uint BENCH_RESULT_STRIDE = 48;

    // The shading probe (glsl/probes/shading.comp): tests evaluate the
    // compiled shading functions through it. One set; PROBE_* ops.
    id SET_PROBE = 0;
    id PROBE_IN = 0;
    id PROBE_OUT = 1;
    uint PROBE_FRESNEL = 0;
    uint PROBE_SCHLICK = 1;
    uint PROBE_BRDF = 2;
    uint PROBE_OFFSET = 3;
    uint PROBE_REFRACT = 4;
    uint PROBE_GGX = 5;
    uint PROBE_TONEMAP = 6;
    uint PROBE_ADAPT = 7;
    uint PROBE_OCTAHEDRAL = 8;

    // Specialization constants.
    id SPEC_SHADOWS = 1;
    id SPEC_REFLECTIONS = 2;
    id SPEC_REFRACTIONS = 3;
    // The luminance reduction's two kernels (glsl/luminance.comp).
    id SPEC_LUMINANCE_STAGE = 7;
    // The compute tracer's subgroup-cooperative ("packet") traversal
    // (glsl/trace/compute_packet.glsl): a bit per ray kind that takes it;
    // the rest trace lane by lane. Default none: on lavapipe it measured no
    // faster (bench/results/lavapipe-2core-vm-rays.md).
    id SPEC_TRACE_PACKET = 8;
    uint TRACE_PACKET_SHADOW = 1;
    uint TRACE_PACKET_CLOSEST = 2;
    uint TRACE_PACKET_DEFAULT = 0;
    // The edge filter shares its pixels' work within 8x8 tiles
    // (glsl/aa_edge.comp); 0 runs its per-pixel reference version.
    id SPEC_EDGE_AA_TILED = 9;

    // Instance mask bits: which kind of ray may hit an instance.
    uint MASK_VISIBLE = 1;
    uint MASK_SHADOW = 2;
    // RT-pipeline hit groups per geometry (shader binding table order).
    uint HIT_GROUP_VISIBLE = 0;
    uint HIT_GROUP_SHADOW = 1;
    uint HIT_GROUP_STRIDE = 2;
    // Ray counters (set 0, SCENE_RAY_COUNTERS) by kind.
    uint RAY_KIND_CAMERA = 0;
    uint RAY_KIND_SHADOW = 1;
    uint RAY_KIND_SECONDARY = 2;
    // Counter slot of the pixels whose reflection/refraction tree was cut
    // (always counted): by the per-pixel ray budget or a full branch stack.
    uint RAY_COUNTER_TRUNCATED = 3;
    // Counter slot of the pixels whose radiance reached tone mapping as
    // NaN, Inf or negative (always counted; they are shown magenta).
    uint RAY_COUNTER_BAD_PIXELS = 4;
    uint RAY_COUNTER_SLOTS = 8;
    // Pixels one fault injection overwrites (glsl/inject.comp; push
    // constants), and its one set with the HDR image.
    uint INJECT_MAX = 4;
    id SET_INJECT = 0;
    id INJECT_HDR = 0;
    // Most secondary rays one pixel traces; bounds `--min-weight 0` with a
    // deep `--max-depth` (2^depth branches through glass).
    uint RAY_BUDGET_PER_PIXEL = 1024;
    // Pending branches one pixel holds (the integrator's explicit stack).
    uint BRANCH_STACK_SIZE = 16;

    // Materials (Material.alpha_mode, Material.flags).
    uint ALPHA_OPAQUE = 0;
    uint ALPHA_MASK = 1;
    uint ALPHA_BLEND = 2;
    uint MAT_DOUBLE_SIDED = 1;
    uint MAT_CASTS_SHADOWS = 2;
    // Surfaces at most this rough get mirror reflections (one ray along r: alpha <= 0.01, a lobe
    // under a degree wide); primary hits up to GLOSSY_ROUGHNESS get glossy rays (render/passes/
    // glossy.rs), rougher ones and secondary hits the split-sum environment alone.
    float MIRROR_ROUGHNESS = 0.1;
    float GLOSSY_ROUGHNESS = 0.6;
    // Instances (Instance.flags).
    uint INST_CASTS_SHADOWS = 1;
    // Lights (Light.type, Light.flags).
    uint LIGHT_DIRECTIONAL = 0;
    uint LIGHT_POINT = 1;
    uint LIGHT_SPOT = 2;
    uint LIGHT_CASTS_SHADOWS = 1;
    // Debug views (Frame.debug_view).
    uint DEBUG_NONE = 0;
    uint DEBUG_ALBEDO = 1;
    uint DEBUG_NORMAL = 2;
    uint DEBUG_DEPTH = 3;
    uint DEBUG_MATERIAL = 4;
    uint DEBUG_OBJECT = 5;
    // The budget's selection: ray-traced objects red, the others grey.
    uint DEBUG_SELECTION = 6;
    // For tools (the report's per-object error): linear radiance holds the
    // primary hit's object index + 1 in every channel, 0 where nothing is hit.
    uint DEBUG_OBJECT_ID = 7;

    // Strides of the host/shader structs in bytes (scalar layout); the Rust
    // mirrors assert them, tests/render/shared_layout.rs reads them from SPIR-V.
    uint VERTEX_STRIDE = 48;
    uint MATERIAL_STRIDE = 416;
    uint INSTANCE_STRIDE = 160;
    uint LIGHT_STRIDE = 64;
    uint BVH_NODE_STRIDE = 32;
    uint BVH_INSTANCE_STRIDE = 144;
    uint CLUSTER_STRIDE = 28;

    // Two-phase occlusion culling (gpu/clusters.rs, render/occlusion.rs), set 1 of the cull pipeline:
    // clusters, last frame's visibility, indirect draws (phase 1's, then phase 2's), counters, HiZ.
    id OCC_CLUSTERS = 0;
    id OCC_VISIBLE = 1;
    id OCC_COMMANDS = 2;
    id OCC_COUNTERS = 3;
    id OCC_HIZ = 4;
    // The pyramid's reduction has one set (its only one, so number 0): the
    // level read, the level written.
    id SET_HIZ = 0;
    id HIZ_SRC = 0;
    id HIZ_DST = 1;
    // Counters: clusters drawn in phase 1, drawn in phase 2, occluded,
    // outside the frustum; triangles drawn.
    uint OCC_COUNTER_SLOTS = 5;
    // At most this many triangles a cluster (bench/results/lavapipe-2core-vm-raster.md).
    uint CLUSTER_TRIANGLES = 128;

    // 4-wide BLASes (src/accel/bvh/wide.rs): the `count` of the binary node
    // at a BLAS's node offset marks a wide tree after it (the node keeps the
    // root bounds), and bit 30 of a wide child word marks a leaf.
    uint BVH_WIDE_HEADER = 1073741824;
    uint BVH_WIDE_LEAF = 1073741824;
    // The flat static tree's header (accel/flat.rs): always this 32-byte
    // slot of the BLAS node buffer, its wide nodes from the next one.
    uint BVH_FLAT_ROOT = 1;
}
