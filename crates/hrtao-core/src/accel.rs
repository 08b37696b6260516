//! Acceleration structures: one BLAS per unique mesh (one geometry per primitive, built for fast trace and
//! compacted), one TLAS over the scene's visible instances, rebuilt after instance edits.
use std::sync::{Arc, Mutex};
use std::time::Instant;

use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;
use hrtao_scene::{Aabb, Scene};

use crate::barrier::{Stage, Use};
use crate::buffer::{full_barrier, Buffer};
use crate::context::Gpu;
use crate::error::{CoreError, Result};
use crate::gpu::{GeometryInfo, InstanceInfo};
use crate::pass::Resource;
use crate::raster::{RasterGeometry, RasterScene};
use crate::recorder::Recorder;
use crate::section::{Sections, Side};

/// An acceleration structure with its backing buffer; destroyed on drop.
pub struct AccelStruct {
    gpu: Arc<Gpu>,
    pub raw: vk::AccelerationStructureKHR,
    pub address: u64,
    _buffer: Buffer,
}

impl AccelStruct {
    fn new(gpu: &Arc<Gpu>, name: &str, ty: vk::AccelerationStructureTypeKHR, size: u64) -> Result<Self> {
        let buffer = Buffer::new(
            gpu,
            name,
            size,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR,
        )?;
        unsafe {
            let raw = gpu
                .accel
                .create_acceleration_structure(
                    &vk::AccelerationStructureCreateInfoKHR::default()
                        .buffer(buffer.raw)
                        .size(size)
                        .ty(ty),
                    None,
                )
                .map_err(|e| CoreError::from_vk("vkCreateAccelerationStructureKHR", e))?;
            let address = gpu.accel.get_acceleration_structure_device_address(
                &vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw),
            );
            Ok(AccelStruct {
                gpu: gpu.clone(),
                raw,
                address,
                _buffer: buffer,
            })
        }
    }
}

impl Drop for AccelStruct {
    fn drop(&mut self) {
        unsafe { self.gpu.accel.destroy_acceleration_structure(self.raw, None) }
    }
}

/// Timings and sizes of the last builds.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct BuildStats {
    pub blas_count: usize,
    pub geometry_count: usize,
    pub blas_ms: f64,
    pub blas_bytes: u64,
    pub tlas_ms: f64,
    pub tlas_instances: usize,
    pub geometry_bytes: u64,
}

/// A scratch buffer whose device address is aligned as the device requires.
struct Scratch {
    _buffer: Buffer,
    base: u64,
}

impl Scratch {
    fn new(gpu: &Arc<Gpu>, size: u64) -> Result<Scratch> {
        let align = gpu.scratch_alignment;
        let buffer = Buffer::new(
            gpu,
            "AS scratch",
            size + align,
            MemoryLocation::GpuOnly,
            vk::BufferUsageFlags::empty(),
        )?;
        let base = buffer.address.div_ceil(align) * align;
        Ok(Scratch {
            _buffer: buffer,
            base,
        })
    }
}

/// TLAS builds so far in this process: each build's generation (`SceneGpu::tlas_generation`) is unique.
static TLAS_BUILDS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn align_up(v: u64, a: u64) -> u64 {
    v.div_ceil(a) * a
}

