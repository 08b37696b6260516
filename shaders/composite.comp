#version 460
// Composite: base colour x AO with a soft key light, over a background gradient, sRGB-encoded RGBA8; and the
// accumulation over still frames (ours, docs/algorithm.md), which anti-aliases (each still frame's primary
// sample is jittered) and, in HRTAO, moves each pixel from its cell estimate c (paper §4-5) to its own rays:
//
//   AO = (k mean(c) + sum(unoccluded)) / (k + sum(rays)) = mean(c) + S / (k + S) r,   k = prior_rays (ours),
//
// the cell estimate counting as k of the pixel's own rays (S of them, r = own mean - mean(c) the residual). The
// residual is pooled with the neighbours' that agree (pooled_evidence), and the shown AO is smoothed over the
// still frames (smoothed). Colours weigh each sample's shade the same way.
// Per-pixel RTAO is the same with k -> 0; the paper's behaviour (no refinement) shows the current frame's c.
// The final AO is written back to `ao` (what read_ao and --ao-out see).
#include "common.glsl"
#include "hash_map.glsl"
#include "filter_plan.glsl"
#include "sky.glsl"

vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

vec3 srgb_to_linear(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), c));
}

// A linear colour as the output's 8-bit sRGB texel (RGBA, or BGRA for a swapchain that takes it directly).
uint pack_output(vec3 linear) {
    uvec3 c8 = uvec3(linear_to_srgb(linear) * 255.0 + 0.5);
    if ((g.flags & FLAG_OUTPUT_BGRA) != 0u) c8 = c8.bgr;
    return c8.r | (c8.g << 8) | (c8.b << 16) | (255u << 24);
}

// The output texel as a linear colour (pack_output's inverse, to 8 bits).
vec3 unpack_output(uint rgba) {
    vec3 c = unpackUnorm4x8(rgba).rgb;
    if ((g.flags & FLAG_OUTPUT_BGRA) != 0u) c = c.bgr;
    return srgb_to_linear(c);
}

vec3 false_color(uint v) {
    uint h = h_check(v);
    return vec3(float(h & 255u), float((h >> 8) & 255u), float((h >> 16) & 255u)) / 255.0;
}

vec3 heat(float x) {
    x = clamp(x, 0.0, 1.0);
    return clamp(vec3(1.5 - abs(4.0 * x - 3.0), 1.5 - abs(4.0 * x - 2.0), 1.5 - abs(4.0 * x - 1.0)), 0.0, 1.0);
}

// Debug views (paper Fig. 3 and ours): false colours of the finest cell, LOD used, samples per cell.
vec3 debug_color(uint index) {
    PixelCells pc = PixelCellRef(g.pixel_cells).v[index];
    if (g.mode == MODE_DEBUG_CELLS) return false_color(pc.cells[0]);
    if (g.mode == MODE_DEBUG_LOD) {
        uint used = UintRef(g.lod_used).v[index];
        return used >= LOD_COUNT ? vec3(0.0) : heat(float(used) / float(LOD_COUNT - 1u));
    }
    uint cell = pc.cells[0];
    uint s = cell < g.hash_capacity ? CellRef(g.hash_cells).v[cell].samples : 0u;
    return heat(log2(1.0 + float(s)) / log2(1.0 + float(max(g.max_samples, 1u))));
}

vec3 background(uvec2 pix) {
    float y = (float(pix.y) + 0.5) / float(g.height);
    return mix(g.background_top.rgb, g.background_bottom.rgb, y);
}

// The surface's albedo times `light`, and the selection's highlight over it.
vec3 lit(GPixel px, vec3 light) {
    // Section caps keep their colour in the clay look too.
    vec3 base = (g.flags & FLAG_SHADED) != 0u || (px.flags & GPIXEL_SECTION) != 0u ? unpack_base_color(px.color) : vec3(0.8);
    vec3 color = base * light;
    if ((InstanceRef(g.instances).v[px.instance].flags & INSTANCE_SELECTED) != 0u) {
        color = mix(color, vec3(1.0, 0.55, 0.1), 0.45);
    }
    return color;
}

