//! Four paths' rays against the scene's spheres and quads at once: one path per SIMD lane.
//!
//! The integrator keeps four camera paths of a pixel in flight. Their rays are independent, so
//! instead of testing each ray against each shape with 3-wide dot products (a shuffle and two
//! additions per dot), the four rays are packed by coordinate (structure of arrays) and each
//! shape is tested against all four in one pass of 4-wide arithmetic. Each lane does exactly
//! the scalar test's operations in the same order (`Sphere::intersect`, `Quad::intersect`:
//! dot products summed as (x + y) + z, the same square root and division, the same
//! comparisons, NaNs missing), and IEEE arithmetic is the same per lane as in a scalar
//! register, so every lane finds the same distance bits and, taking shapes in the scalar
//! order and replacing only on a strictly closer hit, the same shape as
//! `Geometry::nearest_shape`. Tested against it below.

use glam::{BVec4A, Vec3A, Vec4};

use super::geometry::{Geometry, Prim, Quad, Sphere, T_MIN};
use super::lanes::{dot, splat};

/// Four rays by coordinate: lane `k` is ray `k`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayPack {
    o: [Vec4; 3],
    d: [Vec4; 3],
}

/// `t > T_MIN && t < tmax`, lane-wise (false for a NaN).
#[inline(always)]
fn in_range(t: Vec4, tmax: Vec4) -> BVec4A {
    t.cmpgt(Vec4::splat(T_MIN)) & t.cmplt(tmax)
}

#[inline(always)]
fn in_unit(x: Vec4) -> BVec4A {
    x.cmpge(Vec4::ZERO) & x.cmple(Vec4::ONE)
}

impl RayPack {
    /// The rays `o[k] + t d[k]`.
    #[inline(always)]
    pub(crate) fn new(o: [Vec3A; 4], d: [Vec3A; 4]) -> Self {
        let axis = |v: &[Vec3A; 4], a: usize| Vec4::new(v[0][a], v[1][a], v[2][a], v[3][a]);
        Self {
            o: [axis(&o, 0), axis(&o, 1), axis(&o, 2)],
            d: [axis(&d, 0), axis(&d, 1), axis(&d, 2)],
        }
    }

    /// `Sphere::intersect` lane by lane: the distance, or infinity for a miss.
    #[inline(always)]
    fn sphere(&self, s: &Sphere, tmax: Vec4) -> Vec4 {
        let c = splat(s.center);
        let oc = [self.o[0] - c[0], self.o[1] - c[1], self.o[2] - c[2]];
        let b = dot(&oc, &self.d);
        let l = [
            oc[0] - b * self.d[0],
            oc[1] - b * self.d[1],
            oc[2] - b * self.d[2],
        ];
        let disc = Vec4::splat(s.radius * s.radius) - dot(&l, &l);
        // A negative (or NaN) discriminant gives a NaN root, which both range tests reject.
        let root = disc.sqrt();
        let t0 = -b - root;
        let t1 = -b + root;
        let first = in_range(t0, tmax);
        let second = in_range(t1, tmax);
        let miss = disc.cmplt(Vec4::ZERO);
        let t = Vec4::select(first, t0, Vec4::select(second, t1, Vec4::INFINITY));
        Vec4::select(miss, Vec4::INFINITY, t)
    }

    /// `Quad::intersect` lane by lane: the distance, or infinity for a miss.
    #[inline(always)]
    fn quad(&self, q: &Quad, tmax: Vec4) -> Vec4 {
        let n = splat(q.normal);
        let denom = dot(&n, &self.d);
        let num = Vec4::splat(q.plane_d()) - dot(&n, &self.o);
        let mut hit = denom.abs().cmpge(Vec4::splat(1e-12)) & (num * denom).cmpgt(Vec4::ZERO);
        if !hit.any() {
            return Vec4::INFINITY;
        }
        let t = num / denom;
        hit &= in_range(t, tmax);
        let origin = splat(q.origin);
        let p = [
            (self.o[0] + t * self.d[0]) - origin[0],
            (self.o[1] + t * self.d[1]) - origin[1],
            (self.o[2] + t * self.d[2]) - origin[2],
        ];
        hit &= in_unit(dot(&p, &splat(q.a_axis()))) & in_unit(dot(&p, &splat(q.b_axis())));
        Vec4::select(hit, t, Vec4::INFINITY)
    }

