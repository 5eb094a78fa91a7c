//! The GPU buffers, named as the WGSL bindings name them, and their creation and read-back.

use crate::context::GpuContext;
use crate::layout::SceneIndex;
use crate::table::{Table, Texel};
use bytemuck::Pod;
use bytemuck::Zeroable;
use ppm_core::compile::CompiledScene;
use ppm_core::layout::{
    BvhNode, GpuBounds, GpuLight, GpuMaterial, GpuTexture, GpuTriangle, GpuTriangleUv,
};
use ppm_core::passes::BackendError;
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// Usage of every storage buffer: bindable, and copyable both ways for resets and read-back.
const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// A storage buffer holding `data`; an empty slice still gets one zeroed element (and at
/// least 16 bytes), since a binding must hold a whole element.
pub fn storage_init<T: Pod>(ctx: &GpuContext, label: &str, data: &[T]) -> wgpu::Buffer {
    let mut bytes = bytemuck::cast_slice::<T, u8>(data).to_vec();
    bytes.resize(bytes.len().max(16).max(size_of::<T>()), 0);
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &bytes,
            usage: STORAGE,
        })
}

/// A zeroed storage buffer of `bytes` bytes, refused with the limit named if it cannot be bound.
pub fn storage_zeroed(
    ctx: &GpuContext,
    label: &str,
    bytes: u64,
) -> Result<wgpu::Buffer, BackendError> {
    let limit = ctx
        .limits()
        .max_storage_buffer_binding_size
        .min(ctx.limits().max_buffer_size);
    if bytes > limit {
        return Err(BackendError::Limit(format!(
            "buffer '{label}' needs {bytes} bytes; this adapter binds at most {limit} (max_storage_buffer_binding_size)"
        )));
    }
    Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16).next_multiple_of(4),
        usage: STORAGE,
        mapped_at_creation: false,
    }))
}

/// A uniform buffer holding `value`.
pub fn uniform<T: Pod>(ctx: &GpuContext, label: &str, value: &T) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(value),
            usage: wgpu::BufferUsages::UNIFORM,
        })
}

/// Copies `len` elements from the start of `buffer` back to the host.
pub fn read_back<T: Pod>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    len: usize,
) -> Result<Vec<T>, BackendError> {
    let bytes = (len * size_of::<T>()) as u64;
    if bytes == 0 {
        return Ok(Vec::new());
    }
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read-back"),
        size: bytes.next_multiple_of(4),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes.next_multiple_of(4));
    ctx.queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    ctx.wait()?;
    rx.recv()
        .map_err(|_| BackendError::Device("read-back: the map callback never ran".into()))?
        .map_err(|e| BackendError::Device(format!("read-back: {e}")))?;
    let view = staging
        .get_mapped_range(..)
        .map_err(|e| BackendError::Device(format!("read-back: {e}")))?;
    let out = bytemuck::cast_slice::<u8, T>(&view[..bytes as usize]).to_vec();
    drop(view);
    staging.unmap();
    Ok(out)
}

/// The scene, uploaded once per `load_scene`.
pub struct SceneBuffers {
    /// Camera uniform, written in place when only the camera changes.
    pub camera: wgpu::Buffer,
    /// Every scene record in one table (scene.wgsl): materials (eight texels each), triangles
    /// in BVH leaf order (four), flattened BVH nodes (two), emitting triangles (four), the
    /// boxes of moving objects (two; none when nothing moves), and, in a textured scene, the
    /// triangles' texture coordinates (two) and the texture headers (two).
    pub table: Table,
    /// Where each kind starts in `table`, and how many lights and boxes it holds (uniform
    /// [`SceneIndex`]).
    pub index: wgpu::Buffer,
    /// Every texture's texels (`scene_texels` in textures.wgsl; one zeroed element when the
    /// scene has no texture). Moves keep it: they change geometry, never textures.
    pub texels: wgpu::Buffer,
    /// What `texels` holds, to know a later pose's as the same.
    texel_data: Arc<Vec<[u32; 2]>>,
    /// Camera as uploaded (resolution decides the hit-point count).
    pub camera_value: ppm_core::layout::GpuCamera,
    /// Emitting triangles.
    pub light_count: usize,
    /// The scene's triangles (none for a scene without: the table then holds one degenerate
    /// triangle, which nothing reads as the scene's).
    pub triangle_count: u32,
    /// The pose the table holds ([`CompiledScene::pose`]).
    pose: u64,
    /// Where each kind starts in the table, as `index` holds it.
    layout: SceneIndex,
    /// The movers' boxes the table holds, to write them only when they change.
    movers: Vec<GpuBounds>,
}

/// Bytes of one scene-table texel: every record is a whole number of them.
const TEXEL_BYTES: usize = 16;
const _: () = assert!(
    size_of::<GpuMaterial>().is_multiple_of(TEXEL_BYTES)
        && size_of::<GpuTriangle>().is_multiple_of(TEXEL_BYTES)
        && size_of::<BvhNode>().is_multiple_of(TEXEL_BYTES)
        && size_of::<GpuLight>().is_multiple_of(TEXEL_BYTES)
        && size_of::<GpuBounds>().is_multiple_of(TEXEL_BYTES)
        && size_of::<GpuTexture>().is_multiple_of(TEXEL_BYTES)
        && size_of::<GpuTriangleUv>().is_multiple_of(TEXEL_BYTES)
);

/// Deepest BVH the shaders' fixed traversal stack (`STACK_SIZE` in bvh.wgsl) can walk.
const MAX_BVH_DEPTH: usize = 62;

