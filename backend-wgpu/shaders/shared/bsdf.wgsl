// What each material does with light: the twin of ppm_core::bsdf, pinned to it by
// bsdf_vectors.wgsl (geometry and sampling imported). Diffuse materials hold visible points
// and photons; paths continue through every other one: delta lobes (mirror, glass, a smooth
// conductor) and a rough conductor's GGX microfacets.

// ppm_core::bsdf::SMOOTH_ALPHA.
const SMOOTH_ALPHA: f32 = 1e-3;

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
    return material.kind == MATERIAL_MIRROR || material.kind == MATERIAL_GLASS
        || (material.kind == MATERIAL_CONDUCTOR && material.alpha < SMOOTH_ALPHA);
}

fn bsdf_holds_visible_points(material: GpuMaterial) -> bool {
    return material.kind == MATERIAL_DIFFUSE;
}

// f at a visible point, the same for every pair of directions on its side.
fn visible_point_f(material: GpuMaterial) -> vec3<f32> {
    return material.albedo * (1.0 / PI);
}

fn visible_point_pdf(facing: vec3<f32>, wi: vec3<f32>) -> f32 {
    return max(dot(facing, wi), 0.0) * (1.0 / PI);
}

// D(m) of a local microfacet normal, from its tangential components (ppm_core::bsdf::ggx_d).
fn ggx_d(alpha: f32, m: vec3<f32>) -> f32 {
    let a2 = alpha * alpha;
    let d = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
    return 1.0 / (PI * a2 * d * d);
}

// The unit half vector, the sum scaled before normalising (ppm_core::bsdf::half_vector).
fn half_vector(wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let sum = wo + wi;
    let m = abs(sum);
    return normalize(sum / max(m.x, max(m.y, m.z)));
}

fn local_half(facing: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let h = half_vector(wo, wi);
    let basis = orthonormal_basis(facing);
    return vec3<f32>(dot(basis.tangent, h), dot(basis.bitangent, h), dot(facing, h));
}

// cos sqrt(1 + alpha^2 tan^2) without dividing by cos (ppm_core::bsdf::smith_root).
fn smith_root(alpha: f32, cos: f32) -> f32 {
    let a2 = alpha * alpha;
    return sqrt(a2 + (1.0 - a2) * cos * cos);
}

fn ggx_reflection_pdf(alpha: f32, cos_o: f32, d: f32) -> f32 {
    return d / (2.0 * (cos_o + smith_root(alpha, cos_o)));
}

fn sq(x: f32) -> f32 {
    return x * x;
}

// One channel of a conductor's Fresnel term for index eta + i k (ppm_core::bsdf::complex_fresnel).
fn complex_fresnel(cos_in: f32, eta: f32, k: f32) -> f32 {
    let cos_i = clamp(cos_in, 0.0, 1.0);
    let sin2 = 1.0 - cos_i * cos_i;
    let re = eta * eta - k * k - sin2;
    let im = 2.0 * eta * k;
    let modulus = sqrt(re * re + im * im);
    let a = sqrt(max(0.5 * (modulus + re), 0.0));
    let b = select(-1.0, 1.0, im >= 0.0) * sqrt(max(0.5 * (modulus - re), 0.0));
    let rs = (sq(cos_i - a) + b * b) / max(sq(cos_i + a) + b * b, F32_MIN_POSITIVE);
    let n2_re = (eta * eta - k * k) * cos_i;
    let n2_im = 2.0 * eta * k * cos_i;
    let rp = (sq(n2_re - a) + sq(n2_im - b)) / max(sq(n2_re + a) + sq(n2_im + b), F32_MIN_POSITIVE);
    return clamp(0.5 * (rs + rp), 0.0, 1.0);
}

fn conductor_fresnel(material: GpuMaterial, cos_i: f32) -> vec3<f32> {
    return vec3<f32>(
        complex_fresnel(cos_i, material.eta.x, material.k.x),
        complex_fresnel(cos_i, material.eta.y, material.k.y),
        complex_fresnel(cos_i, material.eta.z, material.k.z),
    );
}

