//! Shapes and ray-scene intersection.
//!
//! Analytic shapes (spheres, parallelograms, boxes) cover most scenes at a few dozen
//! instructions per test; triangle meshes live in an obvhs BVH built once and are moved by
//! transforming rays into the mesh's frame (instancing), so a new pose costs nothing.
//!
//! One file per kind of shape: `shapes.rs` (spheres, parallelograms), `boxes.rs` (rotated
//! boxes, box sets behind a BVH), `mesh.rs` (triangle meshes and their placed copies); this
//! file holds what a ray finds ([`Surface`]) and the scene's whole [`Geometry`].

mod boxes;
mod mesh;
mod shapes;
#[cfg(test)]
mod tests;

use boxes::box_face_normal;
pub use boxes::{AaBox, BoxSet, OrientedBox};
pub use mesh::{BvhKind, Mesh, MeshInstance};
pub use shapes::{Quad, Sphere};

use glam::{Vec2, Vec3A};

use super::lanes::QuadLanes;

/// Marks a surface that is not an area light.
pub const NO_LIGHT: u32 = u32::MAX;

/// Hits closer than this are self-intersections (origins are also offset along the normal).
pub(crate) const T_MIN: f32 = 1e-6;

/// obvhs's `Ray::new(o, d, T_MIN, tmax)`, the three inverse components in one 3-wide pass
/// instead of one by one: each lane is `safe_inverse`'s (`1 / x`, or `signum(x) / EPSILON` for
/// `|x| <= EPSILON`, where dividing by the power of two 2^-23 is the exact product with 2^23),
/// so the ray is the same bits (`bvh_ray_is_obvhs_ray`).
#[inline(always)]
pub(crate) fn bvh_ray(o: Vec3A, d: Vec3A, tmax: f32) -> obvhs::ray::Ray {
    let small = d.abs().cmple(Vec3A::splat(f32::EPSILON));
    let tiny = d.signum() * Vec3A::splat(1.0 / f32::EPSILON);
    obvhs::ray::Ray {
        origin: o,
        direction: d,
        inv_direction: Vec3A::select(small, tiny, Vec3A::ONE / d),
        tmin: T_MIN,
        tmax,
    }
}

/// A surface point found by a ray.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// Position.
    pub p: Vec3A,
    /// Unit geometric normal (outward for closed shapes; `u x v` for quads).
    pub n: Vec3A,
    /// Texture coordinates (quads only; zero elsewhere).
    pub uv: Vec2,
    /// Index into the scene's materials.
    pub material: u32,
    /// Emitted radiance on the front side (zero for non-emitters).
    pub emission: Vec3A,
    /// Index into the scene's area lights, or [`NO_LIGHT`].
    pub light: u32,
}

/// A shape found by a ray: its kind and index (a mesh's: instance, triangle).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Prim {
    Sphere(u32),
    Quad(u32),
    Box(u32),
    SetBox(u32),
    Tri(u32, u32),
}

/// Everything a ray can hit.
#[derive(Default)]
pub struct Geometry {
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Parallelograms (walls, floors, area lights).
    pub quads: Vec<Quad>,
    /// Rotated boxes, tested one by one (use a [`BoxSet`] for many).
    pub boxes: Vec<OrientedBox>,
    /// Many axis-aligned boxes behind a BVH.
    pub box_set: Option<BoxSet>,
    /// Placed meshes.
    pub instances: Vec<MeshInstance>,
}

impl Geometry {
    /// Closest surface along the unit-direction ray `o + t d`, `t` in (0, `tmax`).
    #[inline]
    pub fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<(f32, Surface)> {
        self.intersect_in(None, o, d, tmax)
    }

    /// [`Geometry::intersect`] with the quads tested four at a time from `lanes`
    /// (`QuadLanes::pack(&self.quads)`) when given: the same answer, bit for bit.
    #[inline]
    pub(crate) fn intersect_in(
        &self,
        lanes: Option<&[QuadLanes]>,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
    ) -> Option<(f32, Surface)> {
        self.intersect_after(self.nearest_shape(lanes, o, d, tmax), o, d)
    }

    /// [`Geometry::intersect_in`] given its first part, `shape`: the closest sphere or quad and
    /// its distance as [`Geometry::nearest_shape`] finds them (or the range's end and None).
    #[inline(always)]
    pub(crate) fn intersect_after(
        &self,
        shape: (f32, Option<Prim>),
        o: Vec3A,
        d: Vec3A,
    ) -> Option<(f32, Surface)> {
        let (best, prim) = self.nearest_rest(o, d, shape.0, shape.1);
        let prim = prim?;
        let p = o + best * d;
        let mut surface = Surface {
            p,
            n: Vec3A::Z,
            uv: Vec2::ZERO,
            material: 0,
            emission: Vec3A::ZERO,
            light: NO_LIGHT,
        };
        match prim {
            Prim::Sphere(i) => {
                let s = &self.spheres[i as usize];
                surface.n = (p - s.center) / s.radius;
                surface.material = s.material;
            }
            Prim::Quad(i) => {
                let q = &self.quads[i as usize];
                surface.n = q.normal;
                surface.uv = q.uv(p);
                surface.material = q.material;
                if q.normal.dot(d) < 0.0 {
                    surface.emission = q.emission;
                }
                surface.light = q.light;
            }
            Prim::Box(i) => {
                let b = &self.boxes[i as usize];
                surface.n = b.normal(p);
                surface.material = b.material;
            }
            Prim::SetBox(i) => {
                // `box_set` is Some whenever a SetBox was recorded.
                if let Some(set) = &self.box_set {
                    let b = &set.boxes[i as usize];
                    let center = 0.5 * (b.min + b.max);
                    surface.n = box_face_normal(p - center, 0.5 * (b.max - b.min));
                    surface.material = b.material;
                }
            }
            Prim::Tri(k, tri) => {
                let inst = &self.instances[k as usize];
                surface.n = (inst.rotation * inst.mesh.tris[tri as usize].compute_normal())
                    .normalize_or(Vec3A::Z);
                surface.material = inst.material;
            }
        }
        Some((best, surface))
    }

