//! Renderer benchmarks: per-task render time at the task's default settings, the parts of a
//! render per task on one thread (camera rays, primary hits, the whole image), BVH build
//! times, the mug's BVH traversals (ours on obvhs's Bvh2, obvhs's own, its CwBvh), and 1 vs
//! 2 rayon threads on SHADOW.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3A;

use pathtracer::{render, tasks};

use render::rng::Sampler;
use render::{AaBox, BoxSet, BvhKind, Mesh};

fn task_renders(c: &mut Criterion) {
    let mut group = c.benchmark_group("render_task_default");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for task in tasks::all() {
        let theta = task.target();
        let spp = task.defaults().spp;
        group.bench_function(task.name(), |b| {
            b.iter(|| black_box(task.render(&theta, 1, spp, tasks::View::default())))
        });
    }
    group.finish();
}

/// Every camera sample's stream and ray (what the render loop does before tracing), summed so
/// that nothing is optimised away.
fn camera_rays(scene: &render::Scene, spp: u32) -> Vec3A {
    let cam = &scene.camera;
    let mut sum = Vec3A::ZERO;
    for y in 0..cam.height {
        for x in 0..cam.width {
            for s in 0..spp {
                let mut rng = Sampler::new(0, y * cam.width + x, s);
                let (jx, jy) = rng.next_2d();
                sum += cam.direction(x, y, jx, jy);
            }
        }
    }
    sum
}

/// The camera rays and their closest hits (the first segment of every path, unshaded).
fn primary_hits(scene: &render::Scene, spp: u32) -> usize {
    let cam = &scene.camera;
    let mut hits = 0;
    for y in 0..cam.height {
        for x in 0..cam.width {
            for s in 0..spp {
                let mut rng = Sampler::new(0, y * cam.width + x, s);
                let (jx, jy) = rng.next_2d();
                let d = cam.direction(x, y, jx, jy);
                let hit = scene.geometry.intersect(cam.origin(), d, f32::INFINITY);
                hits += usize::from(hit.is_some());
            }
        }
    }
    hits
}

/// Where a render's time goes, per task, on one thread: the camera rays alone, with their
/// closest hits, and the whole render (the rest is shading, shadow rays and later bounces).
/// `cargo bench -p pathtracer --bench render -- render_parts`.
fn render_parts(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let mut group = c.benchmark_group("render_parts");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    for task in tasks::all() {
        let scene = task.scene(&task.target(), tasks::View::default());
        let spp = task.defaults().spp;
        let settings = render::Settings::new(spp, 0, task.max_depth());
        group.bench_function(format!("{}/camera_rays", task.name()), |b| {
            b.iter(|| black_box(camera_rays(&scene, spp)))
        });
        group.bench_function(format!("{}/primary_hits", task.name()), |b| {
            b.iter(|| black_box(primary_hits(&scene, spp)))
        });
        group.bench_function(format!("{}/render", task.name()), |b| {
            b.iter(|| pool.install(|| black_box(render::render(&scene, &settings))))
        });
    }
    group.finish();
}

fn bvh_builds(c: &mut Criterion) {
    let tris = tasks::cup::mug_triangles();
    let mut group = c.benchmark_group("bvh_build");
    group.bench_function("mug_bvh2", |b| {
        b.iter(|| black_box(Mesh::new(&tris, BvhKind::Bvh2)))
    });
    group.bench_function("mug_cwbvh", |b| {
        b.iter(|| black_box(Mesh::new(&tris, BvhKind::CwBvh)))
    });
    let sort = tasks::by_name("sort").expect("sort");
    let theta = sort.start();
    let boxes: Vec<AaBox> = (0..75)
        .map(|k| {
            let c = Vec3A::new(
                5.0 * theta[2 * k] as f32,
                0.15,
                5.0 * theta[2 * k + 1] as f32,
            );
            AaBox {
                min: c - 0.15,
                max: c + 0.15,
                material: 0,
            }
        })
        .collect();
    group.bench_function("sort_75_boxes", |b| {
        b.iter(|| black_box(BoxSet::new(&boxes)))
    });
    group.finish();
}

/// 65,536 rays from a sphere of radius 3 around the mug towards random points of its box.
fn mug_rays() -> Vec<(Vec3A, Vec3A)> {
    (0..65_536u32)
        .map(|i| {
            let mut s = Sampler::new(9, i, 0);
            let (a, b) = s.next_2d();
            let z = 2.0 * a - 1.0;
            let phi = std::f32::consts::TAU * b;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let o = 3.0 * Vec3A::new(r * phi.cos(), z, r * phi.sin()) + Vec3A::new(0.0, 0.6, 0.0);
            let (c, d) = s.next_2d();
            let e = s.next_f32();
            let target = Vec3A::new(2.2 * c - 1.1, 1.2 * d, 2.2 * e - 1.1);
            (o, (target - o).normalize())
        })
        .collect()
}

fn traversal(c: &mut Criterion) {
    let tris = tasks::cup::mug_triangles();
    let rays = mug_rays();
    let mut group = c.benchmark_group("mug_traversal_65k_rays");
    for kind in [BvhKind::Bvh2, BvhKind::Bvh2Obvhs, BvhKind::CwBvh] {
        let mesh = Mesh::new(&tris, kind);
        group.bench_function(format!("{kind:?}_closest"), |b| {
            b.iter(|| {
                rays.iter()
                    .filter(|(o, d)| mesh.intersect(*o, *d, f32::INFINITY).is_some())
                    .count()
            })
        });
        group.bench_function(format!("{kind:?}_occluded"), |b| {
            b.iter(|| {
                rays.iter()
                    .filter(|(o, d)| mesh.occluded(*o, *d, f32::INFINITY))
                    .count()
            })
        });
    }
    group.finish();
}

fn threads(c: &mut Criterion) {
    let shadow = tasks::by_name("shadow").expect("shadow");
    let theta = shadow.start();
    let mut group = c.benchmark_group("shadow_threads");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for n in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("pool");
        group.bench_function(format!("{n}_threads"), |b| {
            b.iter(|| {
                pool.install(|| black_box(shadow.render(&theta, 1, 32, tasks::View::default())))
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    task_renders,
    render_parts,
    bvh_builds,
    traversal,
    threads
);
criterion_main!(benches);
