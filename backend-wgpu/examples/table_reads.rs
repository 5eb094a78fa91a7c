//! Why read-only records live in tables (`src/table.rs`): the same kernel reads 16-byte
//! records at scattered indices from a storage buffer, from a sampled `rgba32uint` texture
//! and from the same texture bound as a read-only storage texture (a table), over a working
//! set that fits the caches (64 KiB) and one that does not (16 MiB), and prints the time of
//! each, best of three, side by side.
//!
//! `cargo run --release -p backend-wgpu --example table_reads`

use backend_wgpu::GpuContext;
use std::time::Instant;
use wgpu::util::DeviceExt;

const KERNELS: &str = r#"
@group(0) @binding(0) var<storage, read> records: array<vec4<u32>>;
@group(0) @binding(1) var table: texture_2d<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<vec4<u32>>;
@group(0) @binding(3) var<uniform> mask: vec4<u32>;
@group(0) @binding(4) var image: texture_storage_2d<rgba32uint, read>;

fn next(x: u32) -> u32 {
    let v = x * 747796405u + 2891336453u;
    let w = ((v >> ((v >> 28u) + 4u)) ^ v) * 277803737u;
    return (w >> 22u) ^ w;
}

@compute @workgroup_size(64)
fn from_buffer(@builtin(global_invocation_id) id: vec3<u32>) {
    var i = id.x;
    var sum = vec4<u32>(0u);
    for (var step = 0u; step < 256u; step++) {
        i = next(i);
        sum += records[i & mask.x];
    }
    sums[id.x] = sum;
}

@compute @workgroup_size(64)
fn from_texture(@builtin(global_invocation_id) id: vec3<u32>) {
    var i = id.x;
    var sum = vec4<u32>(0u);
    for (var step = 0u; step < 256u; step++) {
        i = next(i);
        let r = i & mask.x;
        sum += textureLoad(table, vec2<u32>(r & 4095u, r >> 12u), 0);
    }
    sums[id.x] = sum;
}

@compute @workgroup_size(64)
fn from_table(@builtin(global_invocation_id) id: vec3<u32>) {
    var i = id.x;
    var sum = vec4<u32>(0u);
    for (var step = 0u; step < 256u; step++) {
        i = next(i);
        let r = i & mask.x;
        sum += textureLoad(image, vec2<u32>(r & 4095u, r >> 12u));
    }
    sums[id.x] = sum;
}
"#;

/// Invocations per dispatch (each makes 256 reads).
const INVOCATIONS: u32 = 65_536;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ctx = GpuContext::new()?;
    let device = &ctx.device;
    println!("adapter: {} ({:?})", ctx.adapter.name, ctx.adapter.backend);
    let records = 1u32 << 20;
    let words: Vec<u32> = (0..records * 4).collect();
    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("records"),
        contents: bytemuck::cast_slice(&words),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let texture = device.create_texture_with_data(
        &ctx.queue,
        &wgpu::TextureDescriptor {
            label: Some("records"),
            size: wgpu::Extent3d {
                width: 4096,
                height: records / 4096,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Uint,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&words),
    );
    let view = texture.create_view(&Default::default());
    let sums = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sums"),
        size: u64::from(INVOCATIONS) * 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("table reads"),
        source: wgpu::ShaderSource::Wgsl(KERNELS.into()),
    });
    println!("working set   storage buffer   sampled texture   table");
    for (label, mask) in [("64 KiB", 4095u32), ("16 MiB", records - 1)] {
        let mask = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("mask"),
            contents: bytemuck::cast_slice(&[mask, 0, 0, 0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let time = |entry: &str, source: wgpu::BindingResource| -> f64 {
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            });
            let source_binding = match entry {
                "from_buffer" => 0,
                "from_texture" => 1,
                _ => 4,
            };
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(entry),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: source_binding,
                        resource: source,
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: sums.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: mask.as_entire_binding(),
                    },
                ],
            });
            (0..3)
                .map(|_| {
                    let start = Instant::now();
                    let mut encoder = device.create_command_encoder(&Default::default());
                    {
                        let mut pass = encoder.begin_compute_pass(&Default::default());
                        pass.set_pipeline(&pipeline);
                        pass.set_bind_group(0, &group, &[]);
                        pass.dispatch_workgroups(INVOCATIONS / 64, 1, 1);
                    }
                    ctx.queue.submit([encoder.finish()]);
                    ctx.wait().expect("device alive");
                    start.elapsed().as_secs_f64() * 1e3
                })
                .fold(f64::INFINITY, f64::min)
        };
        let from_buffer = time("from_buffer", buffer.as_entire_binding());
        let from_texture = time("from_texture", wgpu::BindingResource::TextureView(&view));
        let from_table = time("from_table", wgpu::BindingResource::TextureView(&view));
        println!(
            "{label:>11}   {from_buffer:>11.1} ms   {from_texture:>12.1} ms   {from_table:>5.1} ms"
        );
    }
    Ok(())
}
