// BVH traversal over the flattened obvhs nodes, with a fixed-size stack. Needs the bindings
// `nodes` and `triangles` in the importing pass. The CPU backend traverses the same tree with
// obvhs itself; only ties between equal distances can resolve differently.

const STACK_SIZE: u32 = 64u;

struct Hit {
    t: f32,
    triangle: u32,
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

// Nearest triangle with 0 < t < tmax; `triangle` is 0xffffffff on a miss.
fn trace_closest(origin: vec3<f32>, dir: vec3<f32>, tmax: f32, any_hit: bool) -> Hit {
    var hit = Hit(tmax, 0xffffffffu);
    if arrayLength(&nodes) == 0u {
        return hit;
    }
    let inv_dir = vec3<f32>(safe_inverse(dir.x), safe_inverse(dir.y), safe_inverse(dir.z));
    var stack: array<u32, STACK_SIZE>;
    var sp = 1u;
    stack[0] = 0u;
    while sp > 0u {
        sp--;
        let node = nodes[stack[sp]];
        if ray_box(origin, inv_dir, node.min, node.max) >= hit.t {
            continue;
        }
        if node.count > 0u {
            for (var i = node.first; i < node.first + node.count; i++) {
                let t = intersect_triangle(origin, dir, triangles[i], 0.0, hit.t);
                if t < hit.t {
                    hit = Hit(t, i);
                    if any_hit {
                        return hit;
                    }
                }
            }
            continue;
        }
        let left = nodes[node.first];
        let right = nodes[node.first + 1u];
        let t_left = ray_box(origin, inv_dir, left.min, left.max);
        let t_right = ray_box(origin, inv_dir, right.min, right.max);
        // Push the far child first so the near one is visited first.
        let near = select(node.first + 1u, node.first, t_left <= t_right);
        let far = select(node.first, node.first + 1u, t_left <= t_right);
        let t_near = min(t_left, t_right);
        let t_far = max(t_left, t_right);
        if t_far < hit.t && sp < STACK_SIZE {
            stack[sp] = far;
            sp++;
        }
        if t_near < hit.t && sp < STACK_SIZE {
            stack[sp] = near;
            sp++;
        }
    }
    return hit;
}

fn closest_hit(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> Hit {
    return trace_closest(origin, dir, tmax, false);
}

fn occluded(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> bool {
    return trace_closest(origin, dir, tmax, true).triangle != 0xffffffffu;
}
