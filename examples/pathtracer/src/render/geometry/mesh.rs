//! Triangle meshes in their own BVH, and their placed copies (instancing).

use std::sync::Arc;

use glam::{Affine3A, Mat3A, Vec3, Vec3A};
use obvhs::{
    bvh2::Bvh2,
    cwbvh::{builder::build_cwbvh_from_tris, CwBvh},
    ray::{Ray as BvhRay, RayHit},
    triangle::Triangle,
    BvhBuildParams,
};

use super::super::packed::PackedMesh;

/// Which BVH a mesh uses (all built by obvhs; the fastest is the default, see the bench).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhKind {
    /// Binary BVH, collapsed to a 4-wide tree with triangles tested four at a time
    /// (`render/packed.rs`): obvhs's answers, bit for bit up to exact ties.
    Bvh2,
    /// The same binary BVH traversed by obvhs itself (the reference for the bench).
    Bvh2Obvhs,
    /// Compressed 8-wide BVH, traversed four nodes at a time with SIMD.
    CwBvh,
}

pub(super) enum Accel {
    /// A Bvh2 re-laid for faster queries with obvhs's answers.
    Packed(PackedMesh),
    Bvh2(Bvh2),
    CwBvh(CwBvh),
}

/// A triangle ready for ray tests: obvhs's Möller-Trumbore test (`Triangle::intersect`) with
/// its edges and their cross product computed once instead of per test. Every operation of
/// the test is the same, in the same order, so the distances are the same bits.
#[derive(Clone, Copy, Debug)]
pub(super) struct PreparedTriangle {
    pub(super) v0: Vec3A,
    /// `v0 - v1`.
    pub(super) e1: Vec3A,
    /// `v2 - v0`.
    pub(super) e2: Vec3A,
    /// `e1 x e2`.
    pub(super) n: Vec3A,
}

impl PreparedTriangle {
    pub(super) fn new(t: &Triangle) -> Self {
        let e1 = t.v0 - t.v1;
        let e2 = t.v2 - t.v0;
        Self {
            v0: t.v0,
            e1,
            e2,
            n: e1.cross(e2),
        }
    }

    /// (v0, e1, e2, n), as [`PackedMesh`] takes them.
    pub(super) fn parts(&self) -> [Vec3A; 4] {
        [self.v0, self.e1, self.e2, self.n]
    }

    /// Distance along `ray` (in [tmin, tmax]) or infinity: `Triangle::intersect` of obvhs 0.4.
    #[inline(always)]
    pub(super) fn intersect(&self, ray: &BvhRay) -> f32 {
        let c = self.v0 - ray.origin;
        let r = ray.direction.cross(c);
        let inv_det = 1.0 / self.n.dot(ray.direction);
        let u = r.dot(self.e2) * inv_det;
        let v = r.dot(self.e1) * inv_det;
        let w = 1.0 - u - v;
        // A hit needs u, v, w all >= 0 (sign bits clear; -0.0 counts as a miss, as in obvhs).
        let signs = u.to_bits() | v.to_bits() | w.to_bits();
        if inv_det != 0.0 && signs & 0x8000_0000 == 0 {
            let t = self.n.dot(c) * inv_det;
            if t >= ray.tmin && t <= ray.tmax {
                return t;
            }
        }
        f32::INFINITY
    }
}

/// A triangle mesh in its own frame, with its BVH.
pub struct Mesh {
    /// Triangles, in BVH primitive order.
    pub(super) tris: Vec<Triangle>,
    /// The same triangles prepared for ray tests.
    pub(super) prepared: Vec<PreparedTriangle>,
    pub(super) accel: Accel,
}

