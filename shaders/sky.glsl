// Sky light (ours, the paper's "environment shadows" of §6; crates/hrtao-core/src/sky): with FLAG_SKY the
// ray-tracing update extends every ray open within R to infinity, and what escapes is kept as a transfer vector
// in the real spherical harmonics of the sky frame (sky/sh.rs, bands 0..SKY_BAND):
//
//   t_i = mean over the cosine-weighted rays of V(ω) Y_i(ω),   L = Σ_i e_i t_i,
//
// e_i the environment's coefficients (rotated and scaled on the host: `FrameGlobals::sky_env`). Since the rays
// are drawn with density cos/π, t is the projection of V max(0, n·ω)/π, and L the contract's
// (1/π) ∫ E V max(0, n·ω) dω for E in the bands kept. The transfer does not depend on the environment: turning or
// changing it changes e only, and no ray is traced again.
// Cells keep their sums beside HashCell (`sky_cells`, fixed point, so they add with int64 atomics); pixels keep
// the resolved cell transfer, their own rays' and the still accumulation of both (`sky_pixels`). Needs
// common.glsl.
#ifndef HRTAO_SKY_GLSL
#define HRTAO_SKY_GLSL

layout(buffer_reference, scalar) buffer SkyCellRef { int64_t v[]; };
layout(buffer_reference, scalar) buffer SkyPixelRef { float v[]; };

// One ray's basis value in the cells' fixed point (|Y_i| < 1 for the bands kept: SAMPLE_CAP rays stay far from
// int64 overflow).
const float SKY_FIXED = 16777216.0;
// Where a sky ray ends: nothing in a scene lies this far.
const float SKY_FAR = 1.0e30;
// Offsets into a pixel's SKY_PIXEL_FLOATS: the resolved cell transfer and the filter's pong of it (the sky's
// `ao` and `filter_tmp`: filter.comp filters it with the AO's weights), this frame's own rays' sum, the still
// accumulation of the cell transfer (weighted as the AO's) and of the own sums, the light (RGB).
const uint SKY_RESOLVED = 0u;
const uint SKY_PONG = SKY_COEFFS;
const uint SKY_OWN = 2u * SKY_COEFFS;
const uint SKY_ACC_CELL = 3u * SKY_COEFFS;
const uint SKY_ACC_OWN = 4u * SKY_COEFFS;
const uint SKY_LIGHT = 5u * SKY_COEFFS;
// The rays behind SKY_OWN and the frame that traced them (its `frame_index` + 1, as float bits; 0 in a new
// buffer: a pixel that traced nothing since holds an older one), and the own rays of the still accumulation.
const uint SKY_OWN_RAYS = 5u * SKY_COEFFS + 3u;
const uint SKY_OWN_FRAME = 5u * SKY_COEFFS + 4u;
const uint SKY_ACC_RAYS = 5u * SKY_COEFFS + 5u;

const bool SKY_FILTER = true;

bool sky_on() { return (g.flags & FLAG_SKY) != 0u; }

// A world direction in the sky frame (b_z the zenith).
vec3 sky_frame(vec3 d) {
    return vec3(dot(g.sky_axis_x.xyz, d), dot(g.sky_axis_y.xyz, d), dot(g.sky_axis_z.xyz, d));
}

// The associated Legendre polynomial P_l^m(x), m >= 0, Condon-Shortley phase (sky/sh.rs `legendre`).
float sky_legendre(int l, int m, float x) {
    float pmm = 1.0;
    if (m > 0) {
        float s = sqrt(max((1.0 - x) * (1.0 + x), 0.0));
        float odd = 1.0;
        for (int i = 0; i < m; ++i) {
            pmm *= -odd * s;
            odd += 2.0;
        }
    }
    if (l == m) return pmm;
    float pm1 = x * float(2 * m + 1) * pmm;
    if (l == m + 1) return pm1;
    float pll = 0.0;
    for (int ll = m + 2; ll <= l; ++ll) {
        pll = (float(2 * ll - 1) * x * pm1 - float(ll + m - 1) * pmm) / float(ll - m);
        pmm = pm1;
        pm1 = pll;
    }
    return pll;
}

