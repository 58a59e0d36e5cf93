//! Spheres and parallelograms.

use glam::{Vec2, Vec3, Vec3A};

use super::{NO_LIGHT, T_MIN};

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
    pub(super) fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
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
    pub(super) plane_d: f32,
    /// Dotted with the in-plane offset, gives the `a` coordinate.
    pub(super) a_axis: Vec3A,
    /// Dotted with the in-plane offset, gives the `b` coordinate.
    pub(super) b_axis: Vec3A,
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
    pub(super) fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
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
    pub(super) fn uv(&self, p: Vec3A) -> Vec2 {
        let q = p - self.origin;
        Vec2::new(q.dot(self.a_axis), q.dot(self.b_axis))
    }

    /// The point at parallelogram coordinates (`a`, `b`).
    #[inline(always)]
    pub fn point(&self, a: f32, b: f32) -> Vec3A {
        self.origin + a * self.u + b * self.v
    }
}