// Base colour x key light of the pixel's sample (the background gradient on a miss).
vec3 shade(uvec2 pix, GPixel px) {
    if (px.t < 0.0) return background(pix);
    vec3 view = view_dir(px.position);
    // Key light from above-left of the viewer, plus a soft fill: a CAD-viewport look.
    vec3 key = normalize(-view + 0.6 * normalize(g.cam_v.xyz) - 0.4 * normalize(g.cam_u.xyz));
    // The shading normal: curved surfaces shade smoothly across their triangles.
    float diffuse = max(dot(unpack_normal(px.shading), key), 0.0);
    return lit(px, vec3(0.4 + 0.6 * diffuse));
}

// Internal pixels a feature-edge line spans: edge_width view pixels at this render scale (at least one).
int edge_steps() {
    float internal_per_view = float(g.height) / float(max(g.view_height, 1u));
    return clamp(int(round(g.edge_width * internal_per_view)), 1, int(MAX_EDGE_STEPS));
}

// Feature edges (CAD look): 1 where a neighbour along the 4 axes, up to edge_steps() pixels away, shows a miss,
// another instance, a surface off this pixel's tangent plane (a silhouette within one part) or a shading normal
// beyond the crease angle (a crease the model's normals draw, not the facets of a curved surface). Drawn on the
// nearer side, edge_width view pixels wide at any render scale.
// `spacing`: the pixels between the neighbours tested (the lattice while only its pixels show this view).
float edge_spaced(uvec2 pix, GPixel px, int spacing) {
    if ((g.flags & FLAG_EDGES) == 0u || px.t < 0.0) return 0.0;
    float pixel_size = pixel_world_size(px.t) * float(spacing);
    vec3 shading = unpack_normal(px.shading);
    int steps = edge_steps();
    const ivec2 OFFSETS[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
    for (int k = 1; k <= steps; ++k) {
        // Depth tests scale with the distance to the neighbour.
        float size = float(k) * pixel_size;
        for (int i = 0; i < 4; ++i) {
            ivec2 q = ivec2(pix) + k * spacing * OFFSETS[i];
            if (q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) continue;
            GPixel o = GBufferRef(g.gbuffer).px[uint(q.y) * g.width + uint(q.x)];
            if (o.t < 0.0) return 1.0;
            if (o.t < px.t) continue;   // the neighbour is nearer: it draws the line
            float off_plane = abs(dot(o.position - px.position, px.normal));
            if (o.instance != px.instance && off_plane > 0.5 * size) return 1.0;
            if (off_plane > 4.0 * size) return 1.0;
            if (dot(unpack_normal(o.shading), shading) < g.crease_cos) return 1.0;
        }
    }
    return 0.0;
}

float edge(uvec2 pix, GPixel px) {
    // In the first round of slices only the lattice's pixels show this view yet: step over the lattice.
    return edge_spaced(pix, px, g.still_index == 0u ? int(lattice()) : 1);
}

// Ours: the own rays' evidence about the cell estimate, pooled over the pixel's 3x3 neighbours on its surface.
// Each pixel stores (r, s) each frame: its residual r = o - mean(c) (own mean minus its mean cell estimate)
// over its s own rays, in one of two slots by still-frame parity, so no pixel reads a slot written in the same
// dispatch (neighbours are one frame behind).
layout(buffer_reference, scalar) buffer Vec4Ref { vec4 v[]; };

struct Evidence {
    float r;    // the pooled residual
    float s;    // the rays behind it
};

// The own mean's binomial noise variance v/s over s rays, about the blended estimate p.
float own_noise(float p, float s) {
    return max(p * (1.0 - p), 1.0 / (1.0 + s)) / s;
}

// Whether the pixel at `pix` + `d` (index `qi`) is a neighbour whose parity slots speak for the pixel `px`
// (pooled_evidence, smooth_prior): another pixel of the image on the same surface (normals within 25°, within 2
// pixels of its plane), and not one a local edit restarted, which may still hold in its slots what its pre-edit
// cells gave (the removed part's contact shadow); unedited neighbours' slots still hold.
bool slot_neighbour(uvec2 pix, ivec2 d, GPixel px, float pixel_size, out uint qi) {
    ivec2 q = ivec2(pix) + d;
    qi = 0u;
    if ((d.x == 0 && d.y == 0) || q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) return false;
    qi = uint(q.y) * g.width + uint(q.x);
    GPixel o = GBufferRef(g.gbuffer).px[qi];
    if (o.t < 0.0 || dot(o.normal, px.normal) < 0.9) return false;
    if (abs(dot(o.position - px.position, px.normal)) > 2.0 * pixel_size) return false;
    return !neighbour_slots_stale(o.position, g.ao_radius + exp2(float(pixel_lod(o.t))));
}

// Residual pooling (`residual_sigma` z_r > 0): a neighbour's residual joins, weighted by its rays and by
// exp(-d^2 / (2 z_r^2 var(d))), d its difference from the pixel's own and var(d) the two own means' noise.
// Residuals are the cells' bias seen through each pixel's own rays: neighbours sharing a cell share most of
// it, so pooling cuts the own rays' noise (the still image's flicker) several times while it follows the bias.
// As the own rays grow, var(d) shrinks and only neighbours with the same residual stay: the pixel converges
// to its own ray-traced value.
Evidence pooled_evidence(uvec2 pix, GPixel px, float r, float s, float p) {
    Vec4Ref slots = Vec4Ref(g.bias_evidence);
    uint n = g.width * g.height;
    uint index = pix.y * g.width + pix.x;
    uint write_slot = (g.still_index & 1u) * n;
    slots.v[write_slot + index].xy = vec2(r, s);
    Evidence e;
    e.r = r * s;
    e.s = s;
    if (s > 0.0 && g.still_index > 1u) {
        uint read_slot = n - write_slot;
        float pixel_size = pixel_world_size(px.t);
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                uint qi;
                if (!slot_neighbour(pix, ivec2(dx, dy), px, pixel_size, qi)) continue;
                vec2 rs = slots.v[read_slot + qi].xy;
                if (rs.y <= 0.0) continue;
                float vq = own_noise(p, rs.y);
                if (g.residual_sigma > 0.0) {
                    float d = rs.x - r;
                    float var_d = own_noise(p, s) + vq;
                    float w = exp(-d * d / (2.0 * g.residual_sigma * g.residual_sigma * var_d)) * rs.y;
                    e.r += w * rs.x;
                    e.s += w;
                }
            }
        }
    }
    e.r = e.s > 0.0 ? e.r / e.s : 0.0;
    return e;
}

