//! CUP: turn a mug about its axis until its handle points right.
//!
//! The body is rotationally symmetric, so while the handle hides behind it the image does
//! not change: the loss has a plateau around the start. The lights sit near the camera so
//! that the handle's shadow hides behind the body too.

use std::f32::consts::TAU;
use std::sync::Arc;

use glam::{Vec3, Vec3A};
use obvhs::triangle::Triangle;

use super::{param, Aim, Scenario, Shot};
use crate::render::{
    BvhKind, Camera, Geometry, Lights, Material, Mesh, MeshInstance, PointLight, Quad, Scene,
};

const OUTER: f32 = 0.6;
const INNER: f32 = 0.5;
const HEIGHT: f32 = 1.2;
const FLOOR: f32 = 0.08;

/// Looking slightly down at the mug from the front.
pub(super) const CAMERA: Shot = Shot::new(EYE, Aim::At(LOOK), Vec3::Y, 30.0, (128, 96));
const EYE: Vec3 = Vec3::new(0.0, 1.9, 5.0);
const LOOK: Vec3 = Vec3::new(0.0, 0.55, 0.0);

/// The CUP task: the mug mesh and its BVH are built once here.
pub struct Cup {
    mug: Arc<Mesh>,
}

impl Cup {
    /// Tessellates the mug and builds its BVH.
    pub fn new() -> Self {
        Self {
            mug: Arc::new(Mesh::new(&mug_triangles(), BvhKind::Bvh2)),
        }
    }
}

impl Default for Cup {
    fn default() -> Self {
        Self::new()
    }
}

/// Triangles of a quad strip cell (a, b, c, d counter-clockwise).
fn quad_tris(out: &mut Vec<Triangle>, a: Vec3, b: Vec3, c: Vec3, d: Vec3) {
    out.push(Triangle {
        v0: a.into(),
        v1: b.into(),
        v2: c.into(),
    });
    out.push(Triangle {
        v0: a.into(),
        v1: c.into(),
        v2: d.into(),
    });
}

/// A mug in its own frame: axis +y through the origin, standing on y = 0, the handle
/// pointing to +x. Open top, walls of thickness OUTER - INNER, a torus-segment handle whose
/// ends sink into the wall.
pub fn mug_triangles() -> Vec<Triangle> {
    const SEGMENTS: usize = 64;
    let mut tris = Vec::new();
    let ring = |(r, y, i): (f32, f32, usize)| {
        let a = TAU * i as f32 / SEGMENTS as f32;
        Vec3::new(r * a.cos(), y, r * a.sin())
    };
    for i in 0..SEGMENTS {
        let j = i + 1;
        // Outer wall, inner wall and rim between the segment's edges i and j, each a quad
        // (a, b, c, d) counter-clockwise seen from the side it faces; then the inner and
        // outer bottoms.
        #[rustfmt::skip]
        let bands = [
            [(OUTER, 0.0, i),    (OUTER, HEIGHT, i), (OUTER, HEIGHT, j), (OUTER, 0.0, j)],
            [(INNER, FLOOR, i),  (INNER, FLOOR, j),  (INNER, HEIGHT, j), (INNER, HEIGHT, i)],
            [(INNER, HEIGHT, i), (INNER, HEIGHT, j), (OUTER, HEIGHT, j), (OUTER, HEIGHT, i)],
        ];
        for [a, b, c, d] in bands {
            quad_tris(&mut tris, ring(a), ring(b), ring(c), ring(d));
        }
        tris.push(Triangle {
            v0: Vec3A::new(0.0, FLOOR, 0.0),
            v1: ring((INNER, FLOOR, i)).into(),
            v2: ring((INNER, FLOOR, j)).into(),
        });
        tris.push(Triangle {
            v0: Vec3A::ZERO,
            v1: ring((OUTER, 0.0, j)).into(),
            v2: ring((OUTER, 0.0, i)).into(),
        });
    }
    // Handle: a tube of radius `tube` around an arc of radius `major` centred beside the wall.
    const ARC: usize = 32;
    const TUBE: usize = 12;
    let (cx, cy, major, tube) = (OUTER + 0.05, 0.6, 0.32, 0.06);
    let reach = 105f32.to_radians();
    let point = |k: usize, m: usize| {
        let phi = -reach + 2.0 * reach * k as f32 / ARC as f32;
        let psi = TAU * m as f32 / TUBE as f32;
        let radial = Vec3::new(phi.cos(), phi.sin(), 0.0);
        Vec3::new(cx, cy, 0.0) + major * radial + tube * (psi.cos() * radial + psi.sin() * Vec3::Z)
    };
    for k in 0..ARC {
        for m in 0..TUBE {
            quad_tris(
                &mut tris,
                point(k, m),
                point(k + 1, m),
                point(k + 1, m + 1),
                point(k, m + 1),
            );
        }
    }
    tris
}

impl Scenario for Cup {
    fn scene(&self, theta: &[f64], camera: Camera) -> Scene {
        // theta = 0.25 puts the handle on +x (image right); 0.5 turns it away from the camera.
        let angle = TAU * (param(theta, 0) - 0.25);
        let mut quads = vec![
            // Floor (z x x = +y) and back wall (x x y = +z).
            Quad::centered(Vec3::ZERO, Vec3::Z * 12.0, Vec3::X * 12.0, 0),
            Quad::centered(Vec3::new(0.0, 3.0, -2.5), Vec3::X * 12.0, Vec3::Y * 6.0, 1),
        ];
        let mut lights = Lights {
            points: vec![PointLight::new(Vec3::new(0.4, 2.6, 5.0), Vec3::splat(9.0))],
            environment: Vec3A::splat(0.05),
            environment_nee: false,
            ..Default::default()
        };
        // Area light above and in front of the mug, facing down (x x z = -y).
        lights.add_area(
            &mut quads,
            Quad::centered(Vec3::new(-0.3, 4.0, 2.0), Vec3::X * 1.2, Vec3::Z * 1.2, 3),
            Vec3::splat(6.0),
        );
        Scene {
            camera,
            geometry: Geometry {
                quads,
                instances: vec![MeshInstance::new(
                    self.mug.clone(),
                    Vec3::Y,
                    angle,
                    Vec3::ZERO,
                    2,
                )],
                ..Default::default()
            },
            materials: vec![
                Material::grey(0.55),
                Material::diffuse(0.6, 0.65, 0.75),
                Material::diffuse(0.85, 0.45, 0.15),
                Material::grey(0.0),
            ],
            textures: vec![],
            lights,
        }
    }

    fn start(&self) -> Vec<f64> {
        vec![0.5]
    }

    fn target(&self) -> Vec<f64> {
        vec![0.25]
    }
}