// Every basis function at the unit sky-frame direction b (sky/sh.rs `eval`: index l(l + 1) + m, m > 0 the
// cosines, m < 0 the sines).
void sky_basis(vec3 b, out float y[SKY_COEFFS]) {
    float x = clamp(b.z, -1.0, 1.0);
    // cos(m φ) and sin(m φ) by recurrence from the unit azimuth b.xy / |b.xy|, without atan: atan(0, 0) is
    // undefined in GLSL (a GPU may return NaN on every face looking straight up); at the pole P_l^m (m > 0) is 0,
    // so the azimuth taken there, (1, 0), changes nothing.
    // FLAG_INJECT_POLE_NAN (a test hook) takes it as NaN there, as atan(0, 0) may on a GPU.
    float r = length(b.xy);
    vec2 pole = (g.flags & FLAG_INJECT_POLE_NAN) != 0u ? vec2(uintBitsToFloat(0x7fc00000u)) : vec2(1.0, 0.0);
    vec2 az = r > 0.0 ? b.xy / r : pole;
    float cm[int(SKY_BAND) + 1];
    float sm[int(SKY_BAND) + 1];
    cm[0] = 1.0;
    sm[0] = 0.0;
    for (int m = 1; m <= int(SKY_BAND); ++m) {
        cm[m] = cm[m - 1] * az.x - sm[m - 1] * az.y;
        sm[m] = sm[m - 1] * az.x + cm[m - 1] * az.y;
    }
    for (int l = 0; l <= int(SKY_BAND); ++l) {
        int c = l * (l + 1);
        for (int m = 0; m <= l; ++m) {
            // (l - m)! / (l + m)!
            float ratio = 1.0;
            for (int k = l - m + 1; k <= l + m; ++k) ratio /= float(k);
            float k_lm = sqrt(float(2 * l + 1) / (4.0 * PI) * ratio);
            float p = k_lm * sky_legendre(l, m, x);
            if (m == 0) {
                y[c] = p;
            } else {
                y[c + m] = sqrt(2.0) * p * cm[m];
                y[c - m] = sqrt(2.0) * p * sm[m];
            }
        }
    }
}

// The transfer of an open surface of normal n: the clamped cosine's bands (Â_l / π: 1, 2/3, 1/4) times the
// basis at n (sky/sh.rs `unshadowed`). A pixel without cells lights as open, as its AO is 1.
void sky_open_transfer(vec3 n, out float t[SKY_COEFFS]) {
    sky_basis(sky_frame(n), t);
    for (int l = 0; l <= int(SKY_BAND); ++l) {
        float a = l == 0 ? 1.0 : (l == 1 ? 2.0 / 3.0 : (l == 2 ? 0.25 : 0.0));
        for (int i = l * l; i < (l + 1) * (l + 1); ++i) t[i] *= a;
    }
}

// The fraction of an open surface's sky a transfer's band 0 shows: the cosine-weighted escaped fraction
// (t_0 = Y_0 times it).
float sky_escaped(float t0) {
    return t0 * 2.0 * sqrt(PI);
}

// The non-finite guard of a transfer vector (common.glsl `finite_or_count`): a NaN or infinite coefficient
// becomes 0 (at the pole, where an undefined azimuth is the likely cause, P_l^m with m > 0 is 0 anyway),
// counted once per vector.
void sky_finite(inout float t[SKY_COEFFS]) {
    bool ok = true;
    for (uint i = 0u; i < SKY_COEFFS; ++i) {
        if (!is_finite(t[i])) {
            t[i] = 0.0;
            ok = false;
        }
    }
    if (!ok) stat_add(STAT_NON_FINITE, 1u);
}

// The light of a transfer vector: Σ e_i t_i (RGB).
vec3 sky_light(float t[SKY_COEFFS]) {
    vec3 l = vec3(0.0);
    for (uint i = 0u; i < SKY_COEFFS; ++i) {
        l += t[i] * vec3(g.sky_env[3u * i], g.sky_env[3u * i + 1u], g.sky_env[3u * i + 2u]);
    }
    return l;
}

// Adds one cell's sums of basis values (a pixel's rays into it).
void sky_cell_add(uint cell, float sums[SKY_COEFFS]) {
    SkyCellRef cells = SkyCellRef(g.sky_cells);
    for (uint i = 0u; i < SKY_COEFFS; ++i) {
        atomicAdd(cells.v[cell * SKY_COEFFS + i], int64_t(round(sums[i] * SKY_FIXED)));
    }
}

// Empties the sums of a cell this thread has just claimed (hash_map.glsl `reset_counters`).
void sky_cell_reset(uint cell) {
    SkyCellRef cells = SkyCellRef(g.sky_cells);
    for (uint i = 0u; i < SKY_COEFFS; ++i) atomicExchange(cells.v[cell * SKY_COEFFS + i], int64_t(0));
}

// Coefficient i of a cell's transfer: its sum over its `samples` rays.
float sky_cell_mean(uint cell, uint i, float samples) {
    return float(SkyCellRef(g.sky_cells).v[cell * SKY_COEFFS + i]) / (SKY_FIXED * samples);
}

#ifdef HRTAO_TRACES
// Whether a ray open within R escapes to the sky: the rest of it, from R on, hits nothing (and the section
// planes' cut-away parts hide nothing).
bool sky_escapes(vec3 origin, vec3 dir) {
    float tmin = 0.0;
    float tmax = SKY_FAR;
    if (!section_clip(origin, dir, tmin, tmax)) return true;
    return !segment_occluded(origin, dir, max(tmin, g.ao_radius), tmax);
}
#endif

#endif