// Ours: the cell estimate as a still image's prior. Each still frame samples it at a jittered position; the mean
// of n samples converges to the pixel's footprint average, but for the first few it still shows the noise of
// full-resolution cells (on the bundled scene 1.4x rougher than the final image). Their mean leans on the
// pixel's 3x3 neighbours' on its surface (their previous frame's mean, in the parity slots as pooled_evidence),
// with weight 1/n: the prior's noise falls from the first still frame, and the final image keeps a 1/n share.
float smooth_prior(uvec2 pix, GPixel px, float mean_c, float n) {
    Vec4Ref slots = Vec4Ref(g.bias_evidence);
    uint count = g.width * g.height;
    uint index = pix.y * g.width + pix.x;
    uint write_slot = (g.still_index & 1u) * count;
    slots.v[write_slot + index].w = mean_c;
    if (g.still_index == 0u || px.t < 0.0) return mean_c;
    uint read_slot = count - write_slot;
    float pixel_size = pixel_world_size(px.t);
    float sum = 0.0;
    float weight = 0.0;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            uint qi;
            if (!slot_neighbour(pix, ivec2(dx, dy), px, pixel_size, qi)) continue;
            sum += slots.v[read_slot + qi].w;
            weight += 1.0;
        }
    }
    if (weight == 0.0) return mean_c;
    return mix(mean_c, sum / weight, 1.0 / max(n, 1.0));
}

