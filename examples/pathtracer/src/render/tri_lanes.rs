//! A mesh leaf's triangles tested four at a time: one triangle per SIMD lane.
//!
//! obvhs's medium build puts up to 8 triangles in a leaf, and each Möller-Trumbore test is a
//! chain of products, a division and comparisons. Packed by coordinate, four triangles cost
//! one pass. Each lane does exactly the operations of the scalar test (`PreparedTriangle::
//! intersect`, itself obvhs's `Triangle::intersect`) in the same order: glam's cross product
//! `a.y * b.z - a.z * b.y` (and so on), dot products summed as (x + y) + z, `w = (1 - u) - v`,
//! the same sign-bit test (-0.0 and NaNs with the sign set are misses). So every lane's
//! distance is the scalar test's, bit for bit, and the caller keeps the scalar loop's order.

use glam::{Vec3A, Vec4};

/// Up to four triangles, one per lane: a corner, the two edges and their cross product, as in
/// `PreparedTriangle`. Lanes past the leaf's last triangle repeat it (their answers are
/// ignored).
#[derive(Clone, Copy, Debug)]
pub struct TriLanes {
    v0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
    n: [Vec4; 3],
    /// Primitive index of lane 0 (lane k is `first + k`).
    first: u32,
    /// Lanes that hold a triangle of the leaf (1 to 4).
    len: u32,
}

/// The ray, splat per axis for the lane tests.
pub struct RayLanes {
    o: [Vec4; 3],
    d: [Vec4; 3],
}

impl RayLanes {
    /// Origin `o`, direction `d`.
    #[inline(always)]
    pub fn new(o: Vec3A, d: Vec3A) -> Self {
        let splat = |v: Vec3A| [Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z)];
        Self {
            o: splat(o),
            d: splat(d),
        }
    }
}

/// Lane-wise `a . b` summed as glam's `Vec3A::dot`: (x + y) + z.
#[inline(always)]
fn dot(a: &[Vec4; 3], b: &[Vec4; 3]) -> Vec4 {
    (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]
}

impl TriLanes {
    /// Packs triangles `first..first + len` (len 1 to 4), each given as (v0, e1, e2, e1 x e2).
    pub fn pack(first: u32, tris: &[[Vec3A; 4]]) -> Self {
        let last = tris.len() - 1;
        let lane = |part: usize, axis: usize| {
            Vec4::from_array(std::array::from_fn(|k| tris[k.min(last)][part][axis]))
        };
        let vec = |part: usize| [lane(part, 0), lane(part, 1), lane(part, 2)];
        Self {
            v0: vec(0),
            e1: vec(1),
            e2: vec(2),
            n: vec(3),
            first,
            len: tris.len() as u32,
        }
    }

    /// Primitive index of lane 0.
    #[inline(always)]
    pub fn first(&self) -> u32 {
        self.first
    }

    /// The scalar test's distances before its range check: (lane distances, bitmask of the
    /// lanes that hit at a distance >= `tmin`). A lane's hit then counts if its distance is
    /// below the ray's current tmax, exactly as the scalar test followed by `t < tmax`.
    #[inline(always)]
    pub fn distances(&self, ray: &RayLanes, tmin: f32) -> ([f32; 4], u32) {
        let (o, d) = (&ray.o, &ray.d);
        let c = [self.v0[0] - o[0], self.v0[1] - o[1], self.v0[2] - o[2]];
        // d x c, as glam's cross.
        let r = [
            d[1] * c[2] - d[2] * c[1],
            d[2] * c[0] - d[0] * c[2],
            d[0] * c[1] - d[1] * c[0],
        ];
        let inv_det = Vec4::ONE / dot(&self.n, d);
        let u = dot(&r, &self.e2) * inv_det;
        let v = dot(&r, &self.e1) * inv_det;
        let w = Vec4::ONE - u - v;
        let negative = u.is_negative_bitmask() | v.is_negative_bitmask() | w.is_negative_bitmask();
        let t = dot(&self.n, &c) * inv_det;
        let valid = inv_det.cmpne(Vec4::ZERO).bitmask() & t.cmpge(Vec4::splat(tmin)).bitmask();
        let lanes = (1u32 << self.len) - 1;
        (t.to_array(), valid & !negative & lanes)
    }
}
