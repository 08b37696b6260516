// The one definition of every GPU-visible struct and constant.
//
// This file is compiled twice: by the library (where `gpu_structs!`/`gpu_consts!` expand to `#[repr(C)]`
// Rust types, see `gpu.rs`) and by `build.rs` (where the same macros expand to GLSL source written to
// `$OUT_DIR/gpu_types.glsl`, included by every shader). GLSL blocks use `scalar` layout, so the Rust
// `#[repr(C)]` layout of these all-4-byte (or naturally aligned u64) fields is the GLSL layout.

gpu_consts! {
    /// Compute work-group edge (threads are WORKGROUP_SIZE x WORKGROUP_SIZE).
    WORKGROUP_SIZE: u32 = 8;
    /// Work groups per dimension of an indirect dispatch (the portable minimum of maxComputeWorkGroupCount).
    MAX_GROUPS_X: u32 = 65535;
    /// Levels of detail allocated per pixel: the target s_wd and 3 successively coarser ones (paper §4).
    LOD_COUNT: u32 = 4;
    /// `FrameGlobals::mode` values.
    MODE_RTAO: u32 = 0;
    MODE_HRTAO: u32 = 1;
    MODE_NO_AO: u32 = 2;
    MODE_DEBUG_CELLS: u32 = 3;
    MODE_DEBUG_LOD: u32 = 4;
    MODE_DEBUG_SAMPLES: u32 = 5;
    /// `FrameGlobals::flags` bits.
    FLAG_OUTPUT_BGRA: u32 = 1;
    FLAG_FILTER: u32 = 2;
    FLAG_CHECK_BOUNDS: u32 = 4;
    FLAG_SHADED: u32 = 8;
    /// Still-camera refinement (ours, docs/algorithm.md): from the second still frame every pixel traces its own
    /// rays, which also feed its cells, and its AO moves from the cell estimate to its own ray-traced estimate.
    FLAG_REFINE: u32 = 16;
    /// Feature edges (silhouettes and creases) drawn over the shading in the composite; never in the AO image.
    FLAG_EDGES: u32 = 32;
    /// Some region epoch is not 0 (local edits, ours): cell keys read the region table (hash_map.glsl); without
    /// it every epoch is 0 and the keys are the paper's.
    FLAG_REGION_EPOCHS: u32 = 64;
    /// The near-field control variate runs (ours, near_field.glsl, `additions::near_field::flags`: `near_field`
    /// on, in hash-map frames of a young map, `WorldHashMap::young`): the update classifies its rays and the
    /// resolve corrects by them; other frames trace the paper's first-hit queries.
    FLAG_NEAR_FIELD: u32 = 128;
    /// The map is young this frame (`WorldHashMap::young`). A moving frame without it is a navigation frame
    /// (`navigation_frame` in common.glsl), which resolves and filters as the paper does.
    FLAG_YOUNG_MAP: u32 = 256;
    /// The hash map's table has room (`TableLoad::has_room`): an insert takes the free slot ending its probe run
    /// rather than a stale slot met before it, so cells older than the cache lifetime keep their AO until the
    /// table needs their slots (hash_map.glsl `find_or_insert`).
    FLAG_MAP_HAS_ROOM: u32 = 512;
    /// Sky light (`LightSettings::sky`, crates/hrtao-core/src/sky): the update extends the rays open within R to
    /// infinity and its cells and pixels gather the transfer vector of the escaped ones (shaders/sky.glsl); the
    /// composite lights with the environment's coefficients (`FrameGlobals::sky_env`).
    FLAG_SKY: u32 = 1024;
    /// A test hook (`Renderer::set_inject_pole_nan`): the sky basis takes the pole's azimuth as NaN, as a GPU's
    /// atan(0, 0) may, so that a test proves the non-finite guard (STAT_NON_FINITE) keeps the image finite.
    FLAG_INJECT_POLE_NAN: u32 = 2048;
    /// Sky light: the highest spherical-harmonic band of the transfer vectors (sky/sh.rs), and their
    /// coefficients ((SKY_BAND + 1)²).
    SKY_BAND: u32 = 3;
    SKY_COEFFS: u32 = 16;
    /// Sky light: floats per pixel of `FrameGlobals::sky_pixels`: the resolved cell transfer and the filter's
    /// pong of it, this frame's own rays' transfer sum, the still accumulation of the cell transfer and of the own
    /// sums (SKY_COEFFS each), then the light (RGB), the own rays' count and frame, the accumulated own rays
    /// and a free word (shaders/sky.glsl).
    SKY_PIXEL_FLOATS: u32 = 88;
    /// Low bits of a pixel's filter plan holding its iteration count (the rest hold its cell's rays).
    FILTER_PLAN_BITS: u32 = 4;
    /// `FilterGuide::normal` of a pixel without AO (a miss, or no cell): never a packed normal (packSnorm2x16
    /// stops at -32767).
    GUIDE_NONE: u32 = 0x8000_8000;
    /// Most internal pixels a feature-edge line spans (bounds the composite's neighbour reads).
    MAX_EDGE_STEPS: u32 = 8;
    /// `FrameGlobals::projection` and `RasterPush::projection` values (camera.rs `Projection`).
    PROJECTION_PERSPECTIVE: u32 = 0;
    PROJECTION_ORTHOGRAPHIC: u32 = 1;
    /// `InstanceInfo::flags` bits.
    INSTANCE_SELECTED: u32 = 1;
    /// Section planes at most (`FrameGlobals::section0..2`).
    MAX_SECTIONS: u32 = 3;
    /// `GPixel::flags` bits: the pixel shows the cap of a solid cut open by a section plane.
    GPIXEL_SECTION: u32 = 1;
    /// `GPixel::instance` of a pixel whose primary ray hit nothing.
    NO_INSTANCE: u32 = 0xffff_ffff;
    /// Hash cell checksum value of a free cell (checksums are never 0: see hash.glsl).
    EMPTY_CELL: u32 = 0;
    /// A pixel cell index meaning "no cell" (miss, or the insert failed).
    INVALID_CELL: u32 = 0xffff_ffff;
    /// Rays a cell accumulates at most (coarser levels stop receiving propagated rays there): far from u32
    /// overflow, and the ratio unoccluded / samples stays exact in a float.
    SAMPLE_CAP: u32 = 0x0100_0000;
    /// Largest `max_samples`: the QMC index plus one frame's block claims stays far from u32 overflow.
    MAX_SAMPLES_LIMIT: u32 = 0x0010_0000;
    /// Entries of the region epoch table (local edits, ours): a power of two.
    REGION_COUNT: u32 = 65536;
    /// Boxes of the last local edit kept for the composite (more are merged into one).
    MAX_EDIT_BOXES: u32 = 64;
    /// Indices into `FrameStats::counters` (u32: each counts pixels or cells, at most one per pixel and level).
    STAT_CELLS_INSERTED: u32 = 0;
    STAT_FAILED_INSERTS: u32 = 1;
    STAT_MAX_PROBE: u32 = 2;
    STAT_RECLAIMED: u32 = 3;
    STAT_BOUNDS_VIOLATIONS: u32 = 4;
    STAT_CAPPED_PIXELS: u32 = 5;
    /// Pixels queued for the ray-tracing update this frame (compacted, see ray_target.glsl `queue_for_rays`).
    STAT_RAY_QUEUE: u32 = 6;
    /// Adaptive first-frame sampling (ours, ao_update.comp): the sum of the queued pixels' weights for the
    /// second half of the ray budget, in 1/ADAPT_WEIGHT_SCALE units.
    STAT_ADAPT_WEIGHT: u32 = 7;
    /// Pixels queued for the à-trous filter this frame: those whose plan takes at least one iteration
    /// (resolve.comp, filter_plan.glsl `store_resolved`).
    STAT_FILTER_QUEUE: u32 = 8;
    /// Pixels whose target cell still takes rays but that a fractional budget (`trace_fraction`) left out of
    /// this frame's ray queue: with the queued ones, the pixels on young cells.
    STAT_UNPICKED_PIXELS: u32 = 9;
    /// Values a guard found non-finite (NaN or infinite) and replaced where they were made, before they entered
    /// the map's sky sums, a pixel's own or resolved transfer or its resolved AO (common.glsl
    /// `finite_or_count`): 0 on a sound device; reported as `FrameReport::non_finite`. The composite's last
    /// guard before the still accumulation replaces without counting (`finite_or`: it writes no statistics).
    STAT_NON_FINITE: u32 = 10;
    // 11-13: free.
    /// Counters below this index are reset at the start of every frame (with all of `FrameStats::rays`).
    STAT_PER_FRAME: u32 = 14;
    /// Live cells in the table: persistent (not reset per frame), incremented on insert into a free slot.
    STAT_OCCUPIED: u32 = 14;
    /// Words of `FrameStats::counters` (even, so that `FrameStats::rays` sits at an 8-byte offset).
    STAT_COUNT: u32 = 16;
    /// Indices into `FrameStats::rays` (u64: 3840 x 2160 pixels x 1024 rays is above 2^33).
    RAYS_ALL: u32 = 0;
    /// Rays traced by the still-camera refinement (included in RAYS_ALL).
    RAYS_REFINE: u32 = 1;
    /// Rays the target cells took this frame (the paper's collaborative rays; refinement rays that a target
    /// cell also takes are counted here too).
    RAYS_CELL: u32 = 2;
    RAYS_COUNT: u32 = 3;
    /// Offsets in words into the indirect dispatch arguments (`dispatch_args`, written by the last work group of the cell finder and of the resolve, queue_args.glsl):
    /// the ray-tracing update's, then the filter's. Each queue's block: its work-group counts (3 words), the count
    /// of work groups done (1), then, at QUEUE_TRACE_ARGS, the same work as a ray-tracing launch size in threads
    /// (`VkTraceRaysIndirectCommandKHR`, the ray-tracing pipeline backend's indirect trace), then a free word.
    RAY_ARGS_OFFSET: u32 = 0;
    FILTER_ARGS_OFFSET: u32 = 8;
    QUEUE_TRACE_ARGS: u32 = 4;
    DISPATCH_ARGS_WORDS: u32 = 16;
    /// Probe rays a frame traces at most (`probes.rs`: the walk's gravity and collision rays).
    MAX_PROBE_RAYS: u32 = 64;
}

