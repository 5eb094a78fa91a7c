// What each material does with light: the twin of ppm_core::bsdf, pinned to it by
// bsdf_vectors.wgsl (geometry and sampling imported). Diffuse and coated materials hold
// visible points and photons; paths continue through every other one: delta lobes (mirror,
// glass, a smooth conductor) and a rough conductor's GGX microfacets, and through a coat's
// reflection (ppm_core::bsdf::coat).

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
    return material.kind == MATERIAL_MIRROR
        || ((material.kind == MATERIAL_GLASS || material.kind == MATERIAL_CONDUCTOR)
            && max(material.alpha, material.alpha_v) < SMOOTH_ALPHA);
}

// The GGX roughness along and across the tangent (ppm_core::bsdf::roughness).
fn bsdf_roughness(material: GpuMaterial) -> vec2<f32> {
    return vec2<f32>(material.alpha, material.alpha_v);
}

// ppm_core::bsdf::is_anisotropic.
fn bsdf_is_anisotropic(material: GpuMaterial) -> bool {
    return material.alpha != material.alpha_v && !bsdf_is_delta(material);
}

// The lobe's frame on a surface facing `facing` whose u grows along u_direction
// (ppm_core::bsdf::frame).
fn bsdf_frame(material: GpuMaterial, facing: vec3<f32>, u_direction: vec3<f32>) -> Frame {
    if bsdf_is_anisotropic(material) {
        return frame_with_tangent(facing, u_direction);
    }
    return frame_around(facing);
}

// Whether eval_cos and pdf describe the bounces: not at delta surfaces nor at a rough
// dielectric (ppm_core::bsdf::samples_lights).
fn bsdf_samples_lights(material: GpuMaterial) -> bool {
    return !bsdf_is_delta(material) && material.kind != MATERIAL_GLASS;
}

fn bsdf_holds_visible_points(material: GpuMaterial) -> bool {
    return material.kind == MATERIAL_DIFFUSE || material.kind == MATERIAL_COATED;
}

// The part of f at a visible point that is the same for every pair of directions; a coat's
// arrival at each direction completes it (ppm_core::bsdf::visible_point_f).
fn visible_point_f(material: GpuMaterial) -> vec3<f32> {
    if material.kind == MATERIAL_COATED {
        return coat_base_f(material);
    }
    return material.albedo * (1.0 / PI);
}