// f(wo, wi) cos_i of a non-delta surface (ppm_core::bsdf::eval_cos).
fn bsdf_eval_cos(material: GpuMaterial, facing: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_o = dot(facing, wo);
    let cos_i = dot(facing, wi);
    if cos_o <= 0.0 || cos_i <= 0.0 || bsdf_is_delta(material) {
        return vec3<f32>(0.0);
    }
    if material.kind != MATERIAL_CONDUCTOR {
        return visible_point_f(material) * cos_i;
    }
    let h = half_vector(wo, wi);
    let alpha = material.alpha;
    let d = ggx_d(alpha, local_half(facing, wo, wi));
    let root_o = smith_root(alpha, cos_o);
    let root_i = smith_root(alpha, cos_i);
    let visibility_cos = 0.5 * cos_i / (cos_i * root_o + cos_o * root_i);
    return material.albedo * conductor_fresnel(material, dot(wo, h)) * (d * visibility_cos);
}

// Density of wi given wo (ppm_core::bsdf::pdf).
fn bsdf_pdf(material: GpuMaterial, facing: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let cos_o = dot(facing, wo);
    let cos_i = dot(facing, wi);
    if cos_o <= 0.0 || cos_i <= 0.0 || bsdf_is_delta(material) {
        return 0.0;
    }
    if material.kind != MATERIAL_CONDUCTOR {
        return visible_point_pdf(facing, wi);
    }
    let alpha = material.alpha;
    return ggx_reflection_pdf(alpha, cos_o, ggx_d(alpha, local_half(facing, wo, wi)));
}

// A rough conductor's visible normals (Heitz 2018; ppm_core::bsdf::sample_conductor).
fn bsdf_sample_conductor(material: GpuMaterial, facing: vec3<f32>, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    let alpha = material.alpha;
    let basis = orthonormal_basis(facing);
    let local_o = vec3<f32>(dot(basis.tangent, wo), dot(basis.bitangent, wo), dot(facing, wo));
    let v = normalize(vec3<f32>(alpha * local_o.x, alpha * local_o.y, local_o.z));
    let len2 = v.x * v.x + v.y * v.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if len2 > 0.0 {
        t1 = vec3<f32>(-v.y, v.x, 0.0) / sqrt(len2);
    }
    let t2 = cross(v, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + v.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = t1 * p1 + t2 * p2 + v * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    let m = normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    let h = to_world(m, facing);
    let dir = reflect(-wo, h);
    let cos_o = local_o.z;
    let cos_i = dot(facing, dir);
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return BsdfSample(dir, vec3<f32>(0.0), 0.0, false);
    }
    // F G2 / G1(wo) in the form that cancels cos_o (ppm_core::bsdf::sample_conductor).
    let root_o = smith_root(alpha, cos_o);
    let root_i = smith_root(alpha, cos_i);
    let g2_over_g1 = cos_i * (cos_o + root_o) / (cos_i * root_o + cos_o * root_i);
    let weight = material.albedo * conductor_fresnel(material, dot(wo, h)) * g2_over_g1;
    return BsdfSample(dir, weight, ggx_reflection_pdf(alpha, cos_o, ggx_d(alpha, m)), false);
}

fn bsdf_sample_visible(material: GpuMaterial, facing: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    let local = cosine_hemisphere(u.x, u.y);
    return BsdfSample(to_world(local, facing), material.albedo, local.z * (1.0 / PI), false);
}

fn bsdf_sample_delta(material: GpuMaterial, incoming: vec3<f32>, facing: vec3<f32>, front: bool, u_lobe: f32, transport: u32) -> BsdfSample {
    let reflected = reflect(incoming, facing);
    if material.kind == MATERIAL_CONDUCTOR {
        let fresnel = conductor_fresnel(material, -dot(incoming, facing));
        return BsdfSample(reflected, material.albedo * fresnel, 0.0, false);
    }
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
    if material.kind == MATERIAL_CONDUCTOR {
        return bsdf_sample_conductor(material, facing, -incoming, u_dir);
    }
    return bsdf_sample_visible(material, facing, u_dir);
}