gpu_structs! {
    /// A probe ray (`probes.rs`): from `origin` along the unit `dir`, over the segment [tmin, tmax]; `tag` comes
    /// back in its hit (the asker's own number: which ask an answer belongs to).
    struct ProbeRay {
        origin: [f32; 3],
        tmin: f32,
        dir: [f32; 3],
        tmax: f32,
        tag: u32,
        pad0: u32,
        pad1: u32,
        pad2: u32,
    }

    /// What a probe ray found: the distance of the closest hit (negative: none on its segment, in the region the
    /// section planes keep), the hit triangle's unit normal turned toward the ray's origin, and its instance.
    struct ProbeHit {
        normal: [f32; 3],
        t: f32,
        instance: u32,
        /// The ray's `tag`.
        tag: u32,
        pad1: u32,
        pad2: u32,
    }

    /// Per-frame parameters, read by every pass (binding 1).
    struct FrameGlobals {
        /// Camera: eye position; `cam_u`/`cam_v` span half the image (perspective: right * tan(fov/2) * aspect,
        /// up * tan(fov/2); orthographic: the same in world units, up * ortho_height/2); `cam_w` is the unit
        /// forward vector. See `projection`.
        eye: [f32; 4],
        cam_u: [f32; 4],
        cam_v: [f32; 4],
        cam_w: [f32; 4],
        /// Sub-pixel offset of this frame's primary samples, in pixels from the pixel centre (0 = centre).
        jitter: [f32; 2],
        width: u32,
        height: u32,
        /// Frames since the camera, the scene or the settings last changed (0 = a new view): the accumulation
        /// index of per-pixel RTAO and of the still-camera refinement.
        still_index: u32,
        /// The paper's F (eq. 6): bumped on every scene edit.
        scene_f: u32,
        /// Monotonic count of rendered frames (a hash cell's "last used" stamp).
        frame_index: u32,
        /// `frame_index` of the first frame rendered with the current F: cells last used before it are free.
        f_start_frame: u32,
        mode: u32,
        flags: u32,
        rays_per_pixel: u32,
        ao_radius: f32,
        /// eq. (2) as we read it (docs/algorithm.md): the world size of s_p view pixels per unit of distance,
        /// so s_w = d * s_w_per_distance.
        s_w_per_distance: f32,
        /// Upper bound of the finest s_w (a fraction of the AO radius), so cells never smear contact shadows.
        s_w_max: f32,
        /// eq. (3): log2 of the smallest world feature s_min (rounded to a power of two, see hash.glsl).
        log2_s_min: i32,
        /// eq. (5): normal discretisation.
        s_nd: f32,
        hash_capacity: u32,
        max_samples: u32,
        min_samples: u32,
        max_probe: u32,
        /// eq. (6)'s lazy removal: a cell last used more than this many frames ago is older than the cache
        /// lifetime (`MapSettings::cache_lifetime_s`, turned into frames by `hash_map::FrameClock`) and may be
        /// reclaimed; u32::MAX: none is.
        lifetime_frames: u32,
        filter_iterations: u32,
        /// Still-camera refinement: the cell estimate counts as this many of the pixel's own rays.
        prior_rays: f32,
        /// Variance-guided filtering (ours, docs/algorithm.md): neighbours whose AO differs from the pixel's by
        /// more than this many standard deviations of the cells' binomial noise stop the filter; 0 = the paper's
        /// footprint-bounded filter.
        filter_sigma: f32,
        /// Local edits (ours, docs/algorithm.md): the LOD of the largest finest cell (s_w_max), which sets the
        /// grids of the region epoch table (hash.glsl `region_index`).
        region_lod: i32,
        /// Feature edges: normals meeting at more than the crease angle draw a crease (its cosine).
        crease_cos: f32,
        background_top: [f32; 4],
        background_bottom: [f32; 4],
        /// Buffer device addresses of the frame's buffers.
        gbuffer: u64,
        instances: u64,
        geometries: u64,
        ao: u64,
        lod_used: u64,
        filter_tmp: u64,
        /// Per pixel: this frame's own rays (`PixelRays`), and the still-camera accumulation (`PixelAccum`).
        pixel_rays: u64,
        accum: u64,
        output_rgba: u64,
        hash_cells: u64,
        pixel_cells: u64,
        stats: u64,
        /// Pixel indices that trace rays this frame (STAT_RAY_QUEUE of them), those the filter runs on
        /// (STAT_FILTER_QUEUE), and the indirect dispatch sizes (RAY_ARGS_OFFSET, FILTER_ARGS_OFFSET).
        ray_queue: u64,
        filter_queue: u64,
        dispatch_args: u64,
        /// `RegionTable`: REGION_COUNT epochs, then the last local edit (frame index, box count, boxes).
        regions: u64,
        /// `PROJECTION_PERSPECTIVE` (rays from `eye`) or `PROJECTION_ORTHOGRAPHIC` (rays along `cam_w` from the
        /// plane through `eye`, spread by `cam_u`/`cam_v`).
        projection: u32,
        /// eq. (2) as we read it, the distance-independent term: s_w = s_w_base + d * s_w_per_distance
        /// (0 in perspective; s_p * ortho_height / view height in orthographic, where s_w_per_distance is 0).
        s_w_base: f32,
        /// Height of the view in pixels (`Renderer::view_height`; the internal `height` when there is no
        /// separate view): s_p and the feature-edge width count view pixels.
        view_height: u32,
        /// Feature-edge line width in view pixels (`EDGE_WIDTH`), drawn at any render scale.
        edge_width: f32,
        /// Section planes (section.rs): xyz the unit normal, w the offset d; geometry where n·p > d is cut away.
        /// The first `section_count` are in use.
        section0: [f32; 4],
        section1: [f32; 4],
        section2: [f32; 4],
        section_count: u32,
        /// Still-camera refinement (ours): neighbours' own-ray residuals within this many standard deviations
        /// of the pixel's join its residual (composite.comp); 0 = the pixel's own only.
        residual_sigma: f32,
        /// Still-camera refinement (ours): the shown AO moves this fraction of the way to the new estimate
        /// each still frame (1 = no smoothing).
        still_smoothing: f32,
        /// Still-camera refinement (ours): the own rays per pixel of a final still image (`still_samples`), which
        /// cap the own-ray residual's weight on the way there (composite.comp `monotone_weight`).
        still_samples: f32,
        /// Per pixel, two slots (by still-frame parity) of (residual, rays, shown AO, prior): the pixel's own
        /// mean minus its mean cell estimate over its own rays, written by the composite each frame and pooled
        /// over neighbours in the next, the AO it showed and its mean cell estimate (composite.comp); then a
        /// third slot, the first two rounds of slices' (AO, RGBA8, AO shown, 0) (`held_round`).
        bias_evidence: u64,
        /// Fractional ray budget (ours): outside refinement frames, a pixel whose cell takes rays traces this
        /// frame with this probability (1 = every such pixel, as the paper), see ray_target.glsl.
        trace_fraction: f32,
        /// eq. (5): the offset of the normal bins in bins, floor(n s_nd + offset) (`MapSettings::offset_bins`).
        normal_offset: f32,
        /// Per pixel, from the resolve to the filter and composite (filter_plan.glsl): the à-trous iterations the
        /// pixel takes and the rays of the cell its AO came from.
        filter_plan: u64,
        /// Per pixel, from the resolve to the filter's taps (filter_plan.glsl): position and packed normal in
        /// 16 bytes (a tap then reads a quarter of a cache line, not a 48-byte G-buffer sample).
        filter_guide: u64,
        /// Slices (ours, `FrameDesc::slices`): this frame draws every `lattice`-th pixel in x and y from
        /// (`lattice_x`, `lattice_y`) (1, 0, 0: the whole image); passes that read this frame's neighbours step
        /// by `lattice` pixels (common.glsl `neighbour`).
        lattice: u32,
        lattice_x: u32,
        lattice_y: u32,
        /// Frames, counted from a local edit's, in which a pixel drawn sees that edit (hash_map.glsl
        /// `edited_near`): 1, or a round of slices, so each pixel sees it once.
        edit_window: u32,
        /// Slices (ours): in the first two rounds of a still image, the spacing of the square grid of pixels
        /// the view shows interpolated (`slice_order::level`, `Renderer::level_spacing`); 0: the view shows the
        /// pixels as they are drawn.
        level_spacing: u32,
        /// The `frame_index` of the still image's first frame: a pixel resolved since then holds this still
        /// image's `SlicePrior`.
        still_start_frame: u32,
        /// Per pixel `SlicePrior`: the cell estimate it resolved when last drawn (slices' filter taps).
        slice_prior: u64,
        /// Sky light (`FLAG_SKY`, shaders/sky.glsl): per hash cell, SKY_COEFFS fixed-point sums (int64) of the
        /// escaped rays' basis values; per pixel, SKY_PIXEL_FLOATS floats. 0 without the sky light.
        sky_cells: u64,
        sky_pixels: u64,
        /// Sky light: the sky frame's axes in world coordinates (b_i = dot(sky_axis_i, d); sky/environment.rs).
        sky_axis_x: [f32; 4],
        sky_axis_y: [f32; 4],
        sky_axis_z: [f32; 4],
        /// Sky light: the environment's coefficients, rotated and scaled by its intensity (RGB per coefficient).
        sky_env: [f32; 48],
    }

    /// One pixel of the G-buffer written by the primary visibility pass.
    struct GPixel {
        /// World-space hit position.
        position: [f32; 3],
        /// Hit distance along the primary ray; negative when the ray hit nothing.
        t: f32,
        /// Geometric (face) normal, unit length, turned toward the camera.
        normal: [f32; 3],
        /// Scene instance id (`NO_INSTANCE` on a miss).
        instance: u32,
        /// Base colour, sRGB-encoded RGBA8 (`pack_base_color` in normal_pack.glsl): the 8 bits the output has,
        /// in 4 bytes instead of 12 (every pass that reads the G-buffer reads less).
        color: u32,
        /// `GPIXEL_*` bits.
        flags: u32,
        /// Shading normal (interpolated vertex normals, or `normal` where the geometry has none), unit length,
        /// on `normal`'s side, octahedral-packed (`pack_normal` in normal_pack.glsl, `gpu::pack_normal`).
        shading: u32,
    }

    /// Per scene instance: where its mesh's geometries start in the geometry table.
    struct InstanceInfo {
        geometry_base: u32,
        flags: u32,
    }

    /// Per BLAS geometry (a glTF primitive): its vertex, index and shading-normal buffers and base colour.
    struct GeometryInfo {
        vertices: u64,
        indices: u64,
        /// Per-vertex shading normals, `gpu::pack_normal`-packed in object space; 0: the geometry shades flat.
        normals: u64,
        color: [f32; 4],
    }

    /// One visible instance drawn by the rasterised primary visibility (raster.rs): its object-to-world
    /// transform as three rows (`world = row_i · (p, 1)`) and its scene instance id.
    struct RasterInstance {
        row0: [f32; 4],
        row1: [f32; 4],
        row2: [f32; 4],
        instance: u32,
        _pad: [u32; 3],
    }

    /// Push constants of the visibility draw (visibility.vert): the camera, in clip form, and the tables.
    struct RasterPush {
        /// xyz: eye; w: perspective, the near plane distance (depth = near / view distance, reversed);
        /// orthographic, 1 / the far plane distance (see `projection`).
        eye: [f32; 4],
        /// `cam_u / |cam_u|^2` and `cam_v / |cam_v|^2` (see `FrameGlobals`): clip x, y = dot(p - eye, ·).
        cam_u: [f32; 4],
        cam_v: [f32; 4],
        /// Unit forward vector: clip w = dot(p - eye, cam_w).
        cam_w: [f32; 4],
        geometries: u64,
        instances: u64,
        /// `PROJECTION_*`. Orthographic: clip w = 1 and depth = 1 - dot(p - eye, cam_w) * eye.w (eye.w is then
        /// 1 / the far plane distance, depth stays linear and reversed).
        projection: u32,
        _pad: u32,
        /// This frame's sub-pixel jitter (`FrameGlobals::jitter`) in normalised device coordinates, so the
        /// rasteriser samples where the jittered camera rays go, plus a perspective tile's centre
        /// (`Tile::ndc_offset`): the image moves by minus this.
        jitter_ndc: [f32; 2],
        /// Address of the frame's `FrameGlobals` (the section planes clip the draws).
        globals: u64,
        /// Address of the draws' geometries (u32 per draw, in draw order): a draw's is
        /// `draw_geometries[first_draw + gl_DrawID]` (gl_DrawID counts the draws of one indirect call).
        draw_geometries: u64,
        /// The first draw of the call.
        first_draw: u32,
        _pad1: u32,
    }

    /// One cell of the world-space hash map (paper §1).
    struct HashCell {
        /// The cell's key and age in one 64-bit word, claimed and re-stamped by a single atomic compare-and-swap:
        /// low 32 bits the checksum (the second, independent hash of the key; `EMPTY_CELL` marks a free cell),
        /// high 32 bits the `frame_index` of the last frame that used the cell (lazy removal, eq. 6).
        stamp: u64,
        /// Rays accumulated in the cell (at most `max_samples` at the level that traces into it; coarser levels
        /// stop receiving propagated rays at `SAMPLE_CAP`).
        samples: u32,
        /// Rays that escaped (hit nothing within the AO radius).
        unoccluded: u32,
        /// Next index into the cell's QMC sequence (paper §3); rays are claimed from it in blocks, so it exceeds
        /// `max_samples` by at most one block per pixel of one frame.
        qmc_index: u32,
        /// Near-field control variate (ours): the rays classified by whether they hit within the near radius
        /// r_n (only in frames of a young map, `FLAG_NEAR_FIELD`), and those of them that hit nothing there.
        near_traced: u32,
        near_open: u32,
        /// The longest probe run (slots from this home slot to where the key lies, 1 = here) of any key whose home
        /// slot this is, ever claimed since the table was emptied: a read-only lookup (`find_cell`) of a key
        /// homed here scans no further, so that an absent key costs what a present one does rather than a scan to
        /// the first free slot (hash_map.glsl). Also rounds the cell to 32 bytes.
        probe_run: u32,
    }

    /// One CPU-vs-GPU hash test case: inputs, then the GPU's outputs (hash_test.comp).
    struct HashTestCase {
        position: [f32; 3],
        /// Target world feature size s_w (eq. 2) for the point.
        s_w: f32,
        normal: [f32; 3],
        scene_f: u32,
        /// The region epoch of eq. (6) as we extend it (0 = the paper's key).
        epoch: u32,
        /// LOD offset added to the point's level (0..LOD_COUNT).
        lod_offset: u32,
        index: u32,
        checksum: u32,
        lod: i32,
        /// Region epoch table entry of the point's cell (`region_index` at the renderer's region_lod).
        region: u32,
    }

    /// Per pixel, the hash cell indices at the LOD_COUNT levels (cell finder output).
    struct PixelCells {
        cells: [u32; 4],
    }

    /// Per pixel, what the filter's taps read of it (filter_plan.glsl): its position, and its normal
    /// octahedron-encoded in 2 x 16 bits (`GUIDE_NONE`: no AO there, the tap stops).
    struct FilterGuide {
        position: [f32; 3],
        normal: u32,
    }

    /// Per pixel, the cell estimate resolve.comp found for it when it was last drawn, and that frame's
    /// `frame_index`: in a still image's slices the filter taps the pixels of the other slices through it
    /// (filter.comp, `filter_full_taps`).
    struct SlicePrior {
        ao: f32,
        frame: u32,
    }

    /// Per pixel, the rays it traced itself this frame (per-pixel RTAO, still-camera refinement).
    struct PixelRays {
        traced: u32,
        unoccluded: u32,
        /// Counted while the map is young (`FLAG_YOUNG_MAP`): every ray the pixel traced this frame (into its
        /// cell or its own), and those that hit nothing within the near radius r_n (near-field control variate,
        /// ours; meaningful with `FLAG_NEAR_FIELD`).
        near_traced: u32,
        near_open: u32,
        /// Pooled residual control variate (ours): of the `near_traced` rays, those that hit nothing within R.
        open: u32,
    }

    /// Per pixel, the accumulation over still frames (composite.comp). With shade = base colour x light of
    /// each frame's (jittered) sample and c = its cell estimate: the sum of shade x c, the sum of shade x the
    /// unoccluded count of the pixel's own rays, the sums of c and of unoccluded counts (the AO alone), and
    /// the pixel's own rays.
    struct PixelAccum {
        shade_cell: [f32; 3],
        cell: f32,
        shade_open: [f32; 3],
        open: f32,
        rays: f32,
        frames: f32,
    }

    /// Counters of a frame, in device memory; copied to a host-visible buffer once at the end of the frame.
    struct FrameStats {
        counters: [u32; 16],
        rays: [u64; 3],
    }
}
