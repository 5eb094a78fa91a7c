//! Every struct that crosses to the GPU has the same size and field offsets in Rust as in its
//! WGSL declaration, as naga lays the WGSL out. Needs no GPU.

use naga::proc::Layouter;
use ppm_core::bsdf::{BsdfCase, BsdfOutcome, Transport};
use ppm_core::layout::*;
use ppm_core::update::gather::{Found, GatherCase, SlotState};
use ppm_core::update::pairing::PAIRED_DEPOSITS;
use ppm_core::{camera_move, direct_light, local_move};
use std::mem::{offset_of, size_of};

const LAYOUT_WGSL: &str = include_str!("../shaders/shared/layout.wgsl");
const BSDF_WGSL: &str = include_str!("../shaders/shared/bsdf.wgsl");
const RNG_WGSL: &str = include_str!("../shaders/shared/rng.wgsl");
const LOCAL_MOVE_WGSL: &str = include_str!("../shaders/shared/local_move.wgsl");
const DIRECT_LIGHT_WGSL: &str = include_str!("../shaders/shared/direct_light.wgsl");
const SCREEN_COVER_WGSL: &str = include_str!("../shaders/shared/screen_cover.wgsl");
const CAMERA_MOVE_WGSL: &str = include_str!("../shaders/shared/camera_move.wgsl");
const BVH_WGSL: &str = include_str!("../shaders/shared/bvh.wgsl");
const KEPT_PATHS_WGSL: &str = include_str!("../shaders/shared/kept_paths.wgsl");

/// Span, alignment and (member name, offset) list of the WGSL struct `name`, declared in
/// layout.wgsl or in the assembled pass shaders.
fn wgsl_struct(name: &str) -> (u32, u32, Vec<(String, u32)>) {
    let source = std::iter::once(LAYOUT_WGSL)
        .chain(backend_wgpu::shaders::ALL.iter().map(|(_, s)| *s))
        .find(|s| s.contains(&format!("struct {name} {{")))
        .unwrap_or_else(|| panic!("no shader declares struct {name}"));
    let module = naga::front::wgsl::parse_str(source).expect("shader parses");
    let mut layouter = Layouter::default();
    layouter
        .update(module.to_ctx())
        .expect("layout.wgsl lays out");
    for (handle, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name)
            && let naga::TypeInner::Struct { members, span } = &ty.inner
        {
            let fields = members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                .collect();
            return (*span, layouter[handle].alignment.round_up(1), fields);
        }
    }
    panic!("the shader declares no struct {name}");
}

macro_rules! same_layout {
    ($ty:ident { $($field:ident),* $(,)? }) => {{
        let (span, align, wgsl) = wgsl_struct(stringify!($ty));
        let rust: Vec<(String, u32)> = vec![$((stringify!($field).to_owned(), offset_of!($ty, $field) as u32)),*];
        assert_eq!(wgsl, rust, "{}: member offsets", stringify!($ty));
        assert_eq!(span as usize, size_of::<$ty>(), "{}: size", stringify!($ty));
        // An array of the WGSL struct strides by its size rounded up to its alignment: the
        // Rust Vec strides by size_of, so the size must already be a multiple of it.
        assert_eq!(span % align, 0, "{}: size is not a multiple of the WGSL alignment {align}", stringify!($ty));
    }};
}

#[test]
fn buffer_elements_match_their_wgsl_twins() {
    same_layout!(HitPoint {
        position,
        pixel,
        normal,
        material,
        throughput,
        r2,
        tau,
        n,
        direct,
        emitted,
        iterations,
        flags,
        eye_met,
        correction_r2,
        discounted,
        _pad
    });
    same_layout!(Photon {
        position,
        path,
        power,
        normal_oct
    });
    same_layout!(GpuTriangle {
        v0,
        material,
        e1,
        object,
        e2,
        light,
        normal,
        group
    });
    same_layout!(BvhNode {
        min,
        first,
        max,
        count
    });
    same_layout!(GpuMaterial {
        albedo,
        kind,
        emission,
        ior,
        eta,
        alpha,
        k,
        texture,
        coat_internal,
        coat_nonlinear,
        coat_specular_weight,
        alpha_v,
        coat_transmittance
    });
    same_layout!(GpuTexture {
        first,
        width,
        height,
        nearest,
        scale,
        offset
    });
    same_layout!(GpuTriangleUv {
        uv0,
        uv1,
        uv2,
        _pad
    });
    same_layout!(ChainLight {
        radiance,
        emission_weight
    });
    same_layout!(GpuBounds {
        min,
        _pad0,
        max,
        _pad1
    });
    same_layout!(GpuLight {
        v0,
        area,
        e1,
        cdf,
        e2,
        pdf,
        normal,
        material
    });
    same_layout!(GpuCamera {
        eye,
        width,
        forward,
        height,
        right,
        _pad0,
        up,
        _pad1
    });
}

