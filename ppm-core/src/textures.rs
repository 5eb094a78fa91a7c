//! A compiled scene's textures, and the colour they give a surface point: what every backend
//! asks where a path meets a textured material (textures.wgsl is the WGSL twin).
//!
//! A texture scales its material's colour. Where a path bounces, the backends sample the
//! material with its colour scaled ([`SurfaceTextures::shaded`]); where an eye path stops,
//! the factor goes into the slot's throughput instead, so a slot keeps its material's index
//! and size while the gather and the direct-light pass, which read `f` from the material,
//! still weigh by the textured colour: a diffuse `f` is the colour over pi, linear in it.
//!
//! The same coordinates orient an anisotropic lobe: its tangent is the direction in which
//! `u` grows across the triangle ([`SurfaceTextures::frame`]), as in pbrt-v4 and Mitsuba 3.

use crate::bsdf::{self, is_anisotropic, visible_point_f};
use crate::geometry::Frame;
use crate::layout::{GpuMaterial, GpuTexture, GpuTriangle, GpuTriangleUv, material_kind};
use crate::scene::{Scene, Texture, sample};
use glam::{Vec2, Vec3};
use std::sync::Arc;

/// Texture coordinates, headers and texels of a scene, as the backends bind them; all empty
/// for a scene without textures or anisotropic materials, which then pays for none of it.
#[derive(Clone, Debug, Default)]
pub struct SurfaceTextures {
    /// Per triangle, in the triangle buffer's order; where the scene has a texture or an
    /// anisotropic material (zero on the triangles of any other material).
    pub uvs: Vec<GpuTriangleUv>,
    /// One per distinct texture; [`GpuMaterial::texture`] is one plus an index here.
    pub headers: Vec<GpuTexture>,
    /// Every texture's texels, one after the other (shared: moves do not change them).
    pub texels: Arc<Vec<[u32; 2]>>,
}

impl SurfaceTextures {
    /// Whether the scene has no texture.
    pub fn is_empty(&self) -> bool {
        self.headers.is_empty()
    }

    /// The factor on `material`'s colour at `position` on triangle `index` (`tri`): one
    /// where the material has no texture.
    #[inline]
    pub fn factor(
        &self,
        material: &GpuMaterial,
        index: u32,
        tri: &GpuTriangle,
        position: Vec3,
    ) -> Vec3 {
        if material.texture == 0 {
            return Vec3::ONE;
        }
        let uv = surface_uv(&self.uvs[index as usize], tri, position);
        sample(
            &self.headers[material.texture as usize - 1],
            &self.texels,
            uv,
        )
    }

    /// The frame of `material`'s lobe on triangle `index` (`tri`) seen from the side of
    /// `facing` ([`bsdf::frame`]): an anisotropic lobe's tangent is the triangle's
    /// [`u_direction`].
    #[inline]
    pub fn frame(
        &self,
        material: &GpuMaterial,
        index: u32,
        tri: &GpuTriangle,
        facing: Vec3,
    ) -> Frame {
        bsdf::frame(material, facing, || {
            u_direction(&self.uvs[index as usize], tri)
        })
    }

    /// `material` with its colour scaled by its texture at the point, and the factor that
    /// takes the untextured material's [`visible_point_f`] to the textured one's: the
    /// texture's factor itself, but where a coat returns light to its base several times
    /// (`coat_nonlinear`), where `f` is not linear in the colour.
    #[inline]
    pub fn shaded(
        &self,
        material: &GpuMaterial,
        index: u32,
        tri: &GpuTriangle,
        position: Vec3,
    ) -> (GpuMaterial, Vec3) {
        let factor = self.factor(material, index, tri, position);
        let shaded = GpuMaterial {
            albedo: (Vec3::from(material.albedo) * factor).into(),
            ..*material
        };
        if material.kind != material_kind::COATED || material.coat_nonlinear == 0 {
            return (shaded, factor);
        }
        let (f, base) = (visible_point_f(&shaded), visible_point_f(material));
        let ratio = Vec3::select(base.cmpgt(Vec3::ZERO), f / base, Vec3::ZERO);
        (shaded, ratio)
    }
}

