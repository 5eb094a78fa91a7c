// Image textures (ppm_core::textures and ppm_core::scene::texture, step for step): the factor
// a material's texture puts on its colour at a surface point. Needs the bindings
// `scene_table`, `scene` (SceneIndex) and `scene_texels` (array<vec2<u32>>) in the importing
// pass, and tables.wgsl, scene.wgsl imported.

fn scene_texture(i: u32) -> GpuTexture {
    let a = scene_texel(scene.textures + 2u * i);
    let b = scene_texel(scene.textures + 2u * i + 1u);
    return GpuTexture(a.x, a.y, a.z, a.w, bitcast<vec2<f32>>(b.xy), bitcast<vec2<f32>>(b.zw));
}

fn scene_triangle_uv(i: u32) -> GpuTriangleUv {
    let a = scene_texel(scene.uvs + 2u * i);
    let b = scene_texel(scene.uvs + 2u * i + 1u);
    return GpuTriangleUv(bitcast<vec2<f32>>(a.xy), bitcast<vec2<f32>>(a.zw), bitcast<vec2<f32>>(b.xy), b.zw);
}

// An IEEE half float's value, built from its bits (unpack2x16float needs a capability
// baseline WebGPU does not promise): exact, as ppm_core's twin.
fn half_to_f32(h: u32) -> f32 {
    let exponent = (h >> 10u) & 0x1fu;
    let mantissa = h & 0x3ffu;
    if exponent == 0u {
        return f32(mantissa) * 5.9604644775390625e-8;
    }
    return bitcast<f32>(((exponent + 112u) << 23u) | (mantissa << 13u));
}

// Half floats: red and green in the first word, blue in the low half of the second.
fn texel_colour(first: u32, x: u32, y: u32, width: u32) -> vec3<f32> {
    let t = scene_texels[first + y * width + x];
    return vec3<f32>(half_to_f32(t.x & 0xffffu), half_to_f32(t.x >> 16u), half_to_f32(t.y & 0xffffu));
}

// floor(x) as an index in 0 .. n, for x in [0, n].
fn texture_index(x: f32, n: u32) -> u32 {
    return min(u32(max(x, 0.0)), n - 1u);
}

// The column or row a whole number in [-1, n] wraps to.
fn texture_wrap(i: f32, n: u32) -> u32 {
    if i < 0.0 {
        return n - 1u;
    }
    return min(u32(i), n) % n;
}

// x - floor(x) in [0, 1]; 0 where that is not a number in it.
fn texture_fraction(x: f32) -> f32 {
    let f = x - floor(x);
    return select(0.0, f, f >= 0.0 && f <= 1.0);
}

fn texture_sample(header: GpuTexture, uv: vec2<f32>) -> vec3<f32> {
    let st = header.scale * uv + header.offset;
    let s = texture_fraction(st.x);
    let t = 1.0 - texture_fraction(st.y);
    let w = header.width;
    let h = header.height;
    let x = s * f32(w);
    let y = t * f32(h);
    if header.nearest != 0u {
        return texel_colour(header.first, texture_index(x, w), texture_index(y, h), w);
    }
    let xc = x - 0.5;
    let yc = y - 0.5;
    let fx = xc - floor(xc);
    let fy = yc - floor(yc);
    let x0 = texture_wrap(floor(xc), w);
    let y0 = texture_wrap(floor(yc), h);
    let x1 = (x0 + 1u) % w;
    let y1 = (y0 + 1u) % h;
    let top = texel_colour(header.first, x0, y0, w) * (1.0 - fx) + texel_colour(header.first, x1, y0, w) * fx;
    let bottom = texel_colour(header.first, x0, y1, w) * (1.0 - fx) + texel_colour(header.first, x1, y1, w) * fx;
    return top * (1.0 - fy) + bottom * fy;
}

fn surface_uv(uv: GpuTriangleUv, tri: GpuTriangle, position: vec3<f32>) -> vec2<f32> {
    let w = position - tri.v0;
    let d11 = dot(tri.e1, tri.e1);
    let d12 = dot(tri.e1, tri.e2);
    let d22 = dot(tri.e2, tri.e2);
    let dw1 = dot(w, tri.e1);
    let dw2 = dot(w, tri.e2);
    let det = d11 * d22 - d12 * d12;
    var b = vec2<f32>(0.0);
    if det > 0.0 {
        b = vec2<f32>((d22 * dw1 - d12 * dw2) / det, (d11 * dw2 - d12 * dw1) / det);
    }
    return uv.uv0 + (uv.uv1 - uv.uv0) * b.x + (uv.uv2 - uv.uv0) * b.y;
}

// The direction in which u grows across tri, up to its length; the first edge where the
// coordinates give none (ppm_core::textures::u_direction).
fn u_direction(uv: GpuTriangleUv, tri: GpuTriangle) -> vec3<f32> {
    let du1 = uv.uv1 - uv.uv0;
    let du2 = uv.uv2 - uv.uv0;
    let det = du1.x * du2.y - du1.y * du2.x;
    if det == 0.0 || !is_finite_f32(det) {
        return tri.e1;
    }
    return (tri.e1 * du2.y - tri.e2 * du1.y) * sign(det);
}

// The frame of material's lobe on triangle index seen from the side of facing; an
// anisotropic lobe follows the triangle's coordinates (ppm_core::textures::SurfaceTextures::frame).
fn surface_frame(material: GpuMaterial, index: u32, tri: GpuTriangle, facing: vec3<f32>) -> Frame {
    if !bsdf_is_anisotropic(material) {
        return frame_around(facing);
    }
    return frame_with_tangent(facing, u_direction(scene_triangle_uv(index), tri));
}

// The factor on `material`'s colour at `position` on triangle `index`: one without a texture.
fn texture_factor(material: GpuMaterial, index: u32, tri: GpuTriangle, position: vec3<f32>) -> vec3<f32> {
    if material.texture == 0u {
        return vec3<f32>(1.0);
    }
    let uv = surface_uv(scene_triangle_uv(index), tri, position);
    return texture_sample(scene_texture(material.texture - 1u), uv);
}