    /// For each ray, `Geometry::nearest_shape` without packed quads and `tmax` infinite: the
    /// closest sphere or quad and its distance (infinity and None for none), bit for bit.
    #[inline(always)]
    pub(crate) fn nearest_shape(&self, geo: &Geometry) -> [(f32, Option<Prim>); 4] {
        let mut best = Vec4::INFINITY;
        // The shape found per lane as a float code: -1 none, i a sphere, spheres + i a quad
        // (integers are exact in f32 up to 2^24 shapes, far beyond these scenes).
        let mut code = Vec4::splat(-1.0);
        let mut at = 0.0f32;
        for s in &geo.spheres {
            let t = self.sphere(s, best);
            let closer = t.cmplt(best);
            best = Vec4::select(closer, t, best);
            code = Vec4::select(closer, Vec4::splat(at), code);
            at += 1.0;
        }
        for q in &geo.quads {
            let t = self.quad(q, best);
            let closer = t.cmplt(best);
            best = Vec4::select(closer, t, best);
            code = Vec4::select(closer, Vec4::splat(at), code);
            at += 1.0;
        }
        let spheres = geo.spheres.len();
        let (best, code) = (best.to_array(), code.to_array());
        std::array::from_fn(|k| {
            let prim = (code[k] >= 0.0).then(|| {
                let i = code[k] as usize;
                if i < spheres {
                    Prim::Sphere(i as u32)
                } else {
                    Prim::Quad((i - spheres) as u32)
                }
            });
            (best[k], prim)
        })
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn four_paths_in_lanes_find_what_each_finds_alone() {
        // Overlapping spheres (rays start inside some), a room of quads with one duplicated
        // (exact ties: the lower index must win) and one seen edge-on.
        let mut quads = Vec::new();
        for k in 0..6 {
            let f = k as f32;
            quads.push(Quad::new(
                Vec3::new(-2.0 + 0.3 * f, -1.0, -3.0 + 0.5 * f),
                Vec3::new(2.5, 0.2 * f, 0.1),
                Vec3::new(0.1 * f, 2.0, 0.7),
                k,
            ));
        }
        quads.push(quads[2]);
        quads.push(Quad::new(Vec3::ZERO, Vec3::X, Vec3::Y, 9));
        let geo = Geometry {
            quads,
            spheres: vec![
                Sphere::new(Vec3::new(0.5, 0.0, -1.0), 0.6, 20),
                Sphere::new(Vec3::new(0.8, 0.2, -1.2), 0.5, 21),
                Sphere::new(Vec3::new(-1.0, 1.0, 2.0), 1.5, 22),
            ],
            ..Default::default()
        };
        let mut rng = crate::render::rng::Sampler::new(4, 5, 6);
        let mut found = [0usize; 4];
        for _ in 0..20_000 {
            let ray = |rng: &mut crate::render::rng::Sampler| {
                let (a, b) = rng.next_2d();
                let (c, e) = rng.next_2d();
                let o = Vec3A::new(6.0 * a - 3.0, 4.0 * b - 2.0, 3.0 * c - 0.5);
                // Some rays lie in the edge-on quad's plane (z = 0) and run along it.
                let o = if e < 0.05 {
                    o * Vec3A::new(1.0, 1.0, 0.0)
                } else {
                    o
                };
                let aim = Vec3A::new(
                    4.0 * e - 2.0,
                    3.0 * a - 1.5,
                    if e < 0.05 { 0.0 } else { -3.0 },
                );
                (o, (aim - o).normalize())
            };
            let rays: [(Vec3A, Vec3A); 4] = std::array::from_fn(|_| ray(&mut rng));
            let pack = RayPack::new(rays.map(|r| r.0), rays.map(|r| r.1));
            let lanes = pack.nearest_shape(&geo);
            for ((o, d), (t, prim)) in rays.into_iter().zip(lanes) {
                let (t1, prim1) = geo.nearest_shape(None, o, d, f32::INFINITY);
                assert_eq!((t.to_bits(), prim), (t1.to_bits(), prim1), "{o} {d}");
                found[match prim {
                    None => 0,
                    Some(Prim::Sphere(_)) => 1,
                    Some(Prim::Quad(6)) => 3,
                    Some(_) => 2,
                }] += 1;
            }
        }
        // Misses, spheres and quads all seen; the duplicate never wins its tie.
        assert!(found[..3].iter().all(|&n| n > 1000), "{found:?}");
        assert_eq!(found[3], 0);
    }
}