/// The scene on the GPU: geometry buffers, BLASes, instance tables and the TLAS.
pub struct SceneGpu {
    gpu: Arc<Gpu>,
    _vertices: Buffer,
    _indices: Buffer,
    _normals: Option<Buffer>,
    pub geometries: Buffer,
    /// Per mesh: index of its first geometry in `geometries`, or None when the mesh has no triangles.
    geometry_base: Vec<Option<u32>>,
    blas: Vec<Option<AccelStruct>>,
    pub instance_info: Buffer,
    /// The instance table as last written or queued (`InstanceInfo` per scene instance): a highlight change
    /// rewrites only its flags.
    infos: Vec<InstanceInfo>,
    /// The instance table's new contents waiting for the next frame's commands (`record_uploads`): a highlight
    /// change goes to the device in the queue, after the frames before it, with no host wait.
    pending_infos: Mutex<Option<Vec<InstanceInfo>>>,
    /// Bumped by every highlight change (`set_highlight`): the composite shows it, the AO does not depend on it.
    highlight_version: u64,
    tlas_instances: Buffer,
    pub tlas: AccelStruct,
    /// The TLAS's storage size and its build scratch, kept for the next build: a section-plane drag rebuilds
    /// the TLAS every step and reuses both while they fit.
    tlas_capacity: u64,
    tlas_scratch: Option<(u64, Scratch)>,
    /// The build `tlas` is, unique over every scene of the process: a descriptor must be written again for
    /// every new generation, whatever the handle value (a freed handle value may come back).
    tlas_generation: u64,
    /// Draw list of the rasterised primary visibility (the TLAS's instances), updated with the TLAS.
    pub raster: RasterScene,
    pub stats: BuildStats,
    /// Bumped by every `update_instances` (edits, visibility, sections): an image of an older version is stale.
    version: u64,
    /// The scene's F at the last `update_instances`, and the located changes between synced F values
    /// (from, to, world boxes or None when unknown), newest last: see `changes_between`.
    synced_f: u32,
    changes: std::collections::VecDeque<SyncedChange>,
    /// Object-space bounds per mesh (classified against the section planes).
    mesh_bounds: Vec<Aabb>,
    sections: Sections,
    /// Section plane changes so far: each is a scene change (the renderer adds it to F, eq. 6).
    section_changes: u32,
    /// Per recent plane change (newest last): the count it produced and where geometry appeared or
    /// disappeared (None: not located), see `section_changes_between`.
    section_log: std::collections::VecDeque<(u32, Option<Vec<WorldBox>>)>,
    /// Instances per `Side` in the current TLAS (kept, crossing, cut).
    pub section_sides: [usize; 3],
}

/// The scene's F went from `from` to `to` between two `update_instances`, changing the world boxes `boxes`
/// (None: not located).
struct SyncedChange {
    from: u32,
    to: u32,
    boxes: Option<Vec<(Vec3, Vec3)>>,
}

/// A world-space box (min, max) where geometry changed.
pub type WorldBox = (Vec3, Vec3);

/// Synced changes `SceneGpu::changes_between` can look back over.
const SYNCED_CHANGES: usize = 64;

/// Maximum instance id stored in a TLAS instance's 24-bit custom index.
const MAX_INSTANCES: usize = (1 << 24) - 1;

fn geometry_triangles(
    vertex_address: u64,
    index_address: u64,
    vertex_count: u32,
) -> vk::AccelerationStructureGeometryKHR<'static> {
    vk::AccelerationStructureGeometryKHR::default()
        .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
        .flags(vk::GeometryFlagsKHR::OPAQUE)
        .geometry(vk::AccelerationStructureGeometryDataKHR {
            triangles: vk::AccelerationStructureGeometryTrianglesDataKHR::default()
                .vertex_format(vk::Format::R32G32B32_SFLOAT)
                .vertex_data(vk::DeviceOrHostAddressConstKHR {
                    device_address: vertex_address,
                })
                .vertex_stride(12)
                .max_vertex(vertex_count.saturating_sub(1))
                .index_type(vk::IndexType::UINT32)
                .index_data(vk::DeviceOrHostAddressConstKHR {
                    device_address: index_address,
                }),
        })
}

/// A BLAS build of `geoms`: fast trace, compactable.
fn blas_build_info<'a>(
    geoms: &'a [vk::AccelerationStructureGeometryKHR<'a>],
) -> vk::AccelerationStructureBuildGeometryInfoKHR<'a> {
    vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
        .flags(
            vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE
                | vk::BuildAccelerationStructureFlagsKHR::ALLOW_COMPACTION,
        )
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(geoms)
}

