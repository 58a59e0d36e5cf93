//! Boxes: one rotated box tested alone, many axis-aligned boxes behind a BVH.

use glam::{Affine3A, Mat3A, Vec3, Vec3A};
use obvhs::{
    aabb::Aabb,
    bvh2::{builder::build_bvh2, Bvh2},
    ray::{Ray as BvhRay, RayHit},
    BvhBuildParams,
};

use super::super::pairs::PairBvh;
use super::T_MIN;

/// A box rotated by `rotation` about its centre.
#[derive(Clone, Copy, Debug)]
pub struct OrientedBox {
    pub(super) center: Vec3A,
    pub(super) half: Vec3A,
    /// Local to world.
    pub(super) rotation: Mat3A,
    /// World to local.
    pub(super) inverse: Mat3A,
    /// Squared radius of a sphere about `center` that holds the box with room to spare (see
    /// [`OrientedBox::surely_missed`]).
    pub(super) reach2: f32,
    /// Squared distance from `center` within which a ray origin may be for the sphere
    /// test to decide a miss (see [`OrientedBox::surely_missed`]).
    pub(super) near2: f32,
    /// Index into the scene's materials.
    pub material: u32,
}

impl OrientedBox {
    /// A box with half extents `half` at `center`, turned by `angle` radians about `axis`.
    pub fn new(center: Vec3, half: Vec3, axis: Vec3, angle: f32, material: u32) -> Self {
        let rotation = Mat3A::from_axis_angle(axis.normalize(), angle);
        Self {
            center: center.into(),
            half: half.into(),
            rotation,
            inverse: rotation.transpose(),
            reach2: (1.001 * half.length()).powi(2),
            near2: (100.0 * half.length()).powi(2),
            material,
        }
    }

    /// Whether the unit-direction ray from `o` along `d` passes so far from the box that the
    /// slab test cannot report a hit: its line misses a sphere 0.1 % wider than the box's
    /// circumscribed sphere. No division, no rotation: most rays in GI's room miss both boxes,
    /// and the exact test then need not run. Decided only for origins within 100 half
    /// diagonals of the centre, where the rounding of both computations (about 1e-7 of the
    /// distance to the centre, so 1e-5 of the half diagonal) is far below the 0.1 % margin:
    /// the answer, a miss, is the slab test's.
    #[inline(always)]
    pub(super) fn surely_missed(&self, o: Vec3A, d: Vec3A) -> bool {
        let oc = o - self.center;
        let off_line = oc - oc.dot(d) * d;
        off_line.length_squared() > self.reach2 && oc.length_squared() < self.near2
    }

    #[inline(always)]
    pub(super) fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        if self.surely_missed(o, d) {
            return f32::INFINITY;
        }
        self.slab_test(o, d, tmax)
    }

    /// The exact test: the ray in the box's frame against its slabs.
    #[inline(always)]
    pub(super) fn slab_test(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let lo = self.inverse * (o - self.center);
        let ld = self.inverse * d;
        slab(lo, ld.recip(), -self.half, self.half, tmax)
    }

    /// The map from the cube [-1, 1]^3 onto the box (scale by the half extents, rotate,
    /// move to the centre).
    pub fn to_world(&self) -> Affine3A {
        Affine3A::from_mat3_translation(
            (self.rotation * Mat3A::from_diagonal(self.half.into())).into(),
            self.center.into(),
        )
    }

    pub(super) fn normal(&self, p: Vec3A) -> Vec3A {
        let local = self.inverse * (p - self.center);
        self.rotation * box_face_normal(local, self.half)
    }
}

/// The outward normal of the face of a centred box (half extents `half`) nearest `local`.
#[inline(always)]
pub(super) fn box_face_normal(local: Vec3A, half: Vec3A) -> Vec3A {
    let r = local.abs() / half;
    if r.x >= r.y && r.x >= r.z {
        Vec3A::new(local.x.signum(), 0.0, 0.0)
    } else if r.y >= r.z {
        Vec3A::new(0.0, local.y.signum(), 0.0)
    } else {
        Vec3A::new(0.0, 0.0, local.z.signum())
    }
}

/// Ray/axis-aligned box distance, or infinity.
#[inline(always)]
pub(super) fn slab(o: Vec3A, inv_d: Vec3A, min: Vec3A, max: Vec3A, tmax: f32) -> f32 {
    let t1 = (min - o) * inv_d;
    let t2 = (max - o) * inv_d;
    let tn = t1.min(t2).max_element();
    let tf = t1.max(t2).min_element();
    if tn <= tf && tf > T_MIN && tn < tmax {
        if tn > T_MIN {
            tn
        } else {
            tf
        }
    } else {
        f32::INFINITY
    }
}

/// An axis-aligned box of a [`BoxSet`].
#[derive(Clone, Copy, Debug)]
pub struct AaBox {
    /// Minimum corner.
    pub min: Vec3A,
    /// Maximum corner.
    pub max: Vec3A,
    /// Index into the scene's materials.
    pub material: u32,
}

/// Many axis-aligned boxes in their own small BVH, rebuilt when the boxes move (SORT).
pub struct BoxSet {
    pub(super) boxes: Vec<AaBox>,
    pub(super) bvh: Bvh2,
    /// The same tree laid out for faster traversal (None if too deep for it).
    pub(super) pairs: Option<PairBvh>,
}

impl BoxSet {
    /// Builds the BVH (PLOC, fastest preset: a rebuild per render must stay cheap).
    pub fn new(boxes: &[AaBox]) -> Self {
        let aabbs: Vec<Aabb> = boxes.iter().map(|b| Aabb::new(b.min, b.max)).collect();
        let mut unused = std::time::Duration::default();
        let bvh = build_bvh2(&aabbs, BvhBuildParams::fastest_build(), &mut unused);
        let boxes = bvh
            .primitive_indices
            .iter()
            .map(|&i| boxes[i as usize])
            .collect();
        let pairs = PairBvh::new(&bvh);
        Self { boxes, bvh, pairs }
    }

    /// The boxes (in the BVH's order).
    pub fn boxes(&self) -> &[AaBox] {
        &self.boxes
    }

    /// The distance to box `id` along `r` before `r.tmax` (infinity for a miss): the
    /// primitive test of both queries.
    #[inline(always)]
    pub(super) fn hit(&self, r: &BvhRay, id: usize) -> f32 {
        let b = &self.boxes[id];
        slab(r.origin, r.inv_direction, b.min, b.max, r.tmax)
    }

    /// Closest (distance, box) on the ray before `tmax`.
    #[inline(always)]
    pub(super) fn closest(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<(f32, u32)> {
        let ray = super::bvh_ray(o, d, tmax);
        let test = |r: &BvhRay, id: usize| self.hit(r, id);
        if let Some(pairs) = &self.pairs {
            return pairs.closest(ray, test);
        }
        let mut hit = RayHit::none();
        self.bvh
            .ray_traverse(ray, &mut hit, test)
            .then_some((hit.t, hit.primitive_id))
    }

    /// Whether a box lies on the ray before `tmax`.
    #[inline(always)]
    pub(super) fn occluded(&self, o: Vec3A, d: Vec3A, tmax: f32) -> bool {
        let ray = super::bvh_ray(o, d, tmax);
        let test = |r: &BvhRay, id: usize| self.hit(r, id);
        match &self.pairs {
            Some(pairs) => pairs.any(ray, test),
            None => !self.bvh.ray_traverse_miss(ray, test),
        }
    }
}