#[test]
fn the_gather_rule_s_structs_match_their_wgsl_twins() {
    same_layout!(SlotState {
        tau,
        n,
        pending,
        r2,
        emitted,
        flags,
        discounted
    });
    same_layout!(Found {
        flux,
        count,
        weight,
        power_sq,
        _pad
    });
    same_layout!(GatherCase {
        slot,
        found,
        reflectance,
        r2_initial,
        params
    });
}

#[test]
fn the_bsdf_s_test_structs_match_their_wgsl_twins() {
    same_layout!(BsdfCase {
        material,
        incoming,
        front,
        facing,
        u_lobe,
        u_direction,
        transport,
        u_dir,
        _pad
    });
    same_layout!(BsdfOutcome {
        dir,
        pdf,
        weight,
        transmitted,
        f_cos,
        pdf_of_dir,
        glossy_f_cos,
        glossy_pdf
    });
}

#[test]
fn pass_parameters_match_their_wgsl_twins() {
    same_layout!(EyePassParams {
        seed,
        spp,
        max_depth,
        iteration,
        r2_initial,
        ray_epsilon,
        flags,
        rest_at
    });
    same_layout!(DirectLightParams {
        seed,
        samples,
        iteration,
        ray_epsilon,
        accumulate,
        _pad0,
        _pad1,
        _pad2
    });
    same_layout!(PhotonPassParams {
        seed,
        pass_index,
        photon_count,
        max_depth,
        first_hit,
        ray_epsilon,
        power_scale,
        first_path,
        flags,
        mask_offset,
        gather_kind,
        gather_r2_floor
    });
    same_layout!(GatherParams {
        alpha,
        emitted_increment,
        kind,
        region_photons
    });
    same_layout!(GridParams {
        cell_size,
        bucket_count,
        photon_count,
        _pad0
    });
    same_layout!(GridPhoton {
        position,
        cell,
        power,
        normal_oct
    });
    same_layout!(PathDeposits {
        deposits,
        normal_oct,
        slots
    });
    same_layout!(ResolveParams {
        width,
        height,
        spp,
        _pad0
    });
    same_layout!(LocalMoveParams {
        seed,
        groups,
        max_depth,
        ray_epsilon,
        r2_initial,
        r2_floor,
        widest,
        direct_samples,
        objects,
        lights,
        _pad0,
        _pad1
    });
    same_layout!(CameraMoveParams {
        before,
        after,
        spp,
        _pad0,
        _pad1,
        _pad2
    });
}

#[test]
fn dynamic_pass_structs_match_their_wgsl_twins() {
    use backend_wgpu::layout::UpdateParams;
    same_layout!(EmissionRegion {
        light_point,
        mode,
        origin,
        _pad1,
        edge_u,
        area,
        edge_v,
        _pad0
    });
    same_layout!(RecordedPath {
        origin,
        light,
        direction,
        _pad0
    });
    same_layout!(GuidedEmission {
        cos_cone,
        beta,
        paths,
        weighted
    });
    same_layout!(Emitter {
        kind,
        _pad0,
        _pad1,
        _pad2,
        region,
        guide
    });
    same_layout!(UpdateParams {
        epsilon,
        _pad0,
        _pad1,
        _pad2
    });
}

#[test]
fn backend_kernel_parameters_match_their_wgsl_twins() {
    use backend_wgpu::layout::{GridBuildParams, ScanParams, SceneIndex};
    same_layout!(SceneIndex {
        triangles,
        nodes,
        lights,
        movers,
        light_count,
        mover_count,
        uvs,
        textures
    });
    same_layout!(ScanParams {
        count,
        _pad0,
        _pad1,
        _pad2
    });
    same_layout!(GridBuildParams {
        photon_count,
        bucket_count,
        hit_point_count,
        r2_floor,
        held,
        leave_out,
        _pad1,
        _pad2
    });
}