/// The texture coordinates at `position` on `tri`, interpolated from its vertices' by the
/// point's barycentric coordinates (recovered from the position: the hit tests return only
/// the distance).
#[inline]
pub fn surface_uv(uv: &GpuTriangleUv, tri: &GpuTriangle, position: Vec3) -> Vec2 {
    let (e1, e2) = (Vec3::from(tri.e1), Vec3::from(tri.e2));
    let w = position - Vec3::from(tri.v0);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (dw1, dw2) = (w.dot(e1), w.dot(e2));
    let det = d11 * d22 - d12 * d12;
    let (b1, b2) = if det > 0.0 {
        ((d22 * dw1 - d12 * dw2) / det, (d11 * dw2 - d12 * dw1) / det)
    } else {
        (0.0, 0.0)
    };
    let uv0 = Vec2::from(uv.uv0);
    uv0 + (Vec2::from(uv.uv1) - uv0) * b1 + (Vec2::from(uv.uv2) - uv0) * b2
}

/// The direction in which `u` grows across `tri` (pbrt-v4's `dpdu`, up to its length): from
/// `p = v0 + e1 s + e2 t` and `uv = uv0 + du1 s + du2 t`, the direction along which `v`
/// stays put is `du2.y e1 - du1.y e2`, turned to point where `u` grows. The first edge where
/// the coordinates give no direction (two vertices with the same `v` are enough for one).
#[inline]
pub fn u_direction(uv: &GpuTriangleUv, tri: &GpuTriangle) -> Vec3 {
    let (e1, e2) = (Vec3::from(tri.e1), Vec3::from(tri.e2));
    let uv0 = Vec2::from(uv.uv0);
    let (du1, du2) = (Vec2::from(uv.uv1) - uv0, Vec2::from(uv.uv2) - uv0);
    let det = du1.x * du2.y - du1.y * du2.x;
    if det == 0.0 || !det.is_finite() {
        return e1;
    }
    (e1 * du2.y - e2 * du1.y) * det.signum()
}

/// pbrt-v4's coordinates for a triangle given none.
const DEFAULT_UVS: [Vec2; 3] = [Vec2::ZERO, Vec2::X, Vec2::ONE];