    /// The closest sphere or quad on the ray before `tmax` (quads four at a time from `lanes`
    /// when given): the first part of [`Geometry::intersect_in`], with its order and ties.
    #[inline(always)]
    pub(super) fn nearest_shape(
        &self,
        lanes: Option<&[QuadLanes]>,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
    ) -> (f32, Option<Prim>) {
        let mut best = tmax;
        let mut prim = None;
        for (i, s) in self.spheres.iter().enumerate() {
            let t = s.intersect(o, d, best);
            if t < best {
                best = t;
                prim = Some(Prim::Sphere(i as u32));
            }
        }
        match lanes {
            Some(lanes) => {
                for (g, group) in lanes.iter().enumerate() {
                    // Lane order is quad order: the lowest index wins a tie, as below.
                    for (k, t) in group.intersect(o, d, best).into_iter().enumerate() {
                        if t < best {
                            best = t;
                            prim = Some(Prim::Quad((4 * g + k) as u32));
                        }
                    }
                }
            }
            None => {
                for (i, q) in self.quads.iter().enumerate() {
                    let t = q.intersect(o, d, best);
                    if t < best {
                        best = t;
                        prim = Some(Prim::Quad(i as u32));
                    }
                }
            }
        }
        (best, prim)
    }

    /// The rest of [`Geometry::intersect_in`] after [`Geometry::nearest_shape`]: boxes, the box
    /// set and meshes, each hit replacing (`best`, `prim`) only when strictly closer.
    #[inline(always)]
    fn nearest_rest(
        &self,
        o: Vec3A,
        d: Vec3A,
        mut best: f32,
        mut prim: Option<Prim>,
    ) -> (f32, Option<Prim>) {
        for (i, b) in self.boxes.iter().enumerate() {
            let t = b.intersect(o, d, best);
            if t < best {
                best = t;
                prim = Some(Prim::Box(i as u32));
            }
        }
        if let Some(set) = &self.box_set {
            if let Some((t, id)) = set.closest(o, d, best) {
                best = t;
                prim = Some(Prim::SetBox(id));
            }
        }
        for (k, inst) in self.instances.iter().enumerate() {
            let lo = inst.inverse * (o - inst.translation);
            let ld = inst.inverse * d;
            if let Some((t, tri)) = inst.mesh.intersect(lo, ld, best) {
                best = t;
                prim = Some(Prim::Tri(k as u32, tri));
            }
        }
        (best, prim)
    }

    /// Whether a box, a box of the set or a mesh lies on the ray before `tmax`: the shapes
    /// [`Geometry::nearest_rest`] looks at, as shadow-ray queries.
    #[inline(always)]
    pub(super) fn rest_occluded(&self, o: Vec3A, d: Vec3A, tmax: f32) -> bool {
        if self.boxes.iter().any(|b| b.intersect(o, d, tmax) < tmax) {
            return true;
        }
        if let Some(set) = &self.box_set {
            if set.occluded(o, d, tmax) {
                return true;
            }
        }
        self.instances.iter().any(|inst| {
            let lo = inst.inverse * (o - inst.translation);
            let ld = inst.inverse * d;
            inst.mesh.occluded(lo, ld, tmax)
        })
    }

    /// Whether any surface lies on the ray `o + t d` for `t` in (0, `tmax`) (shadow rays).
    #[inline]
    pub fn occluded(&self, o: Vec3A, d: Vec3A, tmax: f32) -> bool {
        self.occluded_in(None, o, d, tmax)
    }

    /// [`Geometry::occluded`] with the quads tested four at a time from `lanes` when given.
    #[inline]
    pub(crate) fn occluded_in(
        &self,
        lanes: Option<&[QuadLanes]>,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
    ) -> bool {
        let quad_hit = match lanes {
            Some(lanes) => lanes
                .iter()
                .any(|g| g.intersect(o, d, tmax).iter().any(|&t| t < tmax)),
            None => self.quads.iter().any(|q| q.intersect(o, d, tmax) < tmax),
        };
        // The boxes, the set and the meshes are [`Geometry::rest_occluded`]'s, written out
        // again: calling it here makes the render loop compile differently and SHADOW slower
        // (see benches/render.rs), for the same answers.
        if quad_hit
            || self.spheres.iter().any(|s| s.intersect(o, d, tmax) < tmax)
            || self.boxes.iter().any(|b| b.intersect(o, d, tmax) < tmax)
        {
            return true;
        }
        if let Some(set) = &self.box_set {
            if set.occluded(o, d, tmax) {
                return true;
            }
        }
        self.instances.iter().any(|inst| {
            let lo = inst.inverse * (o - inst.translation);
            let ld = inst.inverse * d;
            inst.mesh.occluded(lo, ld, tmax)
        })
    }
}
