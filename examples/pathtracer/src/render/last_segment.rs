//! A path's last segment: only light can still be found there, so only what adds light is
//! looked for.
//!
//! At the last segment (`segments == max_depth`) the integrator used the full closest hit just
//! to read the emission of the surface found (area lights are emitting quads) or, on a miss, the
//! environment. Every other surface ends the path with nothing added. So the closest sphere or
//! quad is found exactly as [`Geometry::intersect_in`] finds it (same tests, same order, same
//! ties), and the other shapes (boxes, the box set, meshes) are asked only whether one of them
//! lies strictly before it, as a shadow-ray query: no mesh's closest hit, no surface built. A
//! closest-hit query and a shadow query over the same shapes and range agree on "something
//! there" (both run the same primitive and box tests with the same range until the first hit),
//! so the answer, and the distance an emitter is found at, are the same bits as before.

use glam::Vec3A;

use super::geometry::{Geometry, Prim};

/// What a path's last ray finds, as far as light is concerned.
#[derive(Clone, Copy, Debug)]
pub(crate) enum LastHit {
    /// Nothing on the ray: the environment is seen.
    Miss,
    /// The emitting front side of quad `quad`, at distance `t`.
    Emitter {
        /// Distance along the ray.
        t: f32,
        /// Index into the geometry's quads.
        quad: u32,
    },
    /// A surface that emits nothing towards the ray.
    Dark,
}

impl Geometry {
    /// What the ray `o + t d`, `t` in (0, infinity), finds first, as
    /// [`Geometry::intersect_in`] would, reduced to whether it is light; `shape` is the closest
    /// sphere or quad on the ray as [`Geometry::nearest_shape`] finds it with an infinite range.
    #[inline(always)]
    pub(crate) fn last_hit_after(&self, shape: (f32, Option<Prim>), o: Vec3A, d: Vec3A) -> LastHit {
        match shape {
            (_, None) => {
                if self.rest_occluded(o, d, f32::INFINITY) {
                    LastHit::Dark
                } else {
                    LastHit::Miss
                }
            }
            (t, Some(Prim::Quad(i))) => {
                // `intersect_in` gives a quad's emission only on its front side, and keeps
                // it unless a later shape is strictly closer.
                let q = &self.quads[i as usize];
                let lit = q.emission != Vec3A::ZERO && q.normal.dot(d) < 0.0;
                if lit && !self.rest_occluded(o, d, t) {
                    LastHit::Emitter { t, quad: i }
                } else {
                    LastHit::Dark
                }
            }
            (_, Some(_)) => LastHit::Dark,
        }
    }
}