impl Mesh {
    /// Builds the mesh's BVH (medium-quality preset: built once per task).
    pub fn new(tris: &[Triangle], kind: BvhKind) -> Self {
        let mut unused = std::time::Duration::default();
        let params = BvhBuildParams::medium_build();
        let (accel, order) = match kind {
            BvhKind::Bvh2 | BvhKind::Bvh2Obvhs => {
                let bvh = obvhs::bvh2::builder::build_bvh2_from_tris(tris, params, &mut unused);
                let order = bvh.primitive_indices.clone();
                (Accel::Bvh2(bvh), order)
            }
            BvhKind::CwBvh => {
                let bvh = build_cwbvh_from_tris(tris, params, &mut unused);
                let order = bvh.primitive_indices.clone();
                (Accel::CwBvh(bvh), order)
            }
        };
        let tris: Vec<Triangle> = order.iter().map(|&i| tris[i as usize]).collect();
        let prepared: Vec<PreparedTriangle> = tris.iter().map(PreparedTriangle::new).collect();
        // The default re-lays the Bvh2 for its own traversal, from the triangles just prepared.
        let accel = match accel {
            Accel::Bvh2(bvh) if kind == BvhKind::Bvh2 => {
                let parts: Vec<[Vec3A; 4]> = prepared.iter().map(PreparedTriangle::parts).collect();
                PackedMesh::new(&bvh, &parts).map_or(Accel::Bvh2(bvh), Accel::Packed)
            }
            other => other,
        };
        Self {
            tris,
            prepared,
            accel,
        }
    }

    /// The triangles, in the mesh's frame (in the BVH's order).
    pub fn triangles(&self) -> &[Triangle] {
        &self.tris
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Whether the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Closest hit (distance, triangle) of a ray given in the mesh's frame.
    #[inline(always)]
    pub fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<(f32, u32)> {
        let ray = super::bvh_ray(o, d, tmax);
        let mut hit = RayHit::none();
        let tris = &self.prepared;
        let found = match &self.accel {
            Accel::Packed(p) => return p.closest(ray),
            Accel::Bvh2(b) => b.ray_traverse(ray, &mut hit, |r, id| tris[id].intersect(r)),
            Accel::CwBvh(b) => b.ray_traverse(ray, &mut hit, |r, id| tris[id].intersect(r)),
        };
        found.then_some((hit.t, hit.primitive_id))
    }

    /// Whether anything lies on the ray before `tmax` (ray in the mesh's frame).
    #[inline(always)]
    pub fn occluded(&self, o: Vec3A, d: Vec3A, tmax: f32) -> bool {
        let ray = super::bvh_ray(o, d, tmax);
        let tris = &self.prepared;
        let miss = match &self.accel {
            Accel::Packed(p) => return p.any(ray),
            Accel::Bvh2(b) => b.ray_traverse_miss(ray, |r, id| tris[id].intersect(r)),
            Accel::CwBvh(b) => b.ray_traverse_miss(ray, |r, id| tris[id].intersect(r)),
        };
        !miss
    }
}

/// A placed copy of a mesh: rigid motion (rotation, then translation).
#[derive(Clone)]
pub struct MeshInstance {
    pub(super) mesh: Arc<Mesh>,
    pub(super) rotation: Mat3A,
    pub(super) inverse: Mat3A,
    pub(super) translation: Vec3A,
    /// Index into the scene's materials.
    pub material: u32,
}

impl MeshInstance {
    /// `mesh` rotated by `angle` radians about `axis` (through its origin), then moved by `translation`.
    pub fn new(mesh: Arc<Mesh>, axis: Vec3, angle: f32, translation: Vec3, material: u32) -> Self {
        let rotation = Mat3A::from_axis_angle(axis.normalize(), angle);
        Self {
            mesh,
            rotation,
            inverse: rotation.transpose(),
            translation: translation.into(),
            material,
        }
    }

    /// The placed mesh, in its own frame.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The rigid motion from the mesh's frame to the world.
    pub fn to_world(&self) -> Affine3A {
        Affine3A::from_mat3_translation(self.rotation.into(), self.translation.into())
    }
}