#[test]
fn local_move_structs_match_their_wgsl_twins() {
    use backend_wgpu::layout::{
        CoverCase, CoverOutcome, CoverParams, ListParams, MoveDecisionCase, MoveDecisionOutcome,
    };
    same_layout!(CoverParams {
        to_camera,
        eye,
        triangles,
        width,
        height,
        objects,
        _pad0
    });
    same_layout!(MoveDecisionCase {
        boxes,
        position,
        covered,
        eye,
        eye_met,
        flags,
        groups,
        r2_floor,
        widest,
        objects,
        lights,
        _pad0,
        _pad1
    });
    same_layout!(MoveDecisionOutcome {
        meets,
        flags,
        view,
        correction_r2
    });
    same_layout!(CoverCase {
        cover,
        v0,
        _pad0,
        v1,
        _pad1,
        v2,
        _pad2
    });
    same_layout!(CoverOutcome { words });
    same_layout!(ListParams {
        count,
        known,
        focus,
        _pad0
    });
}

#[test]
fn camera_move_structs_match_their_wgsl_twins() {
    use backend_wgpu::layout::{InheritCase, InheritOutcome};
    same_layout!(InheritCase {
        slot,
        bounds,
        request
    });
    same_layout!(InheritOutcome {
        slot,
        bounds,
        inherited,
        _pad0,
        _pad1,
        _pad2
    });
}

/// The value of the WGSL constant `name` of type `ty`, declared in one of `sources`.
fn wgsl_constant<'a>(sources: &[&'a str], name: &str, ty: &str) -> &'a str {
    let line = sources
        .iter()
        .flat_map(|s| s.lines())
        .find(|l| l.starts_with(&format!("const {name}: {ty} = ")))
        .unwrap_or_else(|| panic!("no shared WGSL module declares {name}: {ty}"));
    line.rsplit("= ").next().unwrap().trim_end_matches(';')
}

