//! Shapes and ray-scene intersection.
//!
//! Analytic shapes (spheres, parallelograms, boxes) cover most scenes at a few dozen
//! instructions per test; triangle meshes live in an obvhs BVH built once and are moved by
//! transforming rays into the mesh's frame (instancing), so a new pose costs nothing.

use std::sync::Arc;

use super::lanes::QuadLanes;
use super::packed::PackedMesh;
use super::pairs::PairBvh;
use glam::{Affine3A, Mat3A, Vec2, Vec3, Vec3A};
use obvhs::{
    aabb::Aabb,
    bvh2::{builder::build_bvh2, Bvh2},
    cwbvh::{builder::build_cwbvh_from_tris, CwBvh},
    ray::{Ray as BvhRay, RayHit},
    triangle::Triangle,
    BvhBuildParams,
};

/// Marks a surface that is not an area light.
pub const NO_LIGHT: u32 = u32::MAX;

/// Hits closer than this are self-intersections (origins are also offset along the normal).
pub(crate) const T_MIN: f32 = 1e-6;

/// A sphere.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3A,
    /// Radius.
    pub radius: f32,
    /// Index into the scene's materials.
    pub material: u32,
}

impl Sphere {
    /// A sphere of `radius` at `center` made of `material`.
    pub fn new(center: Vec3, radius: f32, material: u32) -> Self {
        Self {
            center: center.into(),
            radius,
            material,
        }
    }

    #[inline(always)]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let oc = o - self.center;
        let b = oc.dot(d);
        // r^2 - |oc - b d|^2 rather than b^2 - (|oc|^2 - r^2): no cancellation for far rays.
        let l = oc - b * d;
        let disc = self.radius * self.radius - l.length_squared();
        if disc < 0.0 {
            return f32::INFINITY;
        }
        let s = disc.sqrt();
        let t0 = -b - s;
        if t0 > T_MIN && t0 < tmax {
            return t0;
        }
        let t1 = -b + s;
        if t1 > T_MIN && t1 < tmax {
            return t1;
        }
        f32::INFINITY
    }
}

/// A parallelogram `origin + a u + b v`, (a, b) in [0, 1]^2; its (a, b) are the texture uv.
/// Emitting quads are one-sided area lights facing `normal = normalize(u x v)`.
#[derive(Clone, Copy, Debug)]
pub struct Quad {
    /// One corner.
    pub origin: Vec3A,
    /// First edge.
    pub u: Vec3A,
    /// Second edge.
    pub v: Vec3A,
    /// Unit normal, `normalize(u x v)`.
    pub normal: Vec3A,
    /// Area, `|u x v|`.
    pub area: f32,
    plane_d: f32,
    /// Dotted with the in-plane offset, gives the `a` coordinate.
    a_axis: Vec3A,
    /// Dotted with the in-plane offset, gives the `b` coordinate.
    b_axis: Vec3A,
    /// Index into the scene's materials.
    pub material: u32,
    /// Emitted radiance (zero for non-emitters).
    pub emission: Vec3A,
    /// Index into the scene's area lights, or [`NO_LIGHT`].
    pub light: u32,
}

impl Quad {
    /// The parallelogram with corner `origin` and edges `u`, `v`.
    pub fn new(origin: Vec3, u: Vec3, v: Vec3, material: u32) -> Self {
        let (u, v): (Vec3A, Vec3A) = (u.into(), v.into());
        let cross = u.cross(v);
        let area = cross.length();
        let normal = cross / area;
        let w = cross / cross.length_squared();
        Self {
            origin: origin.into(),
            u,
            v,
            normal,
            area,
            plane_d: normal.dot(origin.into()),
            a_axis: v.cross(w),
            b_axis: w.cross(u),
            material,
            emission: Vec3A::ZERO,
            light: NO_LIGHT,
        }
    }