impl SceneBuffers {
    /// Uploads `scene`, its texels too unless `earlier` (an earlier pose's buffers) holds
    /// the same; refuses a BVH too deep for the traversal stack or texels beyond a binding.
    pub fn new(
        ctx: &GpuContext,
        scene: &CompiledScene,
        earlier: Option<&SceneBuffers>,
    ) -> Result<Self, BackendError> {
        if scene.bvh_depth > MAX_BVH_DEPTH {
            return Err(BackendError::Limit(format!(
                "BVH depth {} exceeds the shaders' traversal stack ({MAX_BVH_DEPTH})",
                scene.bvh_depth
            )));
        }
        // No triangle: one leaf holding one degenerate triangle, which no ray hits (bvh.wgsl).
        let empty_leaf = [BvhNode {
            count: 1,
            ..Default::default()
        }];
        let degenerate = [GpuTriangle::zeroed()];
        let (nodes, triangles) = if scene.nodes.is_empty() {
            (&empty_leaf[..], &degenerate[..])
        } else {
            (&scene.nodes[..], &scene.triangles[..])
        };
        let mut bytes = Vec::new();
        let mut append = |records: &[u8]| {
            let start = (bytes.len() / TEXEL_BYTES) as u32;
            bytes.extend_from_slice(records);
            start
        };
        append(bytemuck::cast_slice(&scene.materials));
        let index = SceneIndex {
            triangles: append(bytemuck::cast_slice(triangles)),
            nodes: append(bytemuck::cast_slice(nodes)),
            lights: append(bytemuck::cast_slice(&scene.lights)),
            movers: append(bytemuck::cast_slice(&scene.movers)),
            light_count: scene.lights.len() as u32,
            mover_count: scene.movers.len() as u32,
            uvs: append(bytemuck::cast_slice(&scene.textures.uvs)),
            textures: append(bytemuck::cast_slice(&scene.textures.headers)),
        };
        let same = |e: &&SceneBuffers| {
            Arc::ptr_eq(&e.texel_data, &scene.textures.texels)
                || e.texel_data == scene.textures.texels
        };
        let texels = match earlier.filter(same) {
            Some(kept) => kept.texels.clone(),
            None => {
                let all = &scene.textures.texels[..];
                let bytes = std::mem::size_of_val(all) as u64;
                let limit = ctx.limits().max_storage_buffer_binding_size;
                if bytes > limit {
                    return Err(BackendError::Limit(format!(
                        "the scene's textures hold {bytes} bytes of texels; this adapter binds at most {limit} (max_storage_buffer_binding_size)"
                    )));
                }
                storage_init(ctx, "texels", all)
            }
        };
        let camera = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("camera"),
                contents: bytemuck::bytes_of(&scene.camera),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
        Ok(Self {
            camera,
            table: Table::with_data(ctx, "scene", Texel::Words4, &bytes)?,
            index: uniform(ctx, "scene index", &index),
            texels,
            texel_data: scene.textures.texels.clone(),
            camera_value: scene.camera,
            light_count: scene.lights.len(),
            triangle_count: scene.triangles.len() as u32,
            pose: scene.pose,
            layout: index,
            movers: scene.movers.clone(),
        })
    }

    /// The pose the table holds ([`CompiledScene::pose`]).
    pub fn pose(&self) -> u64 {
        self.pose
    }

    /// Writes `scene` over these buffers in place, if they hold the pose it was refitted
    /// from (which shares its materials and lights) or the same pose ([`CompiledScene::pose`]
    /// names them), with the same number of movers' boxes: only what the refit wrote, the
    /// boxes and the camera travel, each where it changed, so a drag step uploads what moved
    /// and a camera step its 64 bytes, not the scene. Returns whether it did; if not,
    /// nothing was written.
    pub fn update(&mut self, ctx: &GpuContext, scene: &CompiledScene) -> bool {
        let writes = scene.refit_from.as_ref().filter(|w| w.pose == self.pose);
        let layout = &self.layout;
        let unchanged = scene.lights.len() == self.light_count
            && scene.movers.len() as u32 == layout.mover_count
            && scene.triangles.len() as u32 == self.triangle_count
            && !scene.nodes.is_empty();
        if !unchanged || scene.pose != self.pose && writes.is_none() {
            return false;
        }
        if let Some(writes) = writes {
            let triangle_texels = (size_of::<GpuTriangle>() / TEXEL_BYTES) as u32;
            for run in &writes.triangles {
                let records = &scene.triangles[run.start as usize..run.end as usize];
                let first = layout.triangles + run.start * triangle_texels;
                self.table.write(ctx, first, bytemuck::cast_slice(records));
            }
            let node_texels = (size_of::<BvhNode>() / TEXEL_BYTES) as u32;
            for run in &writes.nodes {
                let records = &scene.nodes[run.start as usize..run.end as usize];
                let first = layout.nodes + run.start * node_texels;
                self.table.write(ctx, first, bytemuck::cast_slice(records));
            }
        }
        if scene.movers != self.movers {
            self.table
                .write(ctx, layout.movers, bytemuck::cast_slice(&scene.movers));
            self.movers.clone_from(&scene.movers);
        }
        if scene.camera != self.camera_value {
            ctx.queue
                .write_buffer(&self.camera, 0, bytemuck::bytes_of(&scene.camera));
            self.camera_value = scene.camera;
        }
        self.pose = scene.pose;
        true
    }
}