/// The textures of `scene`, its triangles numbered as `compile_scene` numbers them (objects
/// in order) and put in buffer order by `order`; the materials' texture fields set.
pub(crate) fn compile_textures(
    scene: &Scene,
    order: &[u32],
    materials: &mut [GpuMaterial],
) -> SurfaceTextures {
    let mut distinct: Vec<&Arc<Texture>> = Vec::new();
    for (material, gpu) in scene.materials.iter().zip(materials.iter_mut()) {
        let Some(texture) = &material.texture else {
            continue;
        };
        let index = match distinct.iter().position(|t| Arc::ptr_eq(t, texture)) {
            Some(i) => i,
            None => {
                distinct.push(texture);
                distinct.len() - 1
            }
        };
        gpu.texture = index as u32 + 1;
    }
    let anisotropic = materials.iter().any(is_anisotropic);
    if distinct.is_empty() && !anisotropic {
        return SurfaceTextures::default();
    }
    let mut headers = Vec::with_capacity(distinct.len());
    let mut texels = Vec::new();
    for t in distinct {
        headers.push(GpuTexture {
            first: texels.len() as u32,
            ..crate::scene::gpu_texture(t)
        });
        texels.extend_from_slice(&t.texels);
    }
    // Coordinates on a material neither textured nor anisotropic are never read: zero, so
    // that two scenes that differ only there compile alike.
    let numbered: Vec<GpuTriangleUv> = scene
        .objects
        .iter()
        .flat_map(|o| {
            let read = scene.materials[o.material].texture.is_some()
                || is_anisotropic(&materials[o.material]);
            (0..o.triangles.len()).map(move |i| read.then(|| o.uvs.get(i).unwrap_or(&DEFAULT_UVS)))
        })
        .map(|uv| match uv {
            Some(uv) => GpuTriangleUv {
                uv0: uv[0].into(),
                uv1: uv[1].into(),
                uv2: uv[2].into(),
                _pad: [0; 2],
            },
            None => GpuTriangleUv::default(),
        })
        .collect();
    SurfaceTextures {
        uvs: order.iter().map(|&p| numbered[p as usize]).collect(),
        headers,
        texels: Arc::new(texels),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::compile_scene;
    use crate::scene::{Material, MaterialKind, Object, TextureFilter};

    /// A unit quad in the z = 0 plane with a 2x1 texture, black on the left, white on the right.
    fn quad_scene() -> Scene {
        let texture = Texture::from_linear(
            "halves",
            2,
            1,
            &[Vec3::ZERO, Vec3::ONE],
            TextureFilter::Nearest,
        )
        .unwrap();
        let quad = [
            [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)],
            [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        ];
        let mut scene = crate::scene::testing::room(Vec::new());
        scene.materials = vec![Material {
            texture: Some(Arc::new(texture)),
            ..Material::new(
                "floor",
                MaterialKind::Diffuse {
                    albedo: Vec3::splat(0.5),
                },
            )
        }];
        scene.objects = vec![Object {
            name: "floor".into(),
            material: 0,
            triangles: quad.to_vec(),
            uvs: quad
                .iter()
                .map(|t| t.map(|v| Vec2::new(v.x, v.y)))
                .collect(),
        }];
        scene
    }

    #[test]
    fn a_hit_reads_its_texel_through_the_bvh_order() {
        let compiled = compile_scene(&quad_scene(), 4, 4);
        let t = &compiled.textures;
        assert_eq!(t.uvs.len(), compiled.triangles.len());
        assert_eq!(compiled.materials[0].texture, 1);
        for (i, tri) in compiled.triangles.iter().enumerate() {
            for (p, expected) in [
                (Vec3::new(0.2, 0.6, 0.0), 0.0),
                (Vec3::new(0.8, 0.3, 0.0), 1.0),
            ] {
                // Only the triangle that holds the point is asked about it.
                let b = surface_uv(&t.uvs[i], tri, p);
                if (0.0..=1.0).contains(&b.x) && (0.0..=1.0).contains(&b.y) {
                    let (shaded, factor) = t.shaded(&compiled.materials[0], i as u32, tri, p);
                    assert_eq!(factor, Vec3::splat(expected));
                    assert_eq!(Vec3::from(shaded.albedo), Vec3::splat(0.5 * expected));
                    assert_relative_eq_uv(b, p);
                }
            }
        }
    }

    fn assert_relative_eq_uv(uv: Vec2, p: Vec3) {
        assert!((uv - Vec2::new(p.x, p.y)).length() < 1e-6, "{uv} at {p}");
    }

    /// The tangent is where `u` grows: for coordinates that project the triangle's points
    /// on any direction of its plane, that direction; for pbrt-v4's default coordinates, or
    /// coordinates that give none, the first edge.
    #[test]
    fn the_u_direction_is_where_u_grows() {
        let (a, b, c) = (
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(1.4, -0.2, 0.5),
            Vec3::new(0.3, 1.1, -0.4),
        );
        let tri = crate::compile::gpu_triangle(&[a, b, c], 0, 0);
        let n = Vec3::from(tri.normal);
        let uvs = |f: &dyn Fn(Vec3) -> Vec2| GpuTriangleUv {
            uv0: f(a).into(),
            uv1: f(b).into(),
            uv2: f(c).into(),
            _pad: [0; 2],
        };
        for s in [Vec3::X, Vec3::Y, Vec3::new(0.5, -2.0, 1.0)] {
            let s = (s - n * n.dot(s)).normalize();
            let t = n.cross(s);
            for flip in [1.0, -1.0] {
                // v along -t as well: the tangent does not depend on v's orientation.
                let uv = uvs(&|p: Vec3| Vec2::new(p.dot(s) + 3.0, flip * p.dot(t)));
                let d = u_direction(&uv, &tri).normalize();
                assert!((d - s).length() < 1e-5, "{d} against {s}");
            }
        }
        let default = uvs(&|p: Vec3| DEFAULT_UVS[[a, b, c].iter().position(|&q| q == p).unwrap()]);
        let e1 = Vec3::from(tri.e1);
        assert!((u_direction(&default, &tri).normalize() - e1.normalize()).length() < 1e-6);
        assert_eq!(u_direction(&uvs(&|_| Vec2::ONE), &tri), e1);
    }

    #[test]
    fn untextured_scenes_carry_no_texture_data() {
        let mut scene = quad_scene();
        scene.materials[0].texture = None;
        let compiled = compile_scene(&scene, 4, 4);
        assert!(compiled.textures.is_empty() && compiled.textures.uvs.is_empty());
        assert!(!compiled.features.textured);
    }
}
