//! Draws the panes' images into the window (or a screenshot texture) on the device: each pane
//! reads its image from a storage buffer that the wgpu backend resolves into directly, or that
//! the CPU backend's image is uploaded to.

use bytemuck::{Pod, Zeroable};
use ppm_core::image::Image;

/// One pane's uniform: `Pane` in display.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PaneUniform {
    /// Top-left window pixel of the pane.
    pub origin: [u32; 2],
    /// Image width and height.
    pub size: [u32; 2],
    /// Multiplies the linear image before encoding.
    pub exposure: f32,
    /// 1: the heat map of the last move's resets over the image.
    pub heat: u32,
    /// 1: the shader encodes sRGB (the target is UNORM).
    pub encode: u32,
    /// Padding.
    pub _pad: u32,
}

/// The WGSL source of the display pass.
pub const SHADER: &str = include_str!("display.wgsl");

/// A pane's buffers on the device.
pub struct PaneBuffers {
    /// `width * height` RGB f32 triples: the resolve pass's output format.
    pub image: wgpu::Buffer,
    /// `width * height` f32: the share of each pixel's slots the last move reset.
    pub reset: wgpu::Buffer,
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// The display pipeline and every pane's buffers.
pub struct Display {
    pipeline: wgpu::RenderPipeline,
    /// Per pane.
    pub panes: Vec<PaneBuffers>,
    width: u32,
    height: u32,
    encode: bool,
}

impl Display {
    /// Buffers for `panes` images of `width` x `height`, drawn into targets of `format`.
    pub fn new(
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        panes: usize,
        width: u32,
        height: u32,
    ) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("display"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let pixels = u64::from(width) * u64::from(height);
        let storage = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let panes = (0..panes)
            .map(|_| {
                let image = storage("pane image", pixels * 12);
                let reset = storage("pane resets", pixels * 4);
                let uniform = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("pane"),
                    size: std::mem::size_of::<PaneUniform>() as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("pane"),
                    layout: &pipeline.get_bind_group_layout(0),
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: uniform.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: image.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: reset.as_entire_binding(),
                        },
                    ],
                });
                PaneBuffers {
                    image,
                    reset,
                    uniform,
                    bind_group,
                }
            })
            .collect();
        Self {
            pipeline,
            panes,
            width,
            height,
            encode: !format.is_srgb(),
        }
    }

    /// Where pane `i` sits in the window: side by side from the top-left corner.
    pub fn origin(&self, i: usize) -> (u32, u32) {
        (i as u32 * self.width, 0)
    }

    /// Image width and height of every pane.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Uploads a CPU image into pane `i`.
    pub fn upload(&self, queue: &wgpu::Queue, i: usize, image: &Image) {
        queue.write_buffer(&self.panes[i].image, 0, bytemuck::cast_slice(&image.pixels));
    }

    /// Uploads pane `i`'s heat map.
    pub fn upload_resets(&self, queue: &wgpu::Queue, i: usize, reset: &[f32]) {
        queue.write_buffer(&self.panes[i].reset, 0, bytemuck::cast_slice(reset));
    }

    /// Records the panes' draw into `pass`, whose target is `target_size` pixels (panes that
    /// do not fit are clipped).
    pub fn draw(
        &self,
        queue: &wgpu::Queue,
        pass: &mut wgpu::RenderPass<'_>,
        target_size: (u32, u32),
        exposure: f32,
        heat: bool,
    ) {
        pass.set_pipeline(&self.pipeline);
        for (i, pane) in self.panes.iter().enumerate() {
            let (x, y) = self.origin(i);
            if x >= target_size.0 || y >= target_size.1 {
                continue;
            }
            let uniform = PaneUniform {
                origin: [x, y],
                size: [self.width, self.height],
                exposure,
                heat: u32::from(heat),
                encode: u32::from(self.encode),
                _pad: 0,
            };
            queue.write_buffer(&pane.uniform, 0, bytemuck::bytes_of(&uniform));
            let w = self.width.min(target_size.0 - x);
            let h = self.height.min(target_size.1 - y);
            pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
            pass.set_bind_group(0, &pane.bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `PaneUniform` crosses to the GPU: its size and field offsets match display.wgsl's
    /// `Pane`, as naga reads it.
    #[test]
    fn pane_uniform_matches_the_wgsl_declaration() {
        let module = naga::front::wgsl::parse_str(SHADER).expect("display.wgsl parses");
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Pane"))
            .expect("display.wgsl declares Pane");
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("Pane is a struct");
        };
        assert_eq!(*span as usize, std::mem::size_of::<PaneUniform>());
        assert_eq!(
            layouter[handle].size as usize,
            std::mem::size_of::<PaneUniform>()
        );
        let offsets: Vec<(String, u32)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
            .collect();
        let expected = [
            ("origin", std::mem::offset_of!(PaneUniform, origin)),
            ("size", std::mem::offset_of!(PaneUniform, size)),
            ("exposure", std::mem::offset_of!(PaneUniform, exposure)),
            ("heat", std::mem::offset_of!(PaneUniform, heat)),
            ("encode", std::mem::offset_of!(PaneUniform, encode)),
            ("_pad", std::mem::offset_of!(PaneUniform, _pad)),
        ];
        let expected: Vec<(String, u32)> = expected
            .iter()
            .map(|(n, o)| (n.to_string(), *o as u32))
            .collect();
        assert_eq!(offsets, expected);
    }
}