// Ours: the shown AO moves `still_smoothing` of the way to the new estimate each still frame (an exponential
// moving average of the refined estimates; `continued`: the pixel showed one in the previous frame of this
// accumulation). It keeps the own rays' noise from showing as flicker, for a lag of a few frames.
float smoothed(uint index, float ao, bool continued) {
    Vec4Ref slots = Vec4Ref(g.bias_evidence);
    uint n = g.width * g.height;
    uint write_slot = (g.still_index & 1u) * n;
    if (continued && g.still_index > 0u) {
        float shown = slots.v[n - write_slot + index].z;
        ao = mix(shown, ao, g.still_smoothing);
    }
    slots.v[write_slot + index].z = ao;
    return ao;
}

// Ours: the weight of the pooled residual (evidence `es` rays, `own` of them the pixel's) on the way to the final
// image of `still_samples` own rays. The shrinkage es / (k + es) alone shows the residual's noise v at w^2 v,
// largest when es nears k: the first refinement frames were 2-4x grainier than the final image. Capped at
// w_f (own / still_samples)^MONOTONE_EXPONENT (w_f: the final weight, the evidence scaled to the final rays), the
// grain w^2 v rises to the final image's w_f^2 v_f as long as v falls no faster than own^-(2 x exponent): an
// average of own rays falls as 1 / own, and pooled with the neighbours that agree (sharper as rays come in) we
// measured own^-1.6. Roughness is the noise's standard deviation, not its variance: with the exponent 1 the
// rounds after the held ones (24-48 own rays) were still 1.2-1.3x rougher than the final image (bundled scene,
// 806x800); with 1.5, 1.09x, for 2-3 % more error in those rounds and the same final image.
const float MONOTONE_EXPONENT = 1.5;
float monotone_weight(float es, float own, float k) {
    float w = es / (k + es);
    float final_rays = max(g.still_samples, 1.0);
    if (own <= 0.0 || own >= final_rays) return w;
    float es_final = es * final_rays / own;
    float w_final = es_final / (k + es_final);
    return min(w, w_final * pow(own / final_rays, MONOTONE_EXPONENT));
}

// Sky light (sky.glsl): the pixel's transfer, its cell estimate counting as k of its own rays, accumulated over
// the still frames as the AO is, its own rays' residual weighed as the AO's (wc the weight of this frame's cell
// estimate, `frames` the sum of those weights after this frame, `restart` whether the accumulation restarted
// this frame). Every ray the pixel traced counts as its own, the rays it traced into its cell too (a young
// map's frames): they sample its own transfer.
// The light of it is kept for --light-out. Turning the environment changes only `sky_light`'s coefficients:
// the accumulation goes on.
vec3 sky_pixel_light(uint index, GPixel px, float wc, float frames, float k, bool accumulates, bool restart) {
    SkyPixelRef sp = SkyPixelRef(g.sky_pixels);
    uint base = index * SKY_PIXEL_FLOATS;
    vec3 light = vec3(0.0);
    if (px.t >= 0.0) {
        bool traced = floatBitsToUint(sp.v[base + SKY_OWN_FRAME]) == g.frame_index + 1u;
        float rays = traced ? sp.v[base + SKY_OWN_RAYS] : 0.0;
        float acc_rays = (restart ? 0.0 : sp.v[base + SKY_ACC_RAYS]) + rays;
        sp.v[base + SKY_ACC_RAYS] = acc_rays;
        // The own rays' weight, as the AO's (monotone_weight): es / (k + es) once the final image's rays are
        // in, less before, so the first frames do not show their own rays' noise (rod's first frame under the
        // lobe at 640x360: 0.0166 -> 0.0120 against Cycles).
        float own_rays = accumulates ? acc_rays : rays;
        float w = own_rays > 0.0 ? monotone_weight(own_rays, own_rays, k) : 0.0;
        float t[SKY_COEFFS];
        for (uint i = 0u; i < SKY_COEFFS; ++i) {
            // The guard (common.glsl `finite_or`): nothing non-finite enters the accumulation.
            float resolved = finite_or(sp.v[base + SKY_RESOLVED + i], 0.0);
            float own = traced ? finite_or(sp.v[base + SKY_OWN + i], 0.0) : 0.0;
            float acc_cell = (restart ? 0.0 : sp.v[base + SKY_ACC_CELL + i]) + wc * resolved;
            float acc_own = (restart ? 0.0 : sp.v[base + SKY_ACC_OWN + i]) + own;
            sp.v[base + SKY_ACC_CELL + i] = acc_cell;
            sp.v[base + SKY_ACC_OWN + i] = acc_own;
            float mean_c = accumulates ? acc_cell / frames : resolved;
            float residual = own_rays > 0.0 ? (accumulates ? acc_own : own) / own_rays - mean_c : 0.0;
            t[i] = mean_c + w * residual;
        }
        light = max(sky_light(t), vec3(0.0));
    }
    sp.v[base + SKY_LIGHT] = light.r;
    sp.v[base + SKY_LIGHT + 1u] = light.g;
    sp.v[base + SKY_LIGHT + 2u] = light.b;
    return light;
}