impl SceneGpu {
    pub fn new(gpu: &Arc<Gpu>, scene: &Scene) -> Result<SceneGpu> {
        if scene.instances.len() > MAX_INSTANCES {
            return Err(CoreError::Invalid(format!(
                "{} instances: at most {MAX_INSTANCES} are supported",
                scene.instances.len()
            )));
        }
        // 1. Geometry: all primitives' vertices, indices and shading normals packed into three buffers.
        let mut vertices: Vec<[f32; 3]> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut normals: Vec<u32> = Vec::new();
        struct Geo {
            vertex_offset: u64,
            index_offset: u64,
            /// Byte offset of its packed normals; None: it shades flat.
            normal_offset: Option<u64>,
            vertex_count: u32,
            triangles: u32,
            color: [f32; 4],
            double_sided: bool,
        }
        let mut per_mesh: Vec<Vec<Geo>> = Vec::with_capacity(scene.meshes.len());
        for mesh in &scene.meshes {
            let mut geos = Vec::new();
            for p in &mesh.primitives {
                let tris = (p.indices.len() / 3) as u32;
                if tris == 0 || p.positions.is_empty() {
                    continue;
                }
                let has_normals = p.normals.len() == p.positions.len();
                geos.push(Geo {
                    vertex_offset: (vertices.len() * 12) as u64,
                    index_offset: (indices.len() * 4) as u64,
                    normal_offset: has_normals.then_some((normals.len() * 4) as u64),
                    vertex_count: p.positions.len() as u32,
                    triangles: tris,
                    color: p.base_color,
                    double_sided: p.double_sided,
                });
                vertices.extend_from_slice(&p.positions);
                indices.extend_from_slice(&p.indices[..tris as usize * 3]);
                if has_normals {
                    normals.extend(p.normals.iter().map(|&n| crate::gpu::pack_normal(n)));
                }
            }
            per_mesh.push(geos);
        }
        let input = vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR;
        let vbuf = Buffer::device_local_from_slice(gpu, "vertices", &vertices, input)?;
        let ibuf = Buffer::device_local_from_slice(
            gpu,
            "indices",
            &indices,
            input | vk::BufferUsageFlags::INDEX_BUFFER,
        )?;
        // A scene without normals has no normal buffer (Vulkan has no empty buffers).
        let nbuf = (!normals.is_empty())
            .then(|| Buffer::device_local_from_slice(gpu, "normals", &normals, vk::BufferUsageFlags::empty()))
            .transpose()?;
        let geometry_bytes = (vertices.len() * 12 + indices.len() * 4 + normals.len() * 4) as u64;
        drop(vertices);
        drop(indices);
        drop(normals);

        let mut table = Vec::new();
        let mut geometry_base = Vec::with_capacity(per_mesh.len());
        for geos in &per_mesh {
            if geos.is_empty() {
                geometry_base.push(None);
                continue;
            }
            geometry_base.push(Some(table.len() as u32));
            for g in geos {
                table.push(GeometryInfo {
                    vertices: vbuf.address + g.vertex_offset,
                    indices: ibuf.address + g.index_offset,
                    normals: match (&nbuf, g.normal_offset) {
                        (Some(n), Some(offset)) => n.address + offset,
                        _ => 0,
                    },
                    color: g.color,
                });
            }
        }
        let geometries =
            Buffer::device_local_from_slice(gpu, "geometry table", &table, vk::BufferUsageFlags::empty())?;
        let raster = RasterScene::new(
            gpu,
            per_mesh
                .iter()
                .zip(&geometry_base)
                .map(|(geos, base)| {
                    let base = base.unwrap_or(0);
                    geos.iter()
                        .enumerate()
                        .map(|(k, g)| RasterGeometry {
                            geometry: base + k as u32,
                            triangles: g.triangles,
                            first_index: g.index_offset / 4,
                            double_sided: g.double_sided,
                        })
                        .collect()
                })
                .collect(),
            ibuf.raw,
        )?;

        // 2. BLAS per mesh, in batches bounded by scratch memory, then compacted.
        let t0 = Instant::now();
        let mut blas: Vec<Option<AccelStruct>> = (0..per_mesh.len()).map(|_| None).collect();
        let mut blas_bytes = 0u64;
        let mut mesh = 0usize;
        const SCRATCH_BUDGET: u64 = 128 << 20;
        while mesh < per_mesh.len() {
            // Gather a batch.
            let mut batch: Vec<(
                usize,
                Vec<vk::AccelerationStructureGeometryKHR>,
                Vec<u32>,
                vk::AccelerationStructureBuildSizesInfoKHR,
            )> = Vec::new();
            let mut scratch_total = 0u64;
            while mesh < per_mesh.len()
                && (batch.is_empty() || scratch_total < SCRATCH_BUDGET)
                && batch.len() < 1024
            {
                let geos = &per_mesh[mesh];
                if !geos.is_empty() {
                    let geoms: Vec<_> = geos
                        .iter()
                        .map(|g| {
                            geometry_triangles(
                                vbuf.address + g.vertex_offset,
                                ibuf.address + g.index_offset,
                                g.vertex_count,
                            )
                        })
                        .collect();
                    let counts: Vec<u32> = geos.iter().map(|g| g.triangles).collect();
                    let info = blas_build_info(&geoms);
                    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
                    unsafe {
                        gpu.accel.get_acceleration_structure_build_sizes(
                            vk::AccelerationStructureBuildTypeKHR::DEVICE,
                            &info,
                            &counts,
                            &mut sizes,
                        )
                    };
                    scratch_total += align_up(sizes.build_scratch_size, gpu.scratch_alignment);
                    batch.push((mesh, geoms, counts, sizes));
                }
                mesh += 1;
            }
            if batch.is_empty() {
                continue;
            }
            let scratch = Scratch::new(gpu, scratch_total)?;
            let mut built = Vec::with_capacity(batch.len());
            for (m, _, _, sizes) in &batch {
                built.push(AccelStruct::new(
                    gpu,
                    &format!("BLAS mesh {m}"),
                    vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                    sizes.acceleration_structure_size,
                )?);
            }
            let query_pool = unsafe {
                gpu.device
                    .create_query_pool(
                        &vk::QueryPoolCreateInfo::default()
                            .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
                            .query_count(batch.len() as u32),
                        None,
                    )
                    .map_err(|e| CoreError::from_vk("vkCreateQueryPool", e))?
            };
            let record = gpu.run_commands(|cmd| unsafe {
                gpu.device
                    .cmd_reset_query_pool(cmd, query_pool, 0, batch.len() as u32);
                let mut offset = 0u64;
                for ((_, geoms, counts, sizes), dst) in batch.iter().zip(&built) {
                    let info = blas_build_info(geoms)
                        .dst_acceleration_structure(dst.raw)
                        .scratch_data(vk::DeviceOrHostAddressKHR {
                            device_address: scratch.base + offset,
                        });
                    offset += align_up(sizes.build_scratch_size, gpu.scratch_alignment);
                    let ranges: Vec<vk::AccelerationStructureBuildRangeInfoKHR> = counts
                        .iter()
                        .map(|&c| vk::AccelerationStructureBuildRangeInfoKHR {
                            primitive_count: c,
                            primitive_offset: 0,
                            first_vertex: 0,
                            transform_offset: 0,
                        })
                        .collect();
                    gpu.accel
                        .cmd_build_acceleration_structures(cmd, &[info], &[&ranges]);
                }
                let barrier = [vk::MemoryBarrier::default()
                    .src_access_mask(vk::AccessFlags::ACCELERATION_STRUCTURE_WRITE_KHR)
                    .dst_access_mask(vk::AccessFlags::ACCELERATION_STRUCTURE_READ_KHR)];
                gpu.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR,
                    vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR,
                    vk::DependencyFlags::empty(),
                    &barrier,
                    &[],
                    &[],
                );
                let handles: Vec<_> = built.iter().map(|a| a.raw).collect();
                gpu.accel.cmd_write_acceleration_structures_properties(
                    cmd,
                    &handles,
                    vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                    query_pool,
                    0,
                );
            });
            let compact_sizes = record.and_then(|_| {
                let mut sizes = vec![0u64; batch.len()];
                unsafe {
                    gpu.device
                        .get_query_pool_results(
                            query_pool,
                            0,
                            &mut sizes,
                            vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                        )
                        .map_err(|e| CoreError::from_vk("vkGetQueryPoolResults", e))?;
                }
                Ok(sizes)
            });
            unsafe { gpu.device.destroy_query_pool(query_pool, None) };
            let compact_sizes = compact_sizes?;
            drop(scratch);
            // Compaction copies.
            let mut compacted = Vec::with_capacity(built.len());
            for ((m, ..), size) in batch.iter().zip(&compact_sizes) {
                compacted.push(AccelStruct::new(
                    gpu,
                    &format!("BLAS mesh {m} (compacted)"),
                    vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                    (*size).max(256),
                )?);
            }
            gpu.run_commands(|cmd| unsafe {
                for (src, dst) in built.iter().zip(&compacted) {
                    gpu.accel.cmd_copy_acceleration_structure(
                        cmd,
                        &vk::CopyAccelerationStructureInfoKHR::default()
                            .src(src.raw)
                            .dst(dst.raw)
                            .mode(vk::CopyAccelerationStructureModeKHR::COMPACT),
                    );
                }
            })?;
            drop(built);
            for (((m, ..), a), size) in batch.iter().zip(compacted).zip(&compact_sizes) {
                blas_bytes += size;
                blas[*m] = Some(a);
            }
        }
        let blas_ms = t0.elapsed().as_secs_f64() * 1e3;

