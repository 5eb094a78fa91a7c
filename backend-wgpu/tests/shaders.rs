//! Every assembled shader parses and validates with naga, without a GPU.

#[test]
fn every_pass_shader_validates() {
    for (name, source) in backend_wgpu::shaders::ALL {
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
    }
}

/// No entry point reads more storage textures (tables) or storage buffers than any WebGPU
/// device offers (`wgpu::Limits::default()`), so the required path runs anywhere. (The kernels
/// bind only what their entry point reads: `Slot::Unused`.)
#[test]
fn every_entry_point_fits_baseline_binding_limits() {
    let baseline = wgpu::Limits::default();
    for (name, source) in backend_wgpu::shaders::ALL {
        let module = naga::front::wgsl::parse_str(source).expect("parses");
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .expect("validates");
        for (i, entry) in module.entry_points.iter().enumerate() {
            let uses = info.get_entry_point(i);
            let (mut textures, mut buffers) = (0, 0);
            for (handle, global) in module.global_variables.iter() {
                if uses[handle].is_empty() {
                    continue;
                }
                match (&module.types[global.ty].inner, global.space) {
                    (
                        naga::TypeInner::Image {
                            class: naga::ImageClass::Storage { .. },
                            ..
                        },
                        _,
                    ) => textures += 1,
                    (_, naga::AddressSpace::Storage { .. }) => buffers += 1,
                    _ => {}
                }
            }
            let at = format!("{name}::{}", entry.name);
            assert!(
                textures <= baseline.max_storage_textures_per_shader_stage,
                "{at}: {textures} storage textures"
            );
            assert!(
                buffers <= baseline.max_storage_buffers_per_shader_stage,
                "{at}: {buffers} storage buffers"
            );
        }
    }
}
