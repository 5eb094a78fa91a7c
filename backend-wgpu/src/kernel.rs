//! One compute pipeline with an explicit bind-group layout, and its dispatch.
//!
//! Layouts are explicit, not derived from the shader, so that several entry points of one
//! shader file share one binding list even when an entry point leaves some bindings unused.

use crate::timestamps::Encoder;

/// What a binding slot holds.
#[derive(Clone, Copy, Debug)]
pub enum Slot {
    /// A uniform buffer.
    Uniform,
    /// A storage buffer the shader only reads.
    Read,
    /// A storage buffer the shader writes.
    ReadWrite,
    /// A read-only table of four-word texels (`texture_storage_2d<rgba32uint, read>`, see
    /// [`crate::table`]).
    Table,
    /// A read-only table of one-word texels (`texture_storage_2d<r32uint, read>`).
    WordTable,
    /// A binding of the shared list that this entry point does not read: left out of its
    /// layout and bind group, so that each entry point stays within the per-stage binding
    /// limits even when the list as a whole does not.
    Unused,
}

/// Something a bind group can hold at a slot: a buffer or a table.
pub trait Bindable {
    /// The resource as a binding.
    fn resource(&self) -> wgpu::BindingResource<'_>;
}

impl Bindable for wgpu::Buffer {
    fn resource(&self) -> wgpu::BindingResource<'_> {
        self.as_entire_binding()
    }
}

impl Bindable for crate::table::Table {
    fn resource(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::TextureView(self.view())
    }
}

/// Workgroup size of every pass shader but the scan (`WORKGROUP_SIZE` in layout.wgsl).
pub const WORKGROUP: u32 = 64;

/// A compute pipeline and the layout of its bind group 0.
pub struct Kernel {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    /// Which bindings the layout holds (not [`Slot::Unused`]).
    used: Vec<bool>,
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
            .filter_map(|(i, slot)| {
                Some(wgpu::BindGroupLayoutEntry {
                    binding: i as u32,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: binding_type(*slot)?,
                    count: None,
                })
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
            used: slots.iter().map(|s| !matches!(s, Slot::Unused)).collect(),
            label: entry,
            workgroup,
        }
    }

    /// A bind group with `resources[i]` at binding `i` (those at unused slots left out).
    pub fn bind(&self, device: &wgpu::Device, resources: &[&dyn Bindable]) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = resources
            .iter()
            .enumerate()
            .filter(|(i, _)| self.used[*i])
            .map(|(i, r)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: r.resource(),
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// Records a dispatch covering `items` work items (one invocation each), in a compute pass
    /// of its own, timed where the device has timestamps; counts past 65,535 workgroups spill
    /// into y, which the shaders fold back with `item_index`.
    pub fn dispatch(&self, encoder: &mut Encoder<'_>, group: &wgpu::BindGroup, items: u32) {
        let groups = items.div_ceil(self.workgroup).max(1);
        let x = groups.min(65_535);
        let y = groups.div_ceil(x);
        let mut pass = encoder.compute_pass(self.label);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// The layout entry type of a slot (none for an unused one).
fn binding_type(slot: Slot) -> Option<wgpu::BindingType> {
    let buffer = |ty| wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    let table = |format| wgpu::BindingType::StorageTexture {
        access: wgpu::StorageTextureAccess::ReadOnly,
        format,
        view_dimension: wgpu::TextureViewDimension::D2,
    };
    Some(match slot {
        Slot::Uniform => buffer(wgpu::BufferBindingType::Uniform),
        Slot::Read => buffer(wgpu::BufferBindingType::Storage { read_only: true }),
        Slot::ReadWrite => buffer(wgpu::BufferBindingType::Storage { read_only: false }),
        Slot::Table => table(wgpu::TextureFormat::Rgba32Uint),
        Slot::WordTable => table(wgpu::TextureFormat::R32Uint),
        Slot::Unused => return None,
    })
}

/// Compiles one assembled shader.
pub fn shader_module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
