// BVH traversal over the flattened obvhs nodes, with a fixed-size stack. Reads the nodes (two
// texels each) and triangles (four texels each) from the scene table (scene.wgsl imported).
// The CPU backend traverses the same tree with obvhs itself, and finds the same triangle:
// the nearest, the lowest index among equally near ones (`nearer`). A scene without triangles is uploaded as one leaf
// holding one degenerate triangle, which no ray hits.

const STACK_SIZE: u32 = 64u;

// The traversal stack, one per invocation rather than per traversal: WGSL zeroes a variable
// where it is declared, and lavapipe zeroes this one entry by entry and lane by lane (512
// masked stores), which cost a quarter of the eye and photon passes when every ray did it.
var<private> stack: array<u32, STACK_SIZE>;

struct Hit {
    t: f32,
    triangle: u32,
}

fn bvh_node(i: u32) -> BvhNode {
    let a = scene_texel(scene.nodes + 2u * i);
    let b = scene_texel(scene.nodes + 2u * i + 1u);
    return BvhNode(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}

fn scene_triangle(i: u32) -> GpuTriangle {
    let a = scene_texel(scene.triangles + 4u * i);
    let b = scene_texel(scene.triangles + 4u * i + 1u);
    let c = scene_texel(scene.triangles + 4u * i + 2u);
    let d = scene_texel(scene.triangles + 4u * i + 3u);
    return GpuTriangle(
        bitcast<vec3<f32>>(a.xyz), a.w,
        bitcast<vec3<f32>>(b.xyz), b.w,
        bitcast<vec3<f32>>(c.xyz), c.w,
        bitcast<vec3<f32>>(d.xyz), d.w,
    );
}

// Distance along the ray to triangle `i` if within (0, tmax), else T_MISS; reads only the
// texels the test needs (the vertex and the two edges).
fn hit_distance(origin: vec3<f32>, dir: vec3<f32>, i: u32, tmax: f32) -> f32 {
    let v0 = bitcast<vec3<f32>>(scene_texel(scene.triangles + 4u * i).xyz);
    let e1 = bitcast<vec3<f32>>(scene_texel(scene.triangles + 4u * i + 1u).xyz);
    let e2 = bitcast<vec3<f32>>(scene_texel(scene.triangles + 4u * i + 2u).xyz);
    return intersect_triangle(origin, dir, v0, e1, e2, 0.0, tmax);
}

fn safe_inverse(x: f32) -> f32 {
    let eps = 1.1920929e-7;
    if abs(x) <= eps {
        return sign_nonzero(x) / eps;
    }
    return 1.0 / x;
}

// Entry distance of the ray into the box, or T_MISS.
fn ray_box(origin: vec3<f32>, inv_dir: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    let t1 = (lo - origin) * inv_dir;
    let t2 = (hi - origin) * inv_dir;
    let tmin = max(max(min(t1.x, t2.x), min(t1.y, t2.y)), max(min(t1.z, t2.z), 0.0));
    let tmax = min(min(max(t1.x, t2.x), max(t1.y, t2.y)), max(t1.z, t2.z));
    if tmin <= tmax {
        return tmin;
    }
    return T_MISS;
}

// Relative slack of box_reach (ppm_core::trace::BOX_SLACK, 16 ulps of one).
const BOX_SLACK: f32 = 1.9073486e-6;

// Whether a triangle at `t` with index `i` replaces `hit`: nearer, or as near with a lower
// index, so that a tie (a ray through an edge two triangles share) resolves as on every
// backend, whatever order the walk visits them in (ppm_core::trace::nearer).
fn nearer(t: f32, i: u32, hit: Hit) -> bool {
    return t < hit.t || (t == hit.t && i < hit.triangle);
}

// How far a triangle may lie and still replace `hit`: just past it once something was hit
// (a tie is tested), `tmax` (excluded) before (ppm_core::trace::tie_bound).
fn tie_bound(hit: Hit) -> f32 {
    if hit.triangle == 0xffffffffu {
        return hit.t;
    }
    return bitcast<f32>(bitcast<u32>(hit.t) + 1u);
}

// How far a box may be entered and still be visited: a little past the nearest hit, since
// a box's entry is rounded apart from the distance of a triangle in its face
// (ppm_core::trace::box_reach).
fn box_reach(hit: Hit) -> f32 {
    if hit.triangle == 0xffffffffu {
        return hit.t;
    }
    return hit.t * (1.0 + BOX_SLACK);
}

// Nearest triangle with 0 < t < tmax, the lowest index among equally near ones
// (`nearer`); `triangle` is 0xffffffff on a miss. Children are visited nearer first: the
// nearer one straight away (its node already read), the farther one from the stack.
fn trace_closest(origin: vec3<f32>, dir: vec3<f32>, tmax: f32, any_hit: bool) -> Hit {
    var hit = Hit(tmax, 0xffffffffu);
    let inv_dir = vec3<f32>(safe_inverse(dir.x), safe_inverse(dir.y), safe_inverse(dir.z));
    var sp = 0u;
    var node = bvh_node(0u);
    var enter = ray_box(origin, inv_dir, node.min, node.max);
    loop {
        if enter < box_reach(hit) {
            if node.count == 0u {
                let left = bvh_node(node.first);
                let right = bvh_node(node.first + 1u);
                let t_left = ray_box(origin, inv_dir, left.min, left.max);
                let t_right = ray_box(origin, inv_dir, right.min, right.max);
                let left_first = t_left <= t_right;
                if max(t_left, t_right) < box_reach(hit) && sp < STACK_SIZE {
                    stack[sp] = select(node.first, node.first + 1u, left_first);
                    sp++;
                }
                if left_first {
                    node = left;
                } else {
                    node = right;
                }
                enter = min(t_left, t_right);
                continue;
            }
            for (var i = node.first; i < node.first + node.count; i++) {
                let bound = tie_bound(hit);
                let t = hit_distance(origin, dir, i, bound);
                if t < bound && nearer(t, i, hit) {
                    hit = Hit(t, i);
                    if any_hit {
                        return hit;
                    }
                }
            }
        }
        if sp == 0u {
            break;
        }
        sp--;
        node = bvh_node(stack[sp]);
        enter = ray_box(origin, inv_dir, node.min, node.max);
    }
    return hit;
}

fn closest_hit(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> Hit {
    return trace_closest(origin, dir, tmax, false);
}

fn occluded(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> bool {
    return trace_closest(origin, dir, tmax, true).triangle != 0xffffffffu;
}