/// The WGSL constants that mirror Rust constants carry the same values.
#[test]
fn shared_constants_agree() {
    for (name, value) in [
        ("MATERIAL_DIFFUSE", material_kind::DIFFUSE),
        ("MATERIAL_MIRROR", material_kind::MIRROR),
        ("MATERIAL_GLASS", material_kind::GLASS),
        ("MATERIAL_CONDUCTOR", material_kind::CONDUCTOR),
        ("MATERIAL_COATED", material_kind::COATED),
        ("TRANSPORT_RADIANCE", Transport::Radiance as u32),
        ("EYE_GLASS_DIM", ppm_core::rng::EYE_GLASS_DIM),
        ("EYE_GLOSSY_DIM", ppm_core::rng::EYE_GLOSSY_DIM),
        ("EYE_LIGHT_DIM", ppm_core::rng::EYE_LIGHT_DIM),
        ("TRANSPORT_IMPORTANCE", Transport::Importance as u32),
        ("HIT_VALID", hit_flags::VALID),
        ("HIT_FRONT", hit_flags::FRONT),
        ("HIT_UPDATED", hit_flags::UPDATED),
        ("HIT_RESTING", hit_flags::RESTING),
        ("HIT_EYE_CHAINED", hit_flags::EYE_CHAINED),
        ("HIT_OBJECT_SHIFT", hit_flags::OBJECT_SHIFT),
        ("EYE_KEEP_STATISTICS", eye_flags::KEEP_STATISTICS),
        ("EYE_JITTER", eye_flags::JITTER),
        ("EYE_FOCUS", eye_flags::FOCUS),
        ("EYE_RECORD_BOUNDS", eye_flags::RECORD_BOUNDS),
        ("EYE_RETRACE", eye_flags::RETRACE),
        ("EYE_SAMPLE_LIGHTS", eye_flags::SAMPLE_LIGHTS),
        ("PHOTON_CHANGED_ONLY", photon_flags::CHANGED_ONLY),
        ("PHOTON_RECORD_CROSSED", photon_flags::RECORD_CROSSED),
        ("PHOTON_CULL_UNCROSSED", photon_flags::CULL_UNCROSSED),
        ("PHOTON_KEEP_PATHS", photon_flags::KEEP_PATHS),
        ("PHOTON_RECORD_DEPOSITS", photon_flags::RECORD_DEPOSITS),
        ("PHOTON_PAIR_DEPOSITS", photon_flags::PAIR_DEPOSITS),
        ("PAIRED_DEPOSITS", PAIRED_DEPOSITS as u32),
        ("NO_MATERIAL", NO_MATERIAL),
        ("FIRST_HIT_SKIP", first_hit::SKIP),
        ("FIRST_HIT_DEPOSIT", first_hit::DEPOSIT),
        ("REGION_AREA", region_mode::AREA),
        ("REGION_POINT", region_mode::POINT),
        ("EMISSION_ORDINARY", emission_kind::ORDINARY),
        ("EMISSION_REGION", emission_kind::REGION),
        ("EMISSION_GUIDED", emission_kind::GUIDED),
        ("GATHER_ORDINARY", gather_kind::ORDINARY),
        ("GATHER_REGION_NEGATIVE", gather_kind::REGION_NEGATIVE),
        ("GATHER_REGION_POSITIVE", gather_kind::REGION_POSITIVE),
        ("GATHER_GUIDED", gather_kind::GUIDED),
        ("GATHER_REGION_APPLY", gather_kind::REGION_APPLY),
        ("GATHER_KIND_MASK", gather_kind::KIND_MASK),
        ("GATHER_RAW_COUNT", gather_kind::RAW_COUNT),
        ("GATHER_DEFERRED", gather_kind::DEFERRED),
        ("GATHER_ADD_FLUX", gather_kind::ADD_FLUX),
        ("HIT_DIRECT_MAY_CHANGE", hit_flags::DIRECT_MAY_CHANGE),
        ("PROBE_PATHS", local_move::PROBE_PATHS),
        ("PROBE_SEED", local_move::PROBE_SEED),
        ("CHANGE_SEED", local_move::CHANGE_SEED),
        ("MOST_SAMPLES", local_move::MOST_SAMPLES),
        ("PAIR_LIGHT_POINT", direct_light::PAIR_LIGHT_POINT),
        ("PAIR_DIRECTION", direct_light::PAIR_DIRECTION),
        ("PAIR_LIGHT_CHOICE", direct_light::PAIR_LIGHT_CHOICE),
        ("RAYS_PER_SAMPLE", direct_light::RAYS_PER_SAMPLE),
        ("OBJECT_GROUPS", ppm_core::compile::OBJECT_GROUPS as u32),
        ("KEPT_SEGMENTS", backend_wgpu::KEPT_SEGMENTS),
        (
            "PHOTON_MARK_CANCELLED",
            backend_wgpu::layout::PHOTON_MARK_CANCELLED,
        ),
    ] {
        let sources = [
            LAYOUT_WGSL,
            BSDF_WGSL,
            RNG_WGSL,
            LOCAL_MOVE_WGSL,
            DIRECT_LIGHT_WGSL,
            CAMERA_MOVE_WGSL,
            KEPT_PATHS_WGSL,
        ];
        let literal = wgsl_constant(&sources, name, "u32").trim_end_matches('u');
        let parsed = match literal.strip_prefix("0x") {
            Some(hex) => u32::from_str_radix(hex, 16).unwrap(),
            None => literal.parse().unwrap(),
        };
        assert_eq!(parsed, value, "{name}");
    }
    for (name, value) in [
        ("CORRECTION_SPREAD", local_move::CORRECTION_SPREAD),
        ("PAIR_FLOOR", ppm_core::update::pairing::PAIR_FLOOR),
        ("SMOOTH_ALPHA", ppm_core::bsdf::SMOOTH_ALPHA),
        ("F32_MAX", f32::MAX),
        ("F32_MIN_POSITIVE", f32::MIN_POSITIVE),
        ("COVER_EPSILON", f32::EPSILON),
        ("NORMAL_COS", camera_move::NORMAL_COS),
        ("GRAZING_COS", camera_move::GRAZING_COS),
        ("BOX_SLACK", ppm_core::trace::BOX_SLACK),
    ] {
        let sources = [
            LAYOUT_WGSL,
            BSDF_WGSL,
            LOCAL_MOVE_WGSL,
            SCREEN_COVER_WGSL,
            CAMERA_MOVE_WGSL,
            BVH_WGSL,
        ];
        let literal = wgsl_constant(&sources, name, "f32");
        assert_eq!(literal.parse::<f32>().unwrap(), value, "{name}");
    }
}