    /// The axis-aligned rectangle centred at `center` with edges `u`, `v` (full lengths).
    pub fn centered(center: Vec3, u: Vec3, v: Vec3, material: u32) -> Self {
        Self::new(center - 0.5 * u - 0.5 * v, u, v, material)
    }

    #[inline(always)]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let denom = self.normal.dot(d);
        if denom.abs() < 1e-12 {
            return f32::INFINITY;
        }
        let num = self.plane_d - self.normal.dot(o);
        // The plane behind the ray (or a NaN) is a miss before the division: t = num / denom
        // is then <= 0 or NaN, which the range test below rejects too (a product that
        // underflows to 0 needs |num| < 1e-33, so t < 1e-21 < T_MIN: also a miss). Same
        // answers, fewer divisions: about half of a room's walls are behind any ray.
        let in_front = num * denom > 0.0;
        if !in_front {
            return f32::INFINITY;
        }
        let t = num / denom;
        // Written so that a NaN t counts as a miss.
        let in_range = t > T_MIN && t < tmax;
        if !in_range {
            return f32::INFINITY;
        }
        let q = o + t * d - self.origin;
        let a = q.dot(self.a_axis);
        let b = q.dot(self.b_axis);
        if (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) {
            t
        } else {
            f32::INFINITY
        }
    }

    /// `normal . origin`: the plane is `normal . p = plane_d`.
    pub(crate) fn plane_d(&self) -> f32 {
        self.plane_d
    }

    /// Dotted with the in-plane offset from `origin`, gives the `a` coordinate.
    pub(crate) fn a_axis(&self) -> Vec3A {
        self.a_axis
    }

    /// Dotted with the in-plane offset from `origin`, gives the `b` coordinate.
    pub(crate) fn b_axis(&self) -> Vec3A {
        self.b_axis
    }

    #[inline(always)]
    fn uv(&self, p: Vec3A) -> Vec2 {
        let q = p - self.origin;
        Vec2::new(q.dot(self.a_axis), q.dot(self.b_axis))
    }

    /// The point at parallelogram coordinates (`a`, `b`).
    #[inline(always)]
    pub fn point(&self, a: f32, b: f32) -> Vec3A {
        self.origin + a * self.u + b * self.v
    }
}

/// A box rotated by `rotation` about its centre.
#[derive(Clone, Copy, Debug)]
pub struct OrientedBox {
    center: Vec3A,
    half: Vec3A,
    /// Local to world.
    rotation: Mat3A,
    /// World to local.
    inverse: Mat3A,
    /// Squared radius of a sphere about `center` that holds the box with room to spare (see
    /// [`OrientedBox::surely_missed`]).
    reach2: f32,
    /// Squared distance from `center` within which a ray origin may be for the sphere
    /// test to decide a miss (see [`OrientedBox::surely_missed`]).
    near2: f32,
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
    fn surely_missed(&self, o: Vec3A, d: Vec3A) -> bool {
        let oc = o - self.center;
        let off_line = oc - oc.dot(d) * d;
        off_line.length_squared() > self.reach2 && oc.length_squared() < self.near2
    }

    #[inline(always)]
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        if self.surely_missed(o, d) {
            return f32::INFINITY;
        }
        self.slab_test(o, d, tmax)
    }

    /// The exact test: the ray in the box's frame against its slabs.
    #[inline(always)]
    fn slab_test(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
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

    fn normal(&self, p: Vec3A) -> Vec3A {
        let local = self.inverse * (p - self.center);
        self.rotation * box_face_normal(local, self.half)
    }
}