        let n = scene.instances.len().max(1) as u64;
        let instance_info = Buffer::new(
            gpu,
            "instance table",
            n * std::mem::size_of::<InstanceInfo>() as u64,
            MemoryLocation::CpuToGpu,
            vk::BufferUsageFlags::empty(),
        )?;
        let tlas_instances = Buffer::new(
            gpu,
            "TLAS instances",
            n * std::mem::size_of::<vk::AccelerationStructureInstanceKHR>() as u64,
            MemoryLocation::CpuToGpu,
            input,
        )?;
        let placeholder = AccelStruct::new(
            gpu,
            "TLAS (empty)",
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            256,
        )?;
        let mut s = SceneGpu {
            gpu: gpu.clone(),
            _vertices: vbuf,
            _indices: ibuf,
            _normals: nbuf,
            geometries,
            geometry_base,
            blas,
            instance_info,
            infos: Vec::new(),
            pending_infos: Mutex::new(None),
            highlight_version: 0,
            tlas_instances,
            tlas: placeholder,
            tlas_capacity: 0,
            tlas_scratch: None,
            tlas_generation: 0,
            raster,
            version: 0,
            synced_f: scene.f(),
            changes: Default::default(),
            mesh_bounds: scene.meshes.iter().map(|m| m.local_bounds()).collect(),
            sections: Sections::default(),
            section_changes: 0,
            section_log: Default::default(),
            section_sides: [0; 3],
            stats: BuildStats {
                blas_count: per_mesh.iter().filter(|g| !g.is_empty()).count(),
                geometry_count: table.len(),
                blas_ms,
                blas_bytes,
                geometry_bytes,
                ..Default::default()
            },
        };
        s.update_instances(scene, u32::MAX)?;
        Ok(s)
    }

    /// Number of BLASes built (one per unique mesh with triangles).
    pub fn blas_count(&self) -> usize {
        self.blas.iter().filter(|b| b.is_some()).count()
    }

    /// The TLAS build generation (unique in the process, never 0 once built).
    pub fn tlas_generation(&self) -> u64 {
        self.tlas_generation
    }

    /// How many times the instance tables were updated (see `version`).
    pub fn version(&self) -> u64 {
        self.version
    }

    /// The world boxes the scene's edits changed between F = `f0` and F = `f1` (both synced), or None when
    /// some change in between is not located (or is too old): then everything may have changed.
    pub fn changes_between(&self, f0: u32, f1: u32) -> Option<Vec<(Vec3, Vec3)>> {
        let mut out = Vec::new();
        let mut to = f1;
        for c in self.changes.iter().rev() {
            if to == f0 {
                break;
            }
            if c.to != to {
                return None;
            }
            out.extend(c.boxes.as_ref()?.iter().copied());
            to = c.from;
        }
        (to == f0).then_some(out)
    }

    /// Where the plane changes from count `c0` to `c1` made geometry appear or disappear (world boxes), or
    /// None when one of them is not located or too old.
    pub fn section_changes_between(&self, c0: u32, c1: u32) -> Option<Vec<(Vec3, Vec3)>> {
        let n = c1.wrapping_sub(c0) as usize;
        if n > self.section_log.len() {
            return None;
        }
        let mut out = Vec::new();
        for (i, (c, boxes)) in self
            .section_log
            .iter()
            .skip(self.section_log.len() - n)
            .enumerate()
        {
            if *c != c0.wrapping_add(i as u32 + 1) {
                return None;
            }
            out.extend(boxes.as_ref()?.iter().copied());
        }
        Some(out)
    }

    pub fn sections(&self) -> &Sections {
        &self.sections
    }

    /// Section plane changes so far (a plane change is a scene change: the renderer adds this to F).
    pub fn section_changes(&self) -> u32 {
        self.section_changes
    }

    /// Sets the section planes and rebuilds the TLAS for them (instances they cut away entirely leave it and the
    /// raster draws; the shaders clip the rays to the kept region). No-op when the planes are unchanged. Must not
    /// be called while a frame using the scene is in flight.
    pub fn set_sections(
        &mut self,
        scene: &Scene,
        sections: &Sections,
        selected: impl Highlight,
    ) -> Result<()> {
        sections.validate().map_err(CoreError::Invalid)?;
        if *sections == self.sections {
            return Ok(());
        }
        let b = scene.bounds_conservative();
        let boxes = if b.is_empty() {
            Some(Vec::new())
        } else {
            self.sections.changed_boxes(sections, (b.min, b.max))
        };
        self.sections = sections.clone();
        self.section_changes = self.section_changes.wrapping_add(1);
        if self.section_log.len() == SYNCED_CHANGES {
            self.section_log.pop_front();
        }
        self.section_log.push_back((self.section_changes, boxes));
        self.update_instances(scene, selected)
    }

    /// Rewrites the instance tables and rebuilds the TLAS from the scene's instances (after edits).
    /// `selected` are the instances to highlight: one id (u32::MAX for none) or a sorted slice of ids.
    pub fn update_instances(&mut self, scene: &Scene, selected: impl Highlight) -> Result<()> {
        self.version += 1;
        if scene.f() != self.synced_f {
            let boxes = scene
                .changes_since(self.synced_f)
                .map(|b| b.iter().map(|a| (a.min, a.max)).collect());
            if self.changes.len() == SYNCED_CHANGES {
                self.changes.pop_front();
            }
            self.changes.push_back(SyncedChange {
                from: self.synced_f,
                to: scene.f(),
                boxes,
            });
            self.synced_f = scene.f();
        }
        let gpu = self.gpu.clone();
        if scene.instances.len() > MAX_INSTANCES {
            return Err(CoreError::Invalid(format!(
                "at most {MAX_INSTANCES} instances are supported"
            )));
        }
        let n = scene.instances.len().max(1) as u64;
        let info_size = n * std::mem::size_of::<InstanceInfo>() as u64;
        if self.instance_info.size < info_size {
            self.instance_info = Buffer::new(
                &gpu,
                "instance table",
                info_size,
                MemoryLocation::CpuToGpu,
                vk::BufferUsageFlags::empty(),
            )?;
        }
        let inst_size = n * std::mem::size_of::<vk::AccelerationStructureInstanceKHR>() as u64;
        if self.tlas_instances.size < inst_size {
            self.tlas_instances = Buffer::new(
                &gpu,
                "TLAS instances",
                inst_size,
                MemoryLocation::CpuToGpu,
                vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR,
            )?;
        }
        let mut infos = Vec::with_capacity(scene.instances.len());
        let mut raw: Vec<u8> = Vec::with_capacity(scene.instances.len() * 64);
        let mut drawn = vec![false; scene.instances.len()];
        let mut sides = [0usize; 3];
        let mut count = 0u32;
        for (i, inst) in scene.instances.iter().enumerate() {
            let base = self.geometry_base.get(inst.mesh as usize).copied().flatten();
            let flags = if selected.contains(i as u32) {
                crate::gpu::INSTANCE_SELECTED
            } else {
                0
            };
            infos.push(InstanceInfo {
                geometry_base: base.unwrap_or(0),
                flags,
            });
            let (Some(_), Some(Some(blas))) = (base, self.blas.get(inst.mesh as usize)) else {
                continue;
            };
            if !inst.visible {
                continue;
            }
            let m = inst.transform;
            if !m.is_finite() {
                return Err(CoreError::Invalid(format!(
                    "instance {i} has a non-finite transform"
                )));
            }
            let bounds = self
                .mesh_bounds
                .get(inst.mesh as usize)
                .copied()
                .unwrap_or_default();
            let side = self.sections.side(&bounds, &m);
            sides[side as usize] += 1; // Kept, Crossing, Cut
            if side == Side::Cut {
                continue;
            }
            drawn[i] = true;
            let mut matrix = [0f32; 12];
            for r in 0..3 {
                for c in 0..4 {
                    matrix[r * 4 + c] = m.col(c)[r];
                }
            }
            let instance = vk::AccelerationStructureInstanceKHR {
                transform: vk::TransformMatrixKHR { matrix },
                instance_custom_index_and_mask: vk::Packed24_8::new(i as u32, 0xff),
                instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                    0,
                    vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
                ),
                acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                    device_handle: blas.address,
                },
            };
            // SAFETY: AccelerationStructureInstanceKHR is a plain 64-byte C struct.
            let bytes = unsafe {
                std::slice::from_raw_parts(
                    &instance as *const _ as *const u8,
                    std::mem::size_of::<vk::AccelerationStructureInstanceKHR>(),
                )
            };
            raw.extend_from_slice(bytes);
            count += 1;
        }
        if infos.is_empty() {
            infos.push(InstanceInfo::default());
        }
        self.instance_info.write(&infos)?;
        // The host write holds the highlight too: a queued one is superseded.
        *self.pending_infos.lock().unwrap_or_else(|p| p.into_inner()) = None;
        self.infos = infos;
        self.raster.update(&gpu, scene, &drawn)?;
        self.section_sides = sides;
        self.tlas_instances.write_bytes(0, &raw)?;

        let t0 = Instant::now();
        let geometry = [vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR {
                instances: vk::AccelerationStructureGeometryInstancesDataKHR::default()
                    .array_of_pointers(false)
                    .data(vk::DeviceOrHostAddressConstKHR {
                        device_address: self.tlas_instances.address,
                    }),
            })];
        let flags = vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE;
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(flags)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(&geometry);
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        unsafe {
            gpu.accel.get_acceleration_structure_build_sizes(
                vk::AccelerationStructureBuildTypeKHR::DEVICE,
                &info,
                &[count],
                &mut sizes,
            )
        };
        // A section-plane drag rebuilds the TLAS every step: its storage and scratch are reused while they fit
        // (no frame reading the TLAS is in flight: see the method's contract), and grow by half when not.
        let size = sizes.acceleration_structure_size.max(256);
        if size > self.tlas_capacity {
            let capacity = size + size / 2;
            self.tlas = AccelStruct::new(
                &gpu,
                "TLAS",
                vk::AccelerationStructureTypeKHR::TOP_LEVEL,
                capacity,
            )?;
            self.tlas_capacity = capacity;
        }
        let scratch_size = sizes.build_scratch_size.max(256);
        if self.tlas_scratch.as_ref().is_none_or(|(s, _)| *s < scratch_size) {
            let capacity = scratch_size + scratch_size / 2;
            self.tlas_scratch = Some((capacity, Scratch::new(&gpu, capacity)?));
        }
        let scratch = self.tlas_scratch.as_ref().map_or(0, |(_, s)| s.base);
        let info = info
            .dst_acceleration_structure(self.tlas.raw)
            .scratch_data(vk::DeviceOrHostAddressKHR {
                device_address: scratch,
            });
        let range = [vk::AccelerationStructureBuildRangeInfoKHR {
            primitive_count: count,
            primitive_offset: 0,
            first_vertex: 0,
            transform_offset: 0,
        }];
        gpu.run_commands(|cmd| unsafe {
            full_barrier(&gpu, cmd);
            gpu.accel
                .cmd_build_acceleration_structures(cmd, &[info], &[&range]);
            full_barrier(&gpu, cmd);
        })?;
        self.tlas_generation = TLAS_BUILDS.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        self.stats.tlas_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.stats.tlas_instances = count as usize;
        Ok(())
    }
}