const vec3 EDGE_COLOR = vec3(0.06, 0.07, 0.08);

// Slices (ours): in the first two rounds of a still image (`held_round`) each drawn pixel keeps its AO and
// colour aside (the third slot of `bias_evidence`), and the view shows the bilinear interpolation of a square
// grid of pixels (`level_spacing`, slice_order.rs, Renderer::level_spacing): round 0 each finer grid as it
// completes, round 1 round 0's finest until it ends, then all its pixels. Every presented frame shows the whole
// new view, smooth and sharper at each grid, never single pixels that differ from the image around them.
// A pixel keeps its shade times its AO, without the feature edges: a line sampled on a grid would show as a row
// of dots. The edges are drawn over the grid's interpolation per pixel once every pixel has this view's G-buffer
// (the round 0's last slice on).
// Push constant x = 1 (a frame that completes a grid, or round 0): the grid interpolated over every pixel;
// y = 1: with the edges.
uint kept_slot(uint index) {
    return 2u * g.width * g.height + index;
}

vec4 kept_aside(ivec2 q) {
    return Vec4Ref(g.bias_evidence).v[kept_slot(uint(q.y) * g.width + uint(q.x))];
}

void keep_aside(uint index, float ao, uint rgba) {
    Vec4Ref(g.bias_evidence).v[kept_slot(index)].xy = vec2(ao, uintBitsToFloat(rgba));
}

bool held_round() {
    return g.level_spacing > 0u;
}

// Uniform cubic B-spline weights of the grid points at offsets -1, 0, 1 and 2 from the cell's corner, at the
// fraction `f` of the cell: a convex combination, smooth (C2) across cells.
vec4 bspline_weights(float f) {
    float f2 = f * f;
    float f3 = f2 * f;
    float u = 1.0 - f;
    return vec4(u * u * u, 3.0 * f3 - 6.0 * f2 + 4.0, -3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0, f3) / 6.0;
}

// The grid of spacing `level_spacing` seen at `pix`: the cubic B-spline of the AO and colour its pixels kept
// aside (4 x 4 grid points). Each grid point holds one pixel's first estimate, noisy; the B-spline approximates
// rather than interpolates, which halves that noise at the grid points where bilinear interpolation keeps all of
// it, and leaves no creases along the grid lines.
void level_value(uvec2 pix, out float ao, out uint rgba) {
    int s = int(g.level_spacing);
    ivec2 base = (ivec2(pix) / s) * s;
    vec2 f = vec2(ivec2(pix) - base) / float(s);
    vec4 wx = bspline_weights(f.x);
    vec4 wy = bspline_weights(f.y);
    vec4 color = vec4(0.0);
    float wsum = 0.0;
    ao = 0.0;
    for (int j = 0; j < 4; ++j) {
        for (int i = 0; i < 4; ++i) {
            ivec2 q = base + s * ivec2(i - 1, j - 1);
            // Past the image's edges the grid points near them stand for the rest (the weights renormalise).
            if (q.x < 0 || q.y < 0 || q.x >= int(g.width) || q.y >= int(g.height)) continue;
            float w = wx[i] * wy[j];
            vec4 kept = kept_aside(q);
            ao += w * kept.x;
            color += w * unpackUnorm4x8(floatBitsToUint(kept.y));
            wsum += w;
        }
    }
    ao /= wsum;
    rgba = packUnorm4x8(color / wsum);
}

