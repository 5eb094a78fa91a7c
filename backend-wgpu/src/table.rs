//! Read-only tables: records that kernels read at scattered indices (the scene's records,
//! the photons in bucket order, the bucket starts), held as texels of a 2D `rgba32uint` or
//! `r32uint` texture bound as a read-only storage texture, rather than in a storage buffer.
//!
//! Why: a storage-buffer read at an index that differs between invocations may be split into
//! one bounds-checked load per invocation and per 32-bit word (lavapipe, which runs the WGSL
//! on the CPU as CI does, splits them so), while a texel load is one vectorised gather; and a
//! storage-texture load skips the mip-level arithmetic that lavapipe spends on every sampled
//! texel fetch. `cargo run --release -p backend-wgpu --example table_reads` reads 16-byte
//! records at random from each, and on lavapipe the table is the fastest of the three by a
//! wide margin (docs/performance.md). GPUs load texels through the same caches as buffers.
//!
//! The records keep their `#[repr(C)]` layout: a record of `n` 16-byte texels is texels
//! `n*i .. n*i + n`, row-major in rows of [`ROW_TEXELS`] (`table_texel` in tables.wgsl), and
//! floats travel as their bits. Baseline WebGPU binds four storage textures per stage, so the
//! scene's records share one table (scene.wgsl).

use crate::context::GpuContext;
use ppm_core::passes::BackendError;

/// Texels per row (`TABLE_ROW_SHIFT` in tables.wgsl is its log2).
pub const ROW_TEXELS: u32 = 4096;

/// What one texel holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Texel {
    /// Four 32-bit words (`rgba32uint`).
    Words4,
    /// One 32-bit word (`r32uint`).
    Word,
}

impl Texel {
    /// Bytes per texel.
    pub fn bytes(self) -> u32 {
        match self {
            Texel::Words4 => 16,
            Texel::Word => 4,
        }
    }

    fn format(self) -> wgpu::TextureFormat {
        match self {
            Texel::Words4 => wgpu::TextureFormat::Rgba32Uint,
            Texel::Word => wgpu::TextureFormat::R32Uint,
        }
    }
}

/// A texture holding up to `capacity` texels of one kind (clones share the texture).
#[derive(Clone)]
pub struct Table {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    texel: Texel,
    capacity: u32,
}

impl Table {
    /// An empty table for at least `texels` texels (a whole number of rows, at least one),
    /// refused with the limit named when the adapter's textures cannot hold it.
    pub fn new(
        ctx: &GpuContext,
        label: &str,
        texel: Texel,
        texels: u32,
    ) -> Result<Self, BackendError> {
        let rows = texels.div_ceil(ROW_TEXELS).max(1);
        let max_rows = ctx.limits().max_texture_dimension_2d;
        if rows > max_rows {
            return Err(BackendError::Limit(format!(
                "table '{label}' needs {texels} texels ({rows} rows of {ROW_TEXELS}); this adapter's textures hold at most {max_rows} rows (max_texture_dimension_2d)"
            )));
        }
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: ROW_TEXELS,
                height: rows,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: texel.format(),
            // COPY_SRC: tests read tables back.
            usage: wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        Ok(Self {
            texture,
            view,
            texel,
            capacity: rows * ROW_TEXELS,
        })
    }

    /// A table holding `bytes` (a whole number of texels).
    pub fn with_data(
        ctx: &GpuContext,
        label: &str,
        texel: Texel,
        bytes: &[u8],
    ) -> Result<Self, BackendError> {
        let texels = (bytes.len() as u32).div_ceil(texel.bytes());
        let table = Self::new(ctx, label, texel, texels)?;
        let mut padded = bytes.to_vec();
        padded.resize((table.capacity * texel.bytes()) as usize, 0);
        ctx.queue.write_texture(
            table.texture.as_image_copy(),
            &padded,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(ROW_TEXELS * texel.bytes()),
                rows_per_image: None,
            },
            table.texture.size(),
        );
        Ok(table)
    }

    /// Writes `bytes` (whole texels) into the table from texel `first` on, a queue write
    /// per row it spans.
    pub fn write(&self, ctx: &GpuContext, first: u32, bytes: &[u8]) {
        let texel_bytes = self.texel.bytes() as usize;
        let (mut texel, mut rest) = (first, bytes);
        while rest.len() >= texel_bytes {
            let (row, x) = (texel / ROW_TEXELS, texel % ROW_TEXELS);
            let n = (ROW_TEXELS - x).min((rest.len() / texel_bytes) as u32);
            let (now, later) = rest.split_at(n as usize * texel_bytes);
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &self.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x, y: row, z: 0 },
                    aspect: wgpu::TextureAspect::All,
                },
                now,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(now.len() as u32),
                    rows_per_image: None,
                },
                wgpu::Extent3d {
                    width: n,
                    height: 1,
                    depth_or_array_layers: 1,
                },
            );
            (texel, rest) = (texel + n, later);
        }
    }

    /// Records the copy of the first `texels` texels of `buffer` into the table.
    pub fn record_copy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        buffer: &wgpu::Buffer,
        texels: u32,
    ) {
        let texels = texels.min(self.capacity);
        let row_bytes = u64::from(ROW_TEXELS * self.texel.bytes());
        let full_rows = texels / ROW_TEXELS;
        let rest = texels % ROW_TEXELS;
        let copy = |encoder: &mut wgpu::CommandEncoder, row: u32, width: u32, rows: u32| {
            encoder.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: u64::from(row) * row_bytes,
                        bytes_per_row: Some(row_bytes as u32),
                        rows_per_image: None,
                    },
                },
                wgpu::TexelCopyTextureInfo {
                    texture: &self.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: 0, y: row, z: 0 },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::Extent3d {
                    width,
                    height: rows,
                    depth_or_array_layers: 1,
                },
            );
        };
        if full_rows > 0 {
            copy(encoder, 0, ROW_TEXELS, full_rows);
        }
        if rest > 0 {
            copy(encoder, full_rows, rest, 1);
        }
    }

    /// The first `texels` texels' words, read back: for tests and debugging, never a pass.
    pub fn contents(&self, ctx: &GpuContext, texels: u32) -> Vec<u32> {
        use crate::buffers::{read_back, storage_zeroed};
        let words = self.texel.bytes() / 4;
        let out = storage_zeroed(
            ctx,
            "table contents",
            u64::from(self.capacity * self.texel.bytes()),
        )
        .expect("small");
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            self.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &out,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(ROW_TEXELS * self.texel.bytes()),
                    rows_per_image: None,
                },
            },
            self.texture.size(),
        );
        ctx.queue.submit([encoder.finish()]);
        read_back::<u32>(ctx, &out, (texels * words) as usize).expect("read back")
    }

    /// The view kernels bind.
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }
}