// Smooth-boundary Fresnel reflectance, eta = eta_i / eta_t (ppm_core::bsdf::dielectric_fresnel).
fn dielectric_fresnel(cos_in: f32, eta: f32) -> f32 {
    let cos_i = clamp(cos_in, 0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return clamp(0.5 * (r_s * r_s + r_p * r_p), 0.0, 1.0);
}

fn coat_is_smooth(material: GpuMaterial) -> bool {
    return material.alpha < SMOOTH_ALPHA;
}

// The coat's transmittance t(mu): 1 - F when smooth, else the table's nodes at (i / 11)^2
// (ppm_core::bsdf::coat_transmittance).
fn coat_transmittance(material: GpuMaterial, mu_in: f32) -> f32 {
    let mu = clamp(mu_in, 0.0, 1.0);
    if coat_is_smooth(material) {
        return 1.0 - dielectric_fresnel(mu, 1.0 / material.ior);
    }
    let last = 11.0;
    let i = min(u32(sqrt(mu) * last), 10u);
    let a = sq(f32(i) / last);
    let b = sq(f32(i + 1u) / last);
    let w = clamp((mu - a) / (b - a), 0.0, 1.0);
    var table = material.coat_transmittance;
    let t0 = table[i / 4u][i % 4u];
    let t1 = table[(i + 1u) / 4u][(i + 1u) % 4u];
    return t0 + (t1 - t0) * w;
}

// What of the light arriving at cosine mu reaches a visible point's f (ppm_core::bsdf::arrival).
fn bsdf_arrival(material: GpuMaterial, mu: f32) -> f32 {
    if material.kind == MATERIAL_COATED {
        return coat_transmittance(material, mu);
    }
    return 1.0;
}

fn coat_base_f(material: GpuMaterial) -> vec3<f32> {
    var returns = vec3<f32>(1.0);
    if material.coat_nonlinear != 0u {
        returns = material.albedo;
    }
    let denominator = (vec3<f32>(1.0) - returns * material.coat_internal) * sq(material.ior);
    return material.albedo * (1.0 / PI) / denominator;
}

// ppm_core::bsdf::specular_probability.
fn coat_specular_probability(material: GpuMaterial, cos_o: f32) -> f32 {
    let t = coat_transmittance(material, cos_o);
    let w = material.coat_specular_weight;
    let specular = (1.0 - t) * w;
    let diffuse = t * (1.0 - w);
    if specular + diffuse > 0.0 {
        return specular / (specular + diffuse);
    }
    return 0.0;
}

// Whether an eye path stops here, and the factor on its throughput; negative when it
// continues (ppm_core::bsdf::visible_point_weight).
fn bsdf_visible_point_weight(material: GpuMaterial, facing: vec3<f32>, wo: vec3<f32>, u_lobe: f32) -> f32 {
    if material.kind == MATERIAL_DIFFUSE {
        return 1.0;
    }
    if material.kind == MATERIAL_COATED {
        let cos_o = dot(facing, wo);
        let p = coat_specular_probability(material, cos_o);
        if u_lobe >= p {
            return coat_transmittance(material, cos_o) / (1.0 - p);
        }
    }
    return -1.0;
}

// The factor that takes an untextured material's visible_point_f to the textured one's
// (ppm_core::textures::SurfaceTextures::shaded).
fn visible_point_scale(base: GpuMaterial, shaded: GpuMaterial, texture: vec3<f32>) -> vec3<f32> {
    if base.kind != MATERIAL_COATED || base.coat_nonlinear == 0u {
        return texture;
    }
    let f = visible_point_f(shaded);
    let f0 = visible_point_f(base);
    return select(vec3<f32>(0.0), f / f0, f0 > vec3<f32>(0.0));
}

fn visible_point_pdf(facing: vec3<f32>, wi: vec3<f32>) -> f32 {
    return max(dot(facing, wi), 0.0) * (1.0 / PI);
}

// D(m) of a local microfacet normal, from its tangential components (ppm_core::bsdf::ggx_d).
fn ggx_d(alpha: vec2<f32>, m: vec3<f32>) -> f32 {
    let sx = m.x / alpha.x;
    let sy = m.y / alpha.y;
    let d = sx * sx + sy * sy + m.z * m.z;
    return 1.0 / (PI * alpha.x * alpha.y * d * d);
}

// The unit half vector, the sum scaled before normalising (ppm_core::bsdf::half_vector).
fn half_vector(wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let sum = wo + wi;
    let m = abs(sum);
    return normalize(sum / max(m.x, max(m.y, m.z)));
}

// cos sqrt(1 + alpha^2 tan^2) of a local unit direction, the roughness along its azimuth,
// without dividing by cos (ppm_core::bsdf::smith_root).
fn smith_root(alpha: vec2<f32>, w: vec3<f32>) -> f32 {
    let x = alpha.x * w.x;
    let y = alpha.y * w.y;
    return sqrt(w.z * w.z + x * x + y * y);
}

fn ggx_reflection_pdf(alpha: vec2<f32>, local_o: vec3<f32>, d: f32) -> f32 {
    return d / (2.0 * (local_o.z + smith_root(alpha, local_o)));
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

// The GGX reflection lobe without its Fresnel term, D G2 / (4 cos_o cos_i) times cos_i
// (ppm_core::bsdf::ggx_reflection_cos).
fn ggx_reflection_cos(alpha: vec2<f32>, frame: Frame, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let local_o = frame_to_local(frame, wo);
    let local_i = frame_to_local(frame, wi);
    let cos_o = local_o.z;
    let cos_i = local_i.z;
    let d = ggx_d(alpha, frame_to_local(frame, half_vector(wo, wi)));
    let root_o = smith_root(alpha, local_o);
    let root_i = smith_root(alpha, local_i);
    return d * (0.5 * cos_i / (cos_i * root_o + cos_o * root_i));
}

fn ggx_pdf(alpha: vec2<f32>, frame: Frame, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return ggx_reflection_pdf(alpha, frame_to_local(frame, wo), ggx_d(alpha, frame_to_local(frame, half_vector(wo, wi))));
}

// Both lobes of a coated surface (ppm_core::bsdf::coat::eval_cos).
fn coat_eval_cos(material: GpuMaterial, frame: Frame, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let facing = frame.normal;
    let cos_o = dot(facing, wo);
    let cos_i = dot(facing, wi);
    let diffuse = coat_base_f(material)
        * (coat_transmittance(material, cos_o) * coat_transmittance(material, cos_i) * cos_i);
    if coat_is_smooth(material) {
        return diffuse;
    }
    let h = half_vector(wo, wi);
    let lobe = ggx_reflection_cos(bsdf_roughness(material), frame, wo, wi);
    return diffuse + vec3<f32>(dielectric_fresnel(dot(wo, h), 1.0 / material.ior) * lobe);
}

fn coat_pdf(material: GpuMaterial, frame: Frame, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let facing = frame.normal;
    let p = coat_specular_probability(material, dot(facing, wo));
    let diffuse = (1.0 - p) * dot(facing, wi) * (1.0 / PI);
    if coat_is_smooth(material) {
        return diffuse;
    }
    return diffuse + p * ggx_pdf(bsdf_roughness(material), frame, wo, wi);
}

// f(wo, wi) cos_i of a non-delta surface (ppm_core::bsdf::eval_cos).
fn bsdf_eval_cos(material: GpuMaterial, frame: Frame, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let facing = frame.normal;
    let cos_o = dot(facing, wo);
    let cos_i = dot(facing, wi);
    if cos_o <= 0.0 || cos_i <= 0.0 || !bsdf_samples_lights(material) {
        return vec3<f32>(0.0);
    }
    if material.kind == MATERIAL_CONDUCTOR {
        let h = half_vector(wo, wi);
        let lobe = ggx_reflection_cos(bsdf_roughness(material), frame, wo, wi);
        return material.albedo * conductor_fresnel(material, dot(wo, h)) * lobe;
    }
    if material.kind == MATERIAL_COATED {
        return coat_eval_cos(material, frame, wo, wi);
    }
    return visible_point_f(material) * cos_i;
}

// Density of wi given wo (ppm_core::bsdf::pdf).
fn bsdf_pdf(material: GpuMaterial, frame: Frame, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let facing = frame.normal;
    let cos_o = dot(facing, wo);
    let cos_i = dot(facing, wi);
    if cos_o <= 0.0 || cos_i <= 0.0 || !bsdf_samples_lights(material) {
        return 0.0;
    }
    if material.kind == MATERIAL_CONDUCTOR {
        return ggx_pdf(bsdf_roughness(material), frame, wo, wi);
    }
    if material.kind == MATERIAL_COATED {
        return coat_pdf(material, frame, wo, wi);
    }
    return visible_point_pdf(facing, wi);
}

// Whether an eye path continuing through the material samples the lights there: a rough
// conductor, a rough coat's reflection, rough glass (ppm_core::bsdf::chain_samples_lights).
fn bsdf_chain_samples_lights(material: GpuMaterial) -> bool {
    return ((material.kind == MATERIAL_CONDUCTOR || material.kind == MATERIAL_GLASS) && !bsdf_is_delta(material))
        || (material.kind == MATERIAL_COATED && !coat_is_smooth(material));
}

// A rough dielectric's f cos_i (x) and the density of wi (y) for an eye path that arrived
// from wo, on either side: reflection above the surface, refraction below it, the densities
// those of the sampler (ppm_core::bsdf::rough_glass::eval_cos_pdf).
fn rough_glass_eval_cos_pdf(material: GpuMaterial, frame: Frame, front: bool, wo: vec3<f32>, wi: vec3<f32>) -> vec2<f32> {
    let alpha = bsdf_roughness(material);
    let facing = frame.normal;
    let local_o = frame_to_local(frame, wo);
    let local_i = frame_to_local(frame, wi);
    let cos_o = local_o.z;
    let cos_i = local_i.z;
    if cos_o <= 0.0 || cos_i == 0.0 {
        return vec2<f32>(0.0);
    }
    let eta = select(material.ior, 1.0 / material.ior, front);
    if cos_i > 0.0 {
        let h = half_vector(wo, wi);
        let lobe = ggx_reflection_cos(alpha, frame, wo, wi);
        let fresnel = fresnel_refract(-wo, h, eta).reflectance;
        return vec2<f32>(fresnel * lobe, fresnel * ggx_pdf(alpha, frame, wo, wi));
    }
    // The microfacet normal that refracts -wo into wi, turned to wo's side.
    let sum = wo * eta + wi;
    var h = normalize(sum / max(abs(sum.x), max(abs(sum.y), abs(sum.z))));
    if dot(facing, h) < 0.0 {
        h = -h;
    }
    let o_h = dot(wo, h);
    let i_h = dot(wi, h);
    let denom = eta * o_h + i_h;
    let denom2 = denom * denom;
    // `!(denom2 > 0.0)` also refuses a NaN.
    if o_h <= 0.0 || i_h >= 0.0 || !(denom2 > 0.0) {
        return vec2<f32>(0.0);
    }
    let fresnel = fresnel_refract(-wo, h, eta);
    if !fresnel.refracts {
        return vec2<f32>(0.0);
    }
    let d = ggx_d(alpha, frame_to_local(frame, h));
    let abs_i = -cos_i;
    let root_o = smith_root(alpha, local_o);
    let root_i = smith_root(alpha, local_i);
    let jacobian = -i_h / denom2;
    let pdf = (1.0 - fresnel.reflectance) * d * 2.0 * o_h / (cos_o + root_o) * jacobian;
    let g2 = 2.0 * cos_o * abs_i / (abs_i * root_o + cos_o * root_i);
    let f_cos = eta * eta * (1.0 - fresnel.reflectance) * d * g2 * o_h * jacobian / cos_o;
    return vec2<f32>(f_cos, pdf);
}

// The lobe an eye path continues by at such a surface, arriving from wo on the side of
// facing (front: the outside): f cos over the lobe's chance in xyz, the density of wi within
// it in w; wi below the surface only at rough glass (ppm_core::bsdf::glossy_lobe).
fn bsdf_glossy_lobe(material: GpuMaterial, frame: Frame, front: bool, wo: vec3<f32>, wi: vec3<f32>) -> vec4<f32> {
    if !bsdf_chain_samples_lights(material) {
        return vec4<f32>(0.0);
    }
    let facing = frame.normal;
    if material.kind == MATERIAL_GLASS {
        let glass = rough_glass_eval_cos_pdf(material, frame, front, wo, wi);
        return vec4<f32>(vec3<f32>(glass.x), glass.y);
    }
    let cos_o = dot(facing, wo);
    let cos_i = dot(facing, wi);
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return vec4<f32>(0.0);
    }
    if material.kind == MATERIAL_COATED {
        let p = coat_specular_probability(material, cos_o);
        if p <= 0.0 {
            return vec4<f32>(0.0);
        }
        let h = half_vector(wo, wi);
        let alpha = bsdf_roughness(material);
        let lobe = ggx_reflection_cos(alpha, frame, wo, wi);
        let f_cos = dielectric_fresnel(dot(wo, h), 1.0 / material.ior) * lobe / p;
        return vec4<f32>(vec3<f32>(f_cos), ggx_pdf(alpha, frame, wo, wi));
    }
    return vec4<f32>(bsdf_eval_cos(material, frame, wo, wi), bsdf_pdf(material, frame, wo, wi));
}

// A reflection off a GGX microfacet drawn from the normals visible from wo (Heitz 2018;
// ppm_core::bsdf::sample_ggx_reflection): g2_over_g1 and pdf zero below the surface.
struct GgxReflection {
    dir: vec3<f32>,
    h: vec3<f32>,
    g2_over_g1: f32,
    pdf: f32,
}

// A microfacet normal visible from wo, local and in world space (ppm_core::bsdf::visible_normal).
struct VisibleNormal {
    m: vec3<f32>,
    h: vec3<f32>,
}

fn visible_normal(alpha: vec2<f32>, frame: Frame, wo: vec3<f32>, u: vec2<f32>) -> VisibleNormal {
    let local_o = frame_to_local(frame, wo);
    let v = normalize(vec3<f32>(alpha.x * local_o.x, alpha.y * local_o.y, local_o.z));
    // A fixed frame near normal incidence (ppm_core::bsdf::NEAR_NORMAL).
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if v.z < 0.99999 {
        t1 = vec3<f32>(-v.y, v.x, 0.0) / sqrt(v.x * v.x + v.y * v.y);
    }
    let t2 = cross(v, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + v.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = t1 * p1 + t2 * p2 + v * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    let m = normalize(vec3<f32>(alpha.x * nh.x, alpha.y * nh.y, max(nh.z, 0.0)));
    return VisibleNormal(m, frame_to_world(frame, m));
}

// G2 / G1(wo) at local directions, local_i on either side, in the form that cancels cos_o
// (ppm_core::bsdf::ggx_g2_over_g1).
fn ggx_g2_over_g1(alpha: vec2<f32>, local_o: vec3<f32>, local_i: vec3<f32>) -> f32 {
    let cos_o = local_o.z;
    let cos_i = abs(local_i.z);
    let root_o = smith_root(alpha, local_o);
    let root_i = smith_root(alpha, local_i);
    return cos_i * (cos_o + root_o) / (cos_i * root_o + cos_o * root_i);
}

fn sample_ggx_reflection(alpha: vec2<f32>, frame: Frame, wo: vec3<f32>, u: vec2<f32>) -> GgxReflection {
    let normal = visible_normal(alpha, frame, wo, u);
    let m = normal.m;
    let h = normal.h;
    let dir = reflect(-wo, h);
    let local_o = frame_to_local(frame, wo);
    let local_i = frame_to_local(frame, dir);
    if local_o.z <= 0.0 || local_i.z <= 0.0 {
        return GgxReflection(dir, h, 0.0, 0.0);
    }
    return GgxReflection(dir, h, ggx_g2_over_g1(alpha, local_o, local_i), ggx_reflection_pdf(alpha, local_o, ggx_d(alpha, m)));
}

// A rough conductor's visible normals (ppm_core::bsdf::sample_conductor).
fn bsdf_sample_conductor(material: GpuMaterial, frame: Frame, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    let r = sample_ggx_reflection(bsdf_roughness(material), frame, wo, u);
    let weight = material.albedo * conductor_fresnel(material, dot(wo, r.h)) * r.g2_over_g1;
    return BsdfSample(r.dir, weight, r.pdf, false);
}

// A rough dielectric: reflection with the Fresnel term at a visible microfacet as its
// chance, else refraction through it; weight G2 / G1(wo), times (eta_i / eta_t)^2 for
// radiance refracted; no density (ppm_core::bsdf::sample_rough_dielectric).
fn bsdf_sample_rough_dielectric(material: GpuMaterial, incoming: vec3<f32>, frame: Frame, front: bool, u_lobe: f32, u_dir: vec2<f32>, transport: u32) -> BsdfSample {
    let wo = -incoming;
    let eta = select(material.ior, 1.0 / material.ior, front);
    let alpha = bsdf_roughness(material);
    let h = visible_normal(alpha, frame, wo, u_dir).h;
    let fresnel = fresnel_refract(incoming, h, eta);
    var dir = reflect(incoming, h);
    var transmitted = false;
    if fresnel.refracts && u_lobe >= fresnel.reflectance {
        dir = fresnel.refracted;
        transmitted = true;
    }
    let local_o = frame_to_local(frame, wo);
    let local_i = frame_to_local(frame, dir);
    let on_its_side = select(local_i.z > 0.0, local_i.z < 0.0, transmitted);
    var weight = 0.0;
    if local_o.z > 0.0 && on_its_side {
        weight = ggx_g2_over_g1(alpha, local_o, local_i);
    }
    if transmitted && transport == TRANSPORT_RADIANCE {
        weight *= eta * eta;
    }
    return BsdfSample(dir, vec3<f32>(weight), 0.0, transmitted);
}

// The cosine lobe at a visible point; the weight is f cos / pdf with the coat's arrival
// (ppm_core::bsdf::sample_visible).
fn bsdf_sample_visible(material: GpuMaterial, facing: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    let local = cosine_hemisphere(u.x, u.y);
    var weight = material.albedo;
    if material.kind == MATERIAL_COATED {
        weight = coat_base_f(material) * (PI * coat_transmittance(material, local.z));
    }
    return BsdfSample(to_world(local, facing), weight, local.z * (1.0 / PI), false);
}

// One lobe of a coated surface, picked by u_lobe, its weight over its chance
// (ppm_core::bsdf::coat::sample).
fn coat_sample(material: GpuMaterial, incoming: vec3<f32>, frame: Frame, u_lobe: f32, u_dir: vec2<f32>) -> BsdfSample {
    let wo = -incoming;
    let facing = frame.normal;
    let cos_o = dot(facing, wo);
    let p = coat_specular_probability(material, cos_o);
    let eta = 1.0 / material.ior;
    if u_lobe < p {
        if coat_is_smooth(material) {
            return BsdfSample(reflect(incoming, facing), vec3<f32>(dielectric_fresnel(cos_o, eta) / p), 0.0, false);
        }
        let r = sample_ggx_reflection(bsdf_roughness(material), frame, wo, u_dir);
        let weight = dielectric_fresnel(dot(wo, r.h), eta) * r.g2_over_g1 / p;
        var density = 0.0;
        if weight > 0.0 {
            density = coat_pdf(material, frame, wo, r.dir);
        }
        return BsdfSample(r.dir, vec3<f32>(weight), density, false);
    }
    let drawn = bsdf_sample_visible(material, facing, u_dir);
    let through = coat_transmittance(material, cos_o) * coat_transmittance(material, dot(facing, drawn.dir));
    let weight = coat_base_f(material) * (PI * through / (1.0 - p));
    return BsdfSample(drawn.dir, weight, coat_pdf(material, frame, wo, drawn.dir), false);
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

fn bsdf_sample(material: GpuMaterial, incoming: vec3<f32>, frame: Frame, front: bool, u_lobe: f32, u_dir: vec2<f32>, transport: u32) -> BsdfSample {
    if bsdf_is_delta(material) {
        return bsdf_sample_delta(material, incoming, frame.normal, front, u_lobe, transport);
    }
    if material.kind == MATERIAL_CONDUCTOR {
        return bsdf_sample_conductor(material, frame, -incoming, u_dir);
    }
    if material.kind == MATERIAL_COATED {
        return coat_sample(material, incoming, frame, u_lobe, u_dir);
    }
    if GLASS && material.kind == MATERIAL_GLASS {
        return bsdf_sample_rough_dielectric(material, incoming, frame, front, u_lobe, u_dir, transport);
    }
    return bsdf_sample_visible(material, frame.normal, u_dir);
}

// How a photon continues (ppm_core::bsdf::photon_bounce): u_lobe picks the lobe at a delta
// or coated surface and plays roulette where the photon scatters diffusely (rescaled past
// a coat's reflection); the weight is zero where the path ends.
fn bsdf_photon_bounce(material: GpuMaterial, incoming: vec3<f32>, frame: Frame, front: bool, u_lobe: f32, u_dir: vec2<f32>) -> BsdfSample {
    let facing = frame.normal;
    var scattered = bsdf_sample(material, incoming, frame, front, u_lobe, u_dir, TRANSPORT_IMPORTANCE);
    var u_roulette = -1.0;
    if material.kind == MATERIAL_DIFFUSE {
        u_roulette = u_lobe;
    } else if material.kind == MATERIAL_COATED {
        let p = coat_specular_probability(material, -dot(incoming, facing));
        if u_lobe >= p {
            u_roulette = min((u_lobe - p) / (1.0 - p), 0.99999994);
        }
    }
    if u_roulette >= 0.0 {
        let survive = min(max(scattered.weight.x, max(scattered.weight.y, scattered.weight.z)), 1.0);
        if u_roulette >= survive {
            scattered.weight = vec3<f32>(0.0);
        } else {
            scattered.weight /= survive;
        }
    }
    return scattered;
}
