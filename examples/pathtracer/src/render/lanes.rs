//! Quads tested four at a time: the scene's parallelograms packed one per SIMD lane.
//!
//! A room (OCCLUSION, GI, CAUSTIC) is mostly quads, and every ray tested them one by one.
//! Packed by coordinate (structure of arrays), four quads cost one pass of 4-wide arithmetic.
//! Each lane does exactly the scalar test's operations in the same order (`Quad::intersect`:
//! dot products summed as (x + y) + z, the same division, the same comparisons), and IEEE
//! arithmetic is the same per lane as in scalar registers, so the distances are the same bits
//! and the closest hit is the same quad (the lowest index among equal distances, as the
//! scalar loop keeps). Tested against the scalar loop in `geometry`'s tests.

use glam::{BVec4A, Vec3A, Vec4};

use super::geometry::{Quad, T_MIN};

/// Four quads' ray-test data, one quad per lane. Lanes past the last quad have a zero normal,
/// which the `|denom| >= 1e-12` test turns into a miss.
#[derive(Clone, Copy, Debug)]
pub struct QuadLanes {
    n: [Vec4; 3],
    plane_d: Vec4,
    origin: [Vec4; 3],
    a_axis: [Vec4; 3],
    b_axis: [Vec4; 3],
}

/// Lane-wise `a.x * b.x + a.y * b.y + a.z * b.z`, summed in glam's order for `Vec3A::dot`.
#[inline(always)]
pub(super) fn dot(a: &[Vec4; 3], b: &[Vec4; 3]) -> Vec4 {
    (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]
}

/// `v` in every lane, by coordinate.
#[inline(always)]
pub(super) fn splat(v: Vec3A) -> [Vec4; 3] {
    [Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z)]
}

#[inline(always)]
fn in_unit(x: Vec4) -> BVec4A {
    x.cmpge(Vec4::ZERO) & x.cmple(Vec4::ONE)
}

impl QuadLanes {
    /// `quads` packed four per group, in order (quad `4 g + k` is lane `k` of group `g`).
    pub fn pack(quads: &[Quad]) -> Vec<QuadLanes> {
        quads
            .chunks(4)
            .map(|group| {
                let lane = |f: &dyn Fn(&Quad) -> f32| {
                    let mut v = [0.0f32; 4];
                    for (x, q) in v.iter_mut().zip(group) {
                        *x = f(q);
                    }
                    Vec4::from_array(v)
                };
                let vec = |f: &dyn Fn(&Quad) -> Vec3A| {
                    [lane(&|q| f(q).x), lane(&|q| f(q).y), lane(&|q| f(q).z)]
                };
                QuadLanes {
                    n: vec(&|q| q.normal),
                    plane_d: lane(&|q| q.plane_d()),
                    origin: vec(&|q| q.origin),
                    a_axis: vec(&|q| q.a_axis()),
                    b_axis: vec(&|q| q.b_axis()),
                }
            })
            .collect()
    }

    /// The four distances of `Quad::intersect` (infinity for a miss), lane by lane.
    #[inline(always)]
    pub fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> [f32; 4] {
        let (o4, d4) = (splat(o), splat(d));
        let denom = dot(&self.n, &d4);
        let num = self.plane_d - dot(&self.n, &o4);
        let t = num / denom;
        let mut hit = denom.abs().cmpge(Vec4::splat(1e-12))
            & (num * denom).cmpgt(Vec4::ZERO)
            & t.cmpgt(Vec4::splat(T_MIN))
            & t.cmplt(Vec4::splat(tmax));
        if !hit.any() {
            return [f32::INFINITY; 4];
        }
        let q = [
            (o4[0] + t * d4[0]) - self.origin[0],
            (o4[1] + t * d4[1]) - self.origin[1],
            (o4[2] + t * d4[2]) - self.origin[2],
        ];
        hit &= in_unit(dot(&q, &self.a_axis)) & in_unit(dot(&q, &self.b_axis));
        Vec4::select(hit, t, Vec4::INFINITY).to_array()
    }
}