/// The outward normal of the face of a centred box (half extents `half`) nearest `local`.
#[inline(always)]
fn box_face_normal(local: Vec3A, half: Vec3A) -> Vec3A {
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
fn slab(o: Vec3A, inv_d: Vec3A, min: Vec3A, max: Vec3A, tmax: f32) -> f32 {
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
    boxes: Vec<AaBox>,
    bvh: Bvh2,
    /// The same tree laid out for faster traversal (None if too deep for it).
    pairs: Option<PairBvh>,
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
    fn hit(&self, r: &BvhRay, id: usize) -> f32 {
        let b = &self.boxes[id];
        slab(r.origin, r.inv_direction, b.min, b.max, r.tmax)
    }

    /// Closest (distance, box) on the ray before `tmax`.
    #[inline(always)]
    fn closest(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<(f32, u32)> {
        let ray = BvhRay::new(o, d, T_MIN, tmax);
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
    fn occluded(&self, o: Vec3A, d: Vec3A, tmax: f32) -> bool {
        let ray = BvhRay::new(o, d, T_MIN, tmax);
        let test = |r: &BvhRay, id: usize| self.hit(r, id);
        match &self.pairs {
            Some(pairs) => pairs.any(ray, test),
            None => !self.bvh.ray_traverse_miss(ray, test),
        }
    }
}

/// Which BVH a mesh uses (all built by obvhs; the fastest is the default, see the bench).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhKind {
    /// Binary BVH, traversed in the pair layout with triangles tested four at a time
    /// (`render/packed.rs`): obvhs's answers, bit for bit.
    Bvh2,
    /// The same binary BVH traversed by obvhs itself (the reference for the bench).
    Bvh2Obvhs,
    /// Compressed 8-wide BVH, traversed four nodes at a time with SIMD.
    CwBvh,
}

enum Accel {
    /// A Bvh2 re-laid for faster queries with obvhs's answers.
    Packed(PackedMesh),
    Bvh2(Bvh2),
    CwBvh(CwBvh),
}

/// A triangle ready for ray tests: obvhs's Möller-Trumbore test (`Triangle::intersect`) with
/// its edges and their cross product computed once instead of per test. Every operation of
/// the test is the same, in the same order, so the distances are the same bits.
#[derive(Clone, Copy, Debug)]
struct PreparedTriangle {
    v0: Vec3A,
    /// `v0 - v1`.
    e1: Vec3A,
    /// `v2 - v0`.
    e2: Vec3A,
    /// `e1 x e2`.
    n: Vec3A,
}

impl PreparedTriangle {
    fn new(t: &Triangle) -> Self {
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
    fn parts(&self) -> [Vec3A; 4] {
        [self.v0, self.e1, self.e2, self.n]
    }

    /// Distance along `ray` (in [tmin, tmax]) or infinity: `Triangle::intersect` of obvhs 0.4.
    #[inline(always)]
    fn intersect(&self, ray: &BvhRay) -> f32 {
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
    tris: Vec<Triangle>,
    /// The same triangles prepared for ray tests.
    prepared: Vec<PreparedTriangle>,
    accel: Accel,
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
        let ray = BvhRay::new(o, d, T_MIN, tmax);
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
        let ray = BvhRay::new(o, d, T_MIN, tmax);
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
    mesh: Arc<Mesh>,
    rotation: Mat3A,
    inverse: Mat3A,
    translation: Vec3A,
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
#[derive(Clone, Copy)]
pub(super) enum Prim {
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
        let (best, prim) = self.nearest_shape(lanes, o, d, tmax);
        let (best, prim) = self.nearest_rest(o, d, best, prim);
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
        // again: calling it here made SHADOW 2-7 % slower on one thread (the render loop
        // compiled differently), for the same answers.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_hits_front_then_back_from_inside() {
        let s = Sphere::new(Vec3::ZERO, 1.0, 0);
        let t = s.intersect(Vec3A::new(0.0, 0.0, 5.0), Vec3A::NEG_Z, f32::INFINITY);
        assert!((t - 4.0).abs() < 1e-5);
        let t = s.intersect(Vec3A::ZERO, Vec3A::X, f32::INFINITY);
        assert!((t - 1.0).abs() < 1e-6);
    }

    #[test]
    fn quad_bounds_and_uv() {
        let q = Quad::new(Vec3::ZERO, Vec3::X * 2.0, Vec3::Y, 0);
        let o = Vec3A::new(1.5, 0.25, 3.0);
        let t = q.intersect(o, Vec3A::NEG_Z, f32::INFINITY);
        assert!((t - 3.0).abs() < 1e-6);
        let uv = q.uv(o + t * Vec3A::NEG_Z);
        assert!((uv.x - 0.75).abs() < 1e-6 && (uv.y - 0.25).abs() < 1e-6);
        let miss = q.intersect(Vec3A::new(2.5, 0.5, 3.0), Vec3A::NEG_Z, f32::INFINITY);
        assert_eq!(miss, f32::INFINITY);
    }

    #[test]
    fn prepared_triangle_is_obvhs_test_bit_for_bit() {
        let tri = Triangle {
            v0: Vec3A::new(-0.3, 0.1, 0.2),
            v1: Vec3A::new(0.9, -0.2, 0.05),
            v2: Vec3A::new(0.1, 0.8, -0.4),
        };
        let prepared = PreparedTriangle::new(&tri);
        let mut rng = crate::render::rng::Sampler::new(1, 2, 3);
        let mut hits = 0;
        for _ in 0..20_000 {
            let (a, b) = rng.next_2d();
            let (c, e) = rng.next_2d();
            let o = Vec3A::new(4.0 * a - 2.0, 4.0 * b - 2.0, 3.0 * c + 0.5);
            let target = Vec3A::new(1.4 * e - 0.5, 1.4 * a - 0.5, 0.3 * b - 0.2);
            let ray = BvhRay::new(o, (target - o).normalize(), T_MIN, 2.0 + 3.0 * e);
            let want = tri.intersect(&ray);
            assert_eq!(
                prepared.intersect(&ray).to_bits(),
                want.to_bits(),
                "{o} {target}"
            );
            hits += usize::from(want.is_finite());
        }
        assert!(hits > 1_000, "{hits}");
    }

    /// A bumpy 16 x 16 grid of triangle pairs: shared edges and vertices, where two
    /// triangles can report the same distance and the traversal order picks the hit.
    fn grid_mesh() -> Vec<Triangle> {
        let z = |i: usize, j: usize| 0.3 * ((i * 7 + j * 3) % 5) as f32 / 5.0;
        let v =
            |i: usize, j: usize| Vec3A::new(i as f32 / 8.0 - 1.0, j as f32 / 8.0 - 1.0, z(i, j));
        let mut tris = Vec::new();
        for i in 0..16 {
            for j in 0..16 {
                let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
                tris.push(Triangle {
                    v0: a,
                    v1: b,
                    v2: c,
                });
                tris.push(Triangle {
                    v0: a,
                    v1: c,
                    v2: d,
                });
            }
        }
        tris
    }

    #[test]
    fn pair_layout_and_packed_triangles_answer_as_obvhs() {
        let tris = grid_mesh();
        let mesh = Mesh::new(&tris, BvhKind::Bvh2);
        assert!(matches!(mesh.accel, Accel::Packed(..)));
        let mut unused = std::time::Duration::default();
        let params = BvhBuildParams::medium_build();
        let bvh = obvhs::bvh2::builder::build_bvh2_from_tris(&tris, params, &mut unused);
        let mut rng = crate::render::rng::Sampler::new(4, 5, 6);
        let mut hits = 0;
        for k in 0..20_000 {
            let (a, b) = rng.next_2d();
            let (c, e) = rng.next_2d();
            let o = Vec3A::new(4.0 * a - 2.0, 4.0 * b - 2.0, 2.0 * c - 0.5);
            // Every fourth ray aims at a grid vertex, where neighbours tie.
            let target = if k % 4 == 0 {
                let (i, j) = ((a * 16.0) as usize, (b * 16.0) as usize);
                tris[2 * (16 * i + j)].v0
            } else {
                Vec3A::new(2.0 * e - 1.0, 2.0 * a - 1.0, 0.3 * b)
            };
            let d = (target - o).normalize();
            let tmax = if k % 3 == 0 {
                f32::INFINITY
            } else {
                1.0 + 3.0 * e
            };
            let mut hit = RayHit::none();
            let ray = BvhRay::new(o, d, T_MIN, tmax);
            let want = bvh
                .ray_traverse(ray, &mut hit, |r, id| {
                    tris[bvh.primitive_indices[id] as usize].intersect(r)
                })
                .then(|| {
                    (
                        hit.t.to_bits(),
                        tris[bvh.primitive_indices[hit.primitive_id as usize] as usize],
                    )
                });
            let got = mesh
                .intersect(o, d, tmax)
                .map(|(t, id)| (t.to_bits(), mesh.triangles()[id as usize]));
            assert_eq!(
                got.map(|(t, tri)| (t, tri.v0, tri.v1, tri.v2)),
                want.map(|(t, tri)| (t, tri.v0, tri.v1, tri.v2)),
                "ray {k}"
            );
            let blocked = !bvh.ray_traverse_miss(ray, |r, id| {
                tris[bvh.primitive_indices[id] as usize].intersect(r)
            });
            assert_eq!(mesh.occluded(o, d, tmax), blocked, "ray {k}");
            hits += usize::from(want.is_some());
        }
        assert!(hits > 5_000, "{hits}");
    }

    #[test]
    fn quads_in_lanes_answer_as_one_by_one() {
        // Nine quads (two full groups and one lane of a third) in a room, some overlapping, one
        // degenerate-thin, and a sphere in front of some of them.
        let mut quads = Vec::new();
        for k in 0..9 {
            let f = k as f32;
            quads.push(Quad::new(
                Vec3::new(-2.0 + 0.3 * f, -1.0, -3.0 + 0.5 * f),
                Vec3::new(2.5, 0.2 * f, 0.1),
                Vec3::new(0.1 * f, 2.0, if k == 4 { 1e-3 } else { 0.7 }),
                k,
            ));
        }
        let geo = Geometry {
            quads,
            spheres: vec![Sphere::new(Vec3::new(0.5, 0.0, -1.0), 0.6, 20)],
            ..Default::default()
        };
        let lanes = QuadLanes::pack(&geo.quads);
        let mut rng = crate::render::rng::Sampler::new(4, 5, 6);
        let mut hits = [0usize; 10];
        for _ in 0..50_000 {
            let (a, b) = rng.next_2d();
            let (c, e) = rng.next_2d();
            let o = Vec3A::new(6.0 * a - 3.0, 4.0 * b - 2.0, 3.0 + 2.0 * c);
            let d = (Vec3A::new(4.0 * e - 2.0, 3.0 * a - 1.5, -3.0) - o).normalize();
            let tmax = if c < 0.5 {
                f32::INFINITY
            } else {
                3.0 + 4.0 * b
            };
            let one = geo.intersect(o, d, tmax);
            let four = geo.intersect_in(Some(&lanes), o, d, tmax);
            match (one, four) {
                (None, None) => {}
                (Some((t1, s1)), Some((t4, s4))) => {
                    assert_eq!(t1.to_bits(), t4.to_bits());
                    assert_eq!((s1.material, s1.n, s1.uv), (s4.material, s4.n, s4.uv));
                    hits[s1.material.min(9) as usize] += 1;
                }
                _ => panic!("{o} {d}: {one:?} vs {four:?}"),
            }
            assert_eq!(
                geo.occluded(o, d, tmax),
                geo.occluded_in(Some(&lanes), o, d, tmax)
            );
        }
        // Every quad is hit by some rays, so every lane was exercised.
        assert!(hits[..9].iter().all(|&h| h > 0), "{hits:?}");
    }

    #[test]
    fn sphere_about_a_box_never_hides_a_hit() {
        // Rotated boxes, elongated ones too, and unit rays from around them aimed at points
        // near their corners and edges (where the circumscribed sphere is tightest): whenever
        // the sphere test rules a ray out, the slab test misses too.
        let mut rng = crate::render::rng::Sampler::new(11, 0, 0);
        let mut u = move || rng.next_f32();
        let (mut rejected, mut grazing) = (0, 0);
        for k in 0..200 {
            let half = Vec3::new(0.1 + u(), 0.1 + 2.0 * u(), 0.1 + 0.5 * u());
            let axis = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5) + Vec3::splat(1e-3);
            let center = Vec3::new(u(), u(), u()) * 4.0 - 2.0;
            let b = OrientedBox::new(center, half, axis, 6.0 * u(), 0);
            let to_world = b.to_world();
            for i in 0..500 {
                let dir = Vec3A::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
                let reach = half.length();
                let (o, d) = if i % 2 == 0 {
                    // Aimed at a point near a corner or an edge of the box's surface, pushed
                    // in or out by up to a few tenths of a per cent.
                    let o = Vec3A::from(center) + (3.0 + 40.0 * u()) * reach * dir;
                    let corner = Vec3::new(u().round(), u().round(), u()) * 2.0 - 1.0;
                    let push = 1.0 + 0.004 * u() - 0.001 * (k % 2) as f32;
                    let aim = Vec3A::from(to_world.transform_point3(corner * push));
                    (o, (aim - o).normalize())
                } else {
                    // Passing the centre at 99-101 % of the half diagonal: around the
                    // sphere's margin.
                    let side = dir.any_orthonormal_vector();
                    let pass = Vec3A::from(center) + (0.99 + 0.02 * u()) * reach * side;
                    (pass - (3.0 + 40.0 * u()) * reach * dir, dir)
                };
                let exact = b.slab_test(o, d, f32::INFINITY);
                if b.surely_missed(o, d) {
                    rejected += 1;
                    assert!(exact == f32::INFINITY, "box {k}: hit at {exact} ruled out");
                } else if exact == f32::INFINITY {
                    grazing += 1;
                }
            }
        }
        // Both kinds of rays occur: the test is not vacuous.
        assert!(
            rejected > 10_000 && grazing > 10_000,
            "{rejected} {grazing}"
        );
    }

    #[test]
    fn rotated_box_and_box_set_agree_with_geometry() {
        let b = OrientedBox::new(
            Vec3::ZERO,
            Vec3::splat(1.0),
            Vec3::Y,
            0.25 * std::f32::consts::PI,
            0,
        );
        // Rotated 45 degrees about y: the corner sits at x = sqrt(2).
        let t = b.intersect(Vec3A::new(5.0, 0.0, 0.0), Vec3A::NEG_X, f32::INFINITY);
        assert!((t - (5.0 - 2f32.sqrt())).abs() < 1e-5, "{t}");
        let set = BoxSet::new(&[
            AaBox {
                min: Vec3A::splat(-1.0),
                max: Vec3A::splat(1.0),
                material: 3,
            },
            AaBox {
                min: Vec3A::new(3.0, -1.0, -1.0),
                max: Vec3A::new(4.0, 1.0, 1.0),
                material: 4,
            },
        ]);
        let geo = Geometry {
            box_set: Some(set),
            ..Default::default()
        };
        let (t, s) = geo
            .intersect(Vec3A::new(10.0, 0.0, 0.0), Vec3A::NEG_X, f32::INFINITY)
            .expect("hit");
        assert!((t - 6.0).abs() < 1e-5 && s.material == 4 && s.n.x > 0.99);
        assert!(geo.occluded(Vec3A::new(10.0, 0.0, 0.0), Vec3A::NEG_X, 8.0));
        assert!(!geo.occluded(Vec3A::new(10.0, 0.0, 0.0), Vec3A::NEG_X, 5.0));
    }
}
