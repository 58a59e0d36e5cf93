//! Ray tests of every shape against their closed forms, and of the whole geometry.

use glam::{Vec3, Vec3A};
use obvhs::{
    ray::{Ray as BvhRay, RayHit},
    triangle::Triangle,
    BvhBuildParams,
};

use super::mesh::{Accel, PreparedTriangle};
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
    let v = |i: usize, j: usize| Vec3A::new(i as f32 / 8.0 - 1.0, j as f32 / 8.0 - 1.0, z(i, j));
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
fn wide_tree_and_packed_triangles_answer_as_obvhs() {
    let tris = grid_mesh();
    let mesh = Mesh::new(&tris, BvhKind::Bvh2);
    assert!(matches!(mesh.accel, Accel::Packed(..)));
    let mut unused = std::time::Duration::default();
    let params = BvhBuildParams::medium_build();
    let bvh = obvhs::bvh2::builder::build_bvh2_from_tris(&tris, params, &mut unused);
    let mut rng = crate::render::rng::Sampler::new(4, 5, 6);
    let (mut hits, mut ties) = (0, 0);
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
        // Off vertices: the same triangle at the same distance, bit for bit. At a vertex the
        // triangles around it tie within rounding, and which one is found depends on the
        // order of visits (the 4-wide tree's differs from the binary tree's, and a box entered
        // a rounding error beyond the hit so far is skipped): the distance agrees to rounding
        // (1e-5 relative), and the triangle found is hit at the distance reported.
        if k % 4 != 0 {
            let same = |h: Option<(u32, Triangle)>| h.map(|(t, tri)| (t, tri.v0, tri.v1, tri.v2));
            assert_eq!(same(got), same(want), "ray {k}");
        } else {
            assert_eq!(got.is_some(), want.is_some(), "ray {k}");
            if let (Some((t, tri)), Some((w, other))) = (got, want) {
                let (t32, w32) = (f32::from_bits(t), f32::from_bits(w));
                assert!((t32 - w32).abs() <= 1e-5 * w32, "ray {k}: {t32} vs {w32}");
                let ray = BvhRay::new(o, d, T_MIN, tmax);
                assert_eq!(tri.intersect(&ray).to_bits(), t, "ray {k}");
                ties += usize::from((tri.v0, tri.v1, tri.v2) != (other.v0, other.v1, other.v2));
            }
        }
        let blocked = !bvh.ray_traverse_miss(ray, |r, id| {
            tris[bvh.primitive_indices[id] as usize].intersect(r)
        });
        assert_eq!(mesh.occluded(o, d, tmax), blocked, "ray {k}");
        hits += usize::from(want.is_some());
    }
    assert!(hits > 5_000, "{hits}");
    // Another triangle than obvhs's at a few of the 5,000 vertex rays only.
    assert!(ties < 500, "{ties}");
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

#[test]
fn bvh_ray_is_obvhs_ray() {
    // Components around obvhs's EPSILON cut-off (both sides, both signs, zeros) and ordinary
    // unit directions: the same inverse bits as `Ray::new`.
    let eps = f32::EPSILON;
    let edge = [
        0.0,
        -0.0,
        eps,
        -eps,
        f32::from_bits(eps.to_bits() + 1),
        f32::from_bits(eps.to_bits() - 1),
        -f32::from_bits(eps.to_bits() + 1),
        1e-30,
        -1e-30,
        1.0,
        -1.0,
    ];
    let mut rng = crate::render::rng::Sampler::new(1, 2, 3);
    let mut dirs = Vec::new();
    for &x in &edge {
        for &y in &edge {
            dirs.push(Vec3A::new(x, y, 0.3));
        }
    }
    for _ in 0..10_000 {
        let (a, b) = rng.next_2d();
        let (c, _) = rng.next_2d();
        dirs.push(Vec3A::new(2.0 * a - 1.0, 2.0 * b - 1.0, 2.0 * c - 1.0).normalize_or(Vec3A::X));
    }
    let o = Vec3A::new(0.5, -1.0, 2.0);
    for d in dirs {
        let want = BvhRay::new(o, d, T_MIN, 3.0);
        let got = super::bvh_ray(o, d, 3.0);
        let bits = |r: &BvhRay| {
            let v = [r.origin, r.direction, r.inv_direction];
            (
                v.map(|v| v.to_array().map(f32::to_bits)),
                r.tmin.to_bits(),
                r.tmax.to_bits(),
            )
        };
        assert_eq!(bits(&got), bits(&want), "{d}");
    }
}