impl SceneGpu {
    /// Highlights `selected` (a selection change): rewrites the instance table's flags, the only thing a
    /// highlight changes (composite.comp reads them; the TLAS, the raster draws and the AO do not). No TLAS is
    /// built and the host waits for nothing: the new table is queued for the next frame's commands
    /// (`record_uploads`), so it reaches the device after every frame submitted before it. Returns whether
    /// anything changed.
    pub fn set_highlight(&mut self, selected: impl Highlight) -> bool {
        let mut infos = self.infos.clone();
        for (i, info) in infos.iter_mut().enumerate() {
            info.flags = if selected.contains(i as u32) {
                crate::gpu::INSTANCE_SELECTED
            } else {
                0
            };
        }
        if bytemuck::cast_slice::<_, u8>(&infos) == bytemuck::cast_slice::<_, u8>(&self.infos) {
            return false;
        }
        self.infos = infos.clone();
        *self.pending_infos.lock().unwrap_or_else(|p| p.into_inner()) = Some(infos);
        self.highlight_version += 1;
        true
    }

    /// Bumped by every highlight change: a frame's output shows one version (`FrameKey::highlight`).
    pub fn highlight_version(&self) -> u64 {
        self.highlight_version
    }

    /// Records the queued instance-table write (`set_highlight`), if any, as the frame's first command:
    /// `vkCmdUpdateBuffer` carries the data in the command buffer itself, so nothing must outlive the frame, and
    /// the recorder orders it after the reads of earlier frames and before this frame's.
    pub(crate) fn record_uploads(&self, rec: &mut Recorder) {
        let Some(infos) = self
            .pending_infos
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take()
        else {
            return;
        };
        let bytes: &[u8] = bytemuck::cast_slice(&infos);
        let buffer = self.instance_info.raw;
        let uses = vec![Use::write(Resource::Instances, Stage::Transfer)];
        rec.commands("instance flags", None, uses, |d, cmd| {
            // vkCmdUpdateBuffer takes at most 65,536 bytes a call, a multiple of 4 (InstanceInfo is 8 bytes).
            for (k, chunk) in bytes.chunks(UPDATE_BUFFER_MAX).enumerate() {
                unsafe { d.cmd_update_buffer(cmd, buffer, (k * UPDATE_BUFFER_MAX) as u64, chunk) };
            }
        });
    }
}

/// The most bytes one `vkCmdUpdateBuffer` may write.
const UPDATE_BUFFER_MAX: usize = 65_536;

/// The instances `SceneGpu::update_instances` highlights.
pub trait Highlight {
    fn contains(&self, instance: u32) -> bool;
}

/// One instance (u32::MAX: none).
impl Highlight for u32 {
    fn contains(&self, instance: u32) -> bool {
        *self == instance
    }
}

/// A sorted list of instances (a model tree node's subtree).
impl Highlight for &[u32] {
    fn contains(&self, instance: u32) -> bool {
        self.binary_search(&instance).is_ok()
    }
}
