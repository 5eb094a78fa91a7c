//! One compute pipeline with an explicit bind-group layout, and its dispatch.
//!
//! Layouts are explicit, not derived from the shader, so that several entry points of one
//! shader file share one binding list even when an entry point leaves some bindings unused.

/// What a binding slot holds.
#[derive(Clone, Copy, Debug)]
pub enum Slot {
    /// A uniform buffer.
    Uniform,
    /// A storage buffer the shader only reads.
    Read,
    /// A storage buffer the shader writes.
    ReadWrite,
}

/// Workgroup size of every pass shader but the scan (`WORKGROUP_SIZE` in layout.wgsl).
pub const WORKGROUP: u32 = 64;

/// A compute pipeline and the layout of its bind group 0.
pub struct Kernel {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    label: &'static str,
    workgroup: u32,
}

impl Kernel {
    /// Builds the pipeline for `entry` of `module`, with bindings `0..slots.len()`.
    pub fn new(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        entry: &'static str,
        slots: &[Slot],
        workgroup: u32,
    ) -> Self {
        Self::specialised(device, module, entry, slots, workgroup, &[])
    }

    /// As [`Kernel::new`], with the shader's `override` constants set: code a specialisation
    /// does not need is compiled out rather than branched over.
    pub fn specialised(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        entry: &'static str,
        slots: &[Slot],
        workgroup: u32,
        constants: &[(&str, f64)],
    ) -> Self {
        let entries: Vec<wgpu::BindGroupLayoutEntry> = slots
            .iter()
            .enumerate()
            .map(|(i, slot)| wgpu::BindGroupLayoutEntry {
                binding: i as u32,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: match slot {
                        Slot::Uniform => wgpu::BufferBindingType::Uniform,
                        Slot::Read => wgpu::BufferBindingType::Storage { read_only: true },
                        Slot::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            })
            .collect();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(entry),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(entry),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pipeline_layout),
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            cache: None,
        });
        Self {
            pipeline,
            layout,
            label: entry,
            workgroup,
        }
    }

    /// A bind group with `buffers[i]` at binding `i`.
    pub fn bind(&self, device: &wgpu::Device, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// Records a dispatch covering `items` work items (one invocation each); counts past
    /// 65,535 workgroups spill into y, which the shaders fold back with `item_index`.
    pub fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        items: u32,
    ) {
        let groups = items.div_ceil(self.workgroup).max(1);
        let x = groups.min(65_535);
        let y = groups.div_ceil(x);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.label),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// Compiles one assembled shader.
pub fn shader_module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