// Push constant 1, in a frame that completes a grid: the grid interpolated over every pixel.
void show_level() {
    uvec2 pix = gl_GlobalInvocationID.xy;
    if (pix.x >= g.width || pix.y >= g.height) return;
    uint index = pix.y * g.width + pix.x;
    float ao;
    uint rgba;
    level_value(pix, ao, rgba);
    if (push.y == 1u) {
        // Every pixel's G-buffer is this view's now: its edges, at full resolution.
        float e = 0.85 * edge_spaced(pix, GBufferRef(g.gbuffer).px[index], 1);
        rgba = pack_output(mix(unpack_output(rgba), EDGE_COLOR, e));
    }
    FloatRef(g.ao).v[index] = ao;
    UintRef(g.output_rgba).v[index] = rgba;
    Vec4Ref(g.bias_evidence).v[kept_slot(index)].z = ao;
}

void main() {
    if (push.x == 1u) {
        show_level();
        return;
    }
    uvec2 pix;
    uint index;
    if (!pixel_coords(pix, index)) return;
    GPixel px = GBufferRef(g.gbuffer).px[index];
    vec3 color;
    // The shade without the feature edges (the held rounds keep it aside); debug views keep their colour.
    vec3 plain = vec3(0.0);
    bool has_plain = false;
    // The sky light's `plain` is lit already (not a shade for the AO to darken).
    bool sky_shown = false;
    float final_ao = FloatRef(g.ao).v[index];
    if (px.t >= 0.0 && (g.mode == MODE_DEBUG_CELLS || g.mode == MODE_DEBUG_LOD || g.mode == MODE_DEBUG_SAMPLES)) {
        color = debug_color(index);
    } else {
        bool hashed = g.mode == MODE_HRTAO;
        plain = shade(pix, px);
        has_plain = true;
        vec3 s = mix(plain, EDGE_COLOR, 0.85 * edge(pix, px));
        // This sample: its cell estimate and its own rays (a miss counts as rays_per_pixel open rays, so
        // partly covered pixels weigh background and surface by coverage).
        // The guard (common.glsl `finite_or`): nothing non-finite enters the accumulation.
        float c = hashed && px.t >= 0.0 ? clamp(finite_or(FloatRef(g.ao).v[index], 1.0), 0.0, 1.0) : 1.0;
        PixelRays pr = PixelRaysRef(g.pixel_rays).v[index];
        float traced = float(pr.traced);
        float open = float(pr.unoccluded);
        if (px.t < 0.0 && (g.mode == MODE_RTAO || (hashed && g.still_index > 0u))) {
            traced = float(g.rays_per_pixel);
            open = traced;
        }
        // As AoSettings::accumulates: per-pixel RTAO, and HRTAO or AO off with refinement.
        bool accumulates = g.mode == MODE_RTAO || ((g.flags & FLAG_REFINE) != 0u && (hashed || g.mode == MODE_NO_AO));
        PixelAccumRef accum = PixelAccumRef(g.accum);
        PixelAccum a;
        // A local edit (ours) restarts the accumulation only of pixels whose AO it can change: within the AO
        // radius (plus their cell) of what it changed, and the pixels that see nothing after it (a part cut
        // away or removed may have left them: what they accumulated was its AO; a miss is exact at once).
        bool edited = px.t >= 0.0 ? edited_near(px.position, g.ao_radius + exp2(float(pixel_lod(px.t))))
                                  : edited_this_frame();
        bool restart = !accumulates || g.still_index == 0u || edited;
        if (restart) {
            a.shade_cell = vec3(0.0);
            a.cell = 0.0;
            a.shade_open = vec3(0.0);
            a.open = 0.0;
            a.rays = 0.0;
            a.frames = 0.0;
        } else {
            a = accum.v[index];
        }
        // Later frames' cell estimates count more (the n-th frame of the pixel's accumulation weighs n): their
        // cells hold more rays and have left the coarse fallbacks of the first frames, while the weighted mean
        // still moves smoothly. n is counted from the pixel's last restart (a local edit restarts some pixels
        // only): frames holds 1 + 2 + ... + (n - 1) = n (n - 1) / 2.
        float wc = round(0.5 + sqrt(2.0 * a.frames + 0.25));
        a.shade_cell += wc * s * c;
        a.cell += wc * c;
        a.shade_open += s * open;
        a.open += open;
        a.rays += traced;
        a.frames += wc;
        accum.v[index] = a;
        // k: the cell estimate's weight in rays (HRTAO), a vanishing weight otherwise (used only when the
        // pixel has no rays at all: AO off, a zero budget). AO = mean(c) + S / (k + S) * residual, the residual
        // pooled with the neighbours' in HRTAO (S its rays); without pooling this is
        // (k mean(c) + sum(unoccluded)) / (k + sum(rays)).
        float k = hashed ? max(g.prior_rays, 1e-6) : 1e-6;
        float ao = (k * a.cell / a.frames + a.open) / (k + a.rays);
        color = (k * a.shade_cell / a.frames + a.shade_open) / (k + a.rays);
        if (hashed && accumulates && g.still_index == 0u) {
            // A moving frame: no own rays, so the AO is this frame's cell estimate; the still frames' smoothing
            // starts from it.
            smooth_prior(pix, px, ao, 1.0);
            ao = smoothed(index, ao, false);
        } else if (hashed && accumulates) {
            float mean_c = smooth_prior(pix, px, a.cell / a.frames, wc);
            float r = a.rays > 0.0 ? a.open / a.rays - mean_c : 0.0;
            float p = (g.prior_rays * mean_c + a.open) / (g.prior_rays + a.rays);
            // A miss (mean(c) = 1, all rays open) has no residual.
            Evidence e = pooled_evidence(pix, px, r, px.t >= 0.0 ? a.rays : 0.0, p);
            ao = mean_c + monotone_weight(e.s, a.rays, k) * e.r;
            ao = smoothed(index, ao, a.frames > 1.0);
            // The colour: each sample's shade weighed as above, moved with the pooled AO.
            float own_ao = (k * mean_c + a.open) / (k + a.rays);
            vec3 shade_mean = (a.shade_cell + a.shade_open) / max(a.cell + a.open, 1e-6);
            color = (k * a.shade_cell / a.frames + a.shade_open) / (k + a.rays) + shade_mean * (ao - own_ao);
        }
        if (g.mode == MODE_NO_AO) {
            ao = 1.0;
            color = a.shade_cell / a.frames;
        }
        if (hashed && sky_on()) {
            // Sky light: the albedo lit by the environment through the pixel's transfer, the background as it is.
            vec3 light = sky_pixel_light(index, px, wc, a.frames, max(g.prior_rays, 1.0), accumulates, restart);
            plain = px.t >= 0.0 ? lit(px, light) : plain;
            sky_shown = true;
            color = mix(plain, EDGE_COLOR, 0.85 * edge(pix, px));
        }
        ao = clamp(ao, 0.0, 1.0);
        if (held_round()) {
            final_ao = ao;
        } else {
            FloatRef(g.ao).v[index] = ao;
        }
    }
    uint rgba = pack_output(color);
    if (held_round()) {
        // Kept aside; the pixel goes on showing the grid's interpolation, whose AO `ao` holds again (the
        // frame's resolve wrote the cell estimate there). In a frame that completes a grid, show_level runs
        // next and writes every pixel.
        keep_aside(index, final_ao, has_plain ? pack_output(sky_shown ? plain : plain * final_ao) : rgba);
        FloatRef(g.ao).v[index] = Vec4Ref(g.bias_evidence).v[kept_slot(index)].z;
    } else {
        UintRef(g.output_rgba).v[index] = rgba;
    }
}
