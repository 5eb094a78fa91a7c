// Which pixels a triangle may cover, seen from the camera: the twin of
// ppm_core::screen_cover, conservative as it is (every doubt marks). The projection's
// inverse basis comes computed on the host (backend-wgpu's local_move.rs, as
// ppm_core::screen_cover::Projection computes it), in CoverParams.

// ppm_core::screen_cover's MARGIN: each pixel's square widened, in pixels.
const COVER_MARGIN: f32 = 0.05;
// f32::EPSILON.
const COVER_EPSILON: f32 = 1.1920929e-7;

// The projection (ppm_core::screen_cover::Projection) and what the cover kernel walks.
struct CoverParams {
    to_camera: mat3x3<f32>,
    eye: vec3<f32>,
    triangles: u32,
    width: u32,
    height: u32,
    objects: u32,
    _pad0: u32,
}

// Image coordinates of `p` in pixels in xy, and z one where `p` lies in front of the eye
// and projects to finite coordinates, zero otherwise (Projection::project).
fn cover_project(c: CoverParams, p: vec3<f32>) -> vec3<f32> {
    let d = p - c.eye;
    // glam's Mat3 * Vec3, column by column.
    let v = c.to_camera[0] * d.x + c.to_camera[1] * d.y + c.to_camera[2] * d.z;
    if !(v.x > 0.0) {
        return vec3<f32>(0.0);
    }
    let sx = v.y / v.x;
    let sy = v.z / v.x;
    let image = vec2<f32>((sx + 1.0) * 0.5, (1.0 - sy) * 0.5) * vec2<f32>(f32(c.width), f32(c.height));
    let finite = is_finite_f32(image.x) && is_finite_f32(image.y);
    return vec3<f32>(image, select(0.0, 1.0, finite));
}

// f32::signum: one for +0 and above, minus one for -0 and below, NaN for NaN.
fn cover_signum(x: f32) -> f32 {
    if x != x {
        return x;
    }
    return select(1.0, -1.0, (bitcast<u32>(x) & 0x80000000u) != 0u);
}

// One triangle on the image: the pixels its widened squares may overlap lie in
// first..=last; `everything` where a vertex lies behind the eye (every pixel marked),
// `nothing` where its box misses the image.
struct CoverTriangle {
    first: vec2<u32>,
    last: vec2<u32>,
    // The vertices, and the edges from each, oriented so that the inside is on their left.
    p0: vec2<f32>,
    p1: vec2<f32>,
    p2: vec2<f32>,
    e0: vec2<f32>,
    e1: vec2<f32>,
    e2: vec2<f32>,
    edge_on: bool,
    everything: bool,
    nothing: bool,
}

// glam's perp_dot.
fn cover_perp_dot(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// The triangle of world-space vertices `v0`, `v1`, `v2` on the image (covered_pixels and
// mark_triangle up to the loop over pixels).
fn cover_triangle(c: CoverParams, v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> CoverTriangle {
    var t: CoverTriangle;
    let a = cover_project(c, v0);
    let b = cover_project(c, v1);
    let d = cover_project(c, v2);
    if a.z == 0.0 || b.z == 0.0 || d.z == 0.0 {
        t.everything = true;
        return t;
    }
    t.p0 = a.xy;
    t.p1 = b.xy;
    t.p2 = d.xy;
    let size = vec2<f32>(f32(c.width), f32(c.height));
    let lo = min(min(t.p0, t.p1), t.p2) - COVER_MARGIN;
    let hi = max(max(t.p0, t.p1), t.p2) + COVER_MARGIN;
    if hi.x < 0.0 || hi.y < 0.0 || lo.x >= size.x || lo.y >= size.y {
        t.nothing = true;
        return t;
    }
    t.first = vec2<u32>(floor(max(lo, vec2<f32>(0.0))));
    t.last = vec2<u32>(floor(min(hi, size - 1.0)));
    let twice_area = cover_perp_dot(t.p1 - t.p0, t.p2 - t.p0);
    let span = hi - lo;
    t.edge_on = abs(twice_area) <= COVER_EPSILON * (span.x * span.x + span.y * span.y);
    let orient = cover_signum(twice_area);
    t.e0 = (t.p1 - t.p0) * orient;
    t.e1 = (t.p2 - t.p1) * orient;
    t.e2 = (t.p0 - t.p2) * orient;
    return t;
}

// Whether the edge from `a` along `edge` leaves some point of the square around `centre`
// on its inner side: the edge function's largest value over the square, at the centre plus
// the half-size times the gradient's 1-norm.
fn cover_inside_edge(a: vec2<f32>, edge: vec2<f32>, centre: vec2<f32>) -> bool {
    let half = 0.5 + COVER_MARGIN;
    return cover_perp_dot(edge, centre - a) + half * (abs(edge.x) + abs(edge.y)) >= 0.0;
}

// Whether the triangle `t` may cover pixel (x, y), one of first..=last.
fn cover_pixel(t: CoverTriangle, x: u32, y: u32) -> bool {
    let centre = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    return t.edge_on || (cover_inside_edge(t.p0, t.e0, centre) && cover_inside_edge(t.p1, t.e1, centre)
        && cover_inside_edge(t.p2, t.e2, centre));
}
