// Ray geometry: the twin of ppm_core::geometry.

// Distance reported for a miss: larger than any real hit.
const T_MISS: f32 = 3.4028235e38;

fn intersect_triangle(origin: vec3<f32>, dir: vec3<f32>, v0: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, tmin: f32, tmax: f32) -> f32 {
    let p = cross(dir, e2);
    let det = dot(e1, p);
    if abs(det) < 1e-20 || !is_finite_f32(det) {
        return T_MISS;
    }
    let inv_det = 1.0 / det;
    let s = origin - v0;
    let b1 = dot(s, p) * inv_det;
    if b1 < 0.0 || b1 > 1.0 {
        return T_MISS;
    }
    let q = cross(s, e1);
    let b2 = dot(dir, q) * inv_det;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return T_MISS;
    }
    let t = dot(e2, q) * inv_det;
    if t > tmin && t < tmax {
        return t;
    }
    return T_MISS;
}

struct Basis {
    tangent: vec3<f32>,
    bitangent: vec3<f32>,
}

fn orthonormal_basis(n: vec3<f32>) -> Basis {
    // copysign(1, n.z), reading the sign bit so that -0.0 counts as negative as in Rust.
    let sign = select(1.0, -1.0, (bitcast<u32>(n.z) & 0x80000000u) != 0u);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Basis(
        vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3<f32>(b, sign + n.y * n.y * a, -n.y),
    );
}

fn to_world(local: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let basis = orthonormal_basis(n);
    return basis.tangent * local.x + basis.bitangent * local.y + n * local.z;
}

// A BSDF's frame at a surface point: the normal on the path's side and the tangent an
// anisotropic lobe follows (ppm_core::geometry::Frame).
struct Frame {
    tangent: vec3<f32>,
    bitangent: vec3<f32>,
    normal: vec3<f32>,
}

fn frame_around(n: vec3<f32>) -> Frame {
    let basis = orthonormal_basis(n);
    return Frame(basis.tangent, basis.bitangent, n);
}

// The frame about n whose tangent is direction less its part along n; frame_around(n)
// where nothing is left of it (ppm_core::geometry::Frame::with_tangent).
fn frame_with_tangent(n: vec3<f32>, direction: vec3<f32>) -> Frame {
    let m = abs(direction);
    let scale = max(m.x, max(m.y, m.z));
    if !(scale > 0.0 && is_finite_f32(scale)) {
        return frame_around(n);
    }
    let d = direction / scale;
    let t = d - n * dot(n, d);
    if !(dot(t, t) > 1e-12) {
        return frame_around(n);
    }
    let tangent = normalize(t);
    return Frame(tangent, cross(n, tangent), n);
}

fn frame_to_local(frame: Frame, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(frame.tangent, v), dot(frame.bitangent, v), dot(frame.normal, v));
}

fn frame_to_world(frame: Frame, local: vec3<f32>) -> vec3<f32> {
    return frame.tangent * local.x + frame.bitangent * local.y + frame.normal * local.z;
}

struct Fresnel {
    reflectance: f32,
    refracts: bool,
    refracted: vec3<f32>,
}

fn fresnel_refract(d: vec3<f32>, n: vec3<f32>, eta: f32) -> Fresnel {
    let cos_i = clamp(-dot(d, n), 0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return Fresnel(1.0, false, vec3<f32>(0.0));
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let f = 0.5 * (r_s * r_s + r_p * r_p);
    let t = d * eta + n * (eta * cos_i - cos_t);
    return Fresnel(clamp(f, 0.0, 1.0), true, normalize(t));
}

fn sign_nonzero(v: f32) -> f32 {
    return select(-1.0, 1.0, v >= 0.0);
}

fn oct_quantise(v: f32) -> u32 {
    return u32(floor((clamp(v, -1.0, 1.0) * 0.5 + 0.5) * 65535.0 + 0.5));
}

fn oct_encode(n: vec3<f32>) -> u32 {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    var x = n.x / l1;
    var y = n.y / l1;
    if n.z < 0.0 {
        let ox = x;
        let oy = y;
        x = (1.0 - abs(oy)) * sign_nonzero(ox);
        y = (1.0 - abs(ox)) * sign_nonzero(oy);
    }
    return oct_quantise(x) | (oct_quantise(y) << 16u);
}

fn oct_unfold(bits: u32) -> vec3<f32> {
    var x = f32(bits & 0xffffu) * (2.0 / 65535.0) - 1.0;
    var y = f32(bits >> 16u) * (2.0 / 65535.0) - 1.0;
    let z = 1.0 - abs(x) - abs(y);
    if z < 0.0 {
        let ox = x;
        let oy = y;
        x = (1.0 - abs(oy)) * sign_nonzero(ox);
        y = (1.0 - abs(ox)) * sign_nonzero(oy);
    }
    return vec3<f32>(x, y, z);
}

fn oct_decode(bits: u32) -> vec3<f32> {
    return normalize(oct_unfold(bits));
}

// Whether the packed normal points into n's hemisphere: the sign needs no normalising.
fn oct_faces(bits: u32, n: vec3<f32>) -> bool {
    return dot(oct_unfold(bits), n) > 0.0;
}

fn camera_ray(camera: GpuCamera, px: f32, py: f32) -> vec3<f32> {
    let sx = 2.0 * px / f32(camera.width) - 1.0;
    let sy = 1.0 - 2.0 * py / f32(camera.height);
    return normalize(camera.forward + camera.right * sx + camera.up * sy);
}

// Whether the segment origin + t dir, 0 <= t <= t_max, meets the closed box [lo, hi]
// (ppm_core::geometry::segment_meets_box); an empty box (lo > hi) is never met.
fn segment_meets_box(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, lo: vec3<f32>, hi: vec3<f32>) -> bool {
    if any(lo > hi) {
        return false;
    }
    var t0 = 0.0;
    var t1 = t_max;
    for (var axis = 0u; axis < 3u; axis++) {
        let o = origin[axis];
        let d = dir[axis];
        if d == 0.0 {
            if o < lo[axis] || o > hi[axis] {
                return false;
            }
            continue;
        }
        let a = (lo[axis] - o) / d;
        let b = (hi[axis] - o) / d;
        t0 = max(t0, min(a, b));
        t1 = min(t1, max(a, b));
        if t0 > t1 {
            return false;
        }
    }
    return true;
}
