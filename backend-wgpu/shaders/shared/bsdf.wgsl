// What each material does with light: the twin of ppm_core::bsdf, pinned to it by
// bsdf_vectors.wgsl (geometry and sampling imported). Delta materials (mirror, glass) continue
// paths; every other material holds visible points and photons, and is diffuse so far.

// What a path carries (ppm_core::bsdf::Transport). An eye path's throughput weights radiance,
// which refraction scales by (eta_i / eta_t)^2; a photon's power is flux, which it keeps.
const TRANSPORT_RADIANCE: u32 = 0u;
const TRANSPORT_IMPORTANCE: u32 = 1u;

// False for a scene without glass: the refraction half of the delta lobes is compiled out
// (backend_wgpu::Specialisation); a pipeline that does not set it keeps it.
override GLASS: bool = true;

struct BsdfSample {
    dir: vec3<f32>,
    // f cos / pdf (times (eta_i / eta_t)^2 for radiance through a refraction).
    weight: vec3<f32>,
    // Solid-angle density of dir; zero for a delta lobe.
    pdf: f32,
    transmitted: bool,
}

fn bsdf_is_delta(material: GpuMaterial) -> bool {
    return material.kind == MATERIAL_MIRROR || material.kind == MATERIAL_GLASS;
}

// f at a visible point, the same for every pair of directions on its side.
fn visible_point_f(material: GpuMaterial) -> vec3<f32> {
    return material.albedo * (1.0 / PI);
}

fn bsdf_pdf(material: GpuMaterial, facing: vec3<f32>, wi: vec3<f32>) -> f32 {
    if bsdf_is_delta(material) {
        return 0.0;
    }
    return max(dot(facing, wi), 0.0) * (1.0 / PI);
}

fn bsdf_sample_visible(material: GpuMaterial, facing: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    let local = cosine_hemisphere(u.x, u.y);
    return BsdfSample(to_world(local, facing), material.albedo, local.z * (1.0 / PI), false);
}

fn bsdf_sample_delta(material: GpuMaterial, incoming: vec3<f32>, facing: vec3<f32>, front: bool, u_lobe: f32, transport: u32) -> BsdfSample {
    let reflected = reflect(incoming, facing);
    if material.kind == MATERIAL_MIRROR || !GLASS {
        return BsdfSample(reflected, material.albedo, 0.0, false);
    }
    let eta = select(material.ior, 1.0 / material.ior, front);
    let fresnel = fresnel_refract(incoming, facing, eta);
    if fresnel.refracts && u_lobe >= fresnel.reflectance {
        let scale = select(1.0, eta * eta, transport == TRANSPORT_RADIANCE);
        return BsdfSample(fresnel.refracted, vec3<f32>(scale), 0.0, true);
    }
    return BsdfSample(reflected, vec3<f32>(1.0), 0.0, false);
}

fn bsdf_sample(material: GpuMaterial, incoming: vec3<f32>, facing: vec3<f32>, front: bool, u_lobe: f32, u_dir: vec2<f32>, transport: u32) -> BsdfSample {
    if bsdf_is_delta(material) {
        return bsdf_sample_delta(material, incoming, facing, front, u_lobe, transport);
    }
    return bsdf_sample_visible(material, facing, u_dir);
}
