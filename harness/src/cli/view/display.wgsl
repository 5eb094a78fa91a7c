// Draws one pane of the viewer: the resolved image (RGB f32 triples, rows from the top, as the
// resolve pass writes them) at one image pixel per window pixel, scaled by the exposure and
// sRGB-encoded exactly as `ppm render` writes its PNG, with the heat map of the slots the last
// move reset laid over it in red.

struct Pane {
    // Top-left window pixel of the pane.
    origin: vec2<u32>,
    // Image width and height.
    size: vec2<u32>,
    exposure: f32,
    // 1: lay the heat map over the image.
    heat: u32,
    // 1: encode sRGB here (a UNORM target); 0: the target's format encodes it.
    encode: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> pane: Pane;
@group(0) @binding(1) var<storage, read> image: array<f32>;
// Per pixel, the share of its slots the last move reset.
@group(0) @binding(2) var<storage, read> reset: array<f32>;

// One triangle covering the viewport.
@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(xy * 2.0 - 1.0, 0.0, 1.0);
}

// ppm_core::image::srgb_encode: NaN shows black, the rest is clamped to [0, 1].
fn srgb_encode(v: f32) -> f32 {
    var x = 0.0;
    if v == v {
        x = clamp(v, 0.0, 1.0);
    }
    if x <= 0.0031308 {
        return 12.92 * x;
    }
    if x >= 1.0 {
        return 1.0;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let x = u32(at.x) - pane.origin.x;
    let y = u32(at.y) - pane.origin.y;
    if x >= pane.size.x || y >= pane.size.y {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let i = y * pane.size.x + x;
    let linear = vec3<f32>(image[3u * i], image[3u * i + 1u], image[3u * i + 2u]) * pane.exposure;
    var rgb = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    if pane.encode == 1u {
        rgb = vec3<f32>(srgb_encode(linear.x), srgb_encode(linear.y), srgb_encode(linear.z));
    }
    if pane.heat == 1u {
        rgb = mix(rgb, vec3<f32>(1.0, 0.0, 0.0), 0.6 * clamp(reset[i], 0.0, 1.0));
    }
    return vec4<f32>(rgb, 1.0);
}
