//! Renderer correctness against analytic answers. Every test is deterministic (fixed seeds);
//! tolerances are several standard errors of the estimate.

use glam::{Vec3, Vec3A};

use super::*;

fn furnace(material: Material, environment_nee: bool) -> Scene {
    Scene {
        camera: Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 40.0, 32, 32),
        geometry: Geometry {
            spheres: vec![Sphere::new(Vec3::ZERO, 1.0, 0)],
            ..Default::default()
        },
        materials: vec![material],
        textures: vec![],
        lights: Lights {
            environment: Vec3A::splat(0.75),
            environment_nee,
            ..Default::default()
        },
    }
}

/// White furnace: inside a uniform environment of radiance L, a closed white diffuse or
/// lossless glass object is invisible: every pixel is L. Mean within 1 %.
#[test]
fn white_furnace_diffuse_and_glass() {
    let cases = [
        (Material::grey(1.0), true),
        (Material::grey(1.0), false),
        (Material::Dielectric { ior: 1.5 }, true),
    ];
    for (material, env_nee) in cases {
        let scene = furnace(material, env_nee);
        let img = render(&scene, &Settings::new(64, 3, 64));
        // The sphere covers the centre of the image.
        let mean = img.mean_rgb(8, 8, 24, 24);
        for c in mean {
            assert!((c / 0.75 - 1.0).abs() < 0.01, "{material:?}: {mean:?}");
        }
        assert!(img.data.iter().all(|v| v.is_finite()));
    }
}

/// A point light over a diffuse plane: radiance albedo / pi * I cos / d^2 (the pixel's box
/// filter is the only source of variance and of a second-order bias, both < 1 %).
#[test]
fn point_light_irradiance_on_diffuse_plane() {
    let albedo = 0.5f32;
    let light = Vec3::new(1.0, 2.0, 3.0);
    let intensity = 10.0f32;
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 60.0, 64, 64);
    let scene = Scene {
        camera,
        geometry: Geometry {
            quads: vec![Quad::centered(
                Vec3::ZERO,
                Vec3::X * 40.0,
                Vec3::Y * 40.0,
                0,
            )],
            ..Default::default()
        },
        materials: vec![Material::diffuse(albedo, albedo, albedo)],
        textures: vec![],
        lights: Lights {
            points: vec![PointLight::new(light, Vec3::splat(intensity))],
            ..Default::default()
        },
    };
    let img = render(&scene, &Settings::new(64, 11, 2));
    for (x, y) in [(32, 32), (10, 50), (50, 12), (40, 20), (5, 5)] {
        let d = camera.direction(x, y, 0.5, 0.5);
        let p = camera.origin() + d * (10.0 / -d.z);
        let to = Vec3A::from(light) - p;
        let expected = albedo / std::f32::consts::PI * intensity * to.z / to.length().powi(3);
        let got = img.pixel(x, y)[0];
        assert!(
            (got / expected - 1.0).abs() < 0.01,
            "pixel ({x},{y}): {got} vs {expected}"
        );
    }
}

/// A grey floor (z = 0, `floor` on a side) lit by a unit-square area light facing down at
/// `light`, with a sphere of `material` on it, seen by `camera`.
fn lit_floor(
    camera: Camera,
    floor: f32,
    (light, radiance): (Vec3, f32),
    sphere: (Vec3, f32),
    material: Material,
) -> Scene {
    let mut quads = vec![Quad::centered(
        Vec3::ZERO,
        Vec3::X * floor,
        Vec3::Y * floor,
        0,
    )];
    let mut lights = Lights::default();
    // Facing down (-z): u x v = x x (-y) = -z.
    lights.add_area(
        &mut quads,
        Quad::centered(light, Vec3::X, Vec3::NEG_Y, 1),
        Vec3::splat(radiance),
    );
    let (center, radius) = sphere;
    Scene {
        camera,
        geometry: Geometry {
            quads,
            spheres: vec![Sphere::new(center, radius, 2)],
            ..Default::default()
        },
        materials: vec![Material::grey(0.8), Material::grey(0.0), material],
        textures: vec![],
        lights,
    }
}

/// A diffuse sphere beside a small area light, seen from the side.
fn area_light_scene() -> Scene {
    lit_floor(
        Camera::look_at(Vec3::new(0.0, -6.0, 4.0), Vec3::ZERO, Vec3::Z, 50.0, 48, 48),
        10.0,
        (Vec3::new(0.5, 0.0, 2.0), 6.0),
        (Vec3::new(-0.3, 0.2, 0.7), 0.7),
        Material::diffuse(0.7, 0.3, 0.2),
    )
}

/// NEE + MIS and pure BSDF sampling estimate the same image: means over four quadrants
/// agree within 3 % (the BSDF-only image is the noisy one).
#[test]
fn nee_mis_matches_bsdf_sampling() {
    let scene = area_light_scene();
    let with = render(&scene, &Settings::new(64, 5, 4));
    let without = render(
        &scene,
        &Settings {
            nee: false,
            ..Settings::new(1024, 6, 4)
        },
    );
    for (x0, y0) in [(0, 0), (24, 0), (0, 24), (24, 24)] {
        let a = with.mean_rgb(x0, y0, x0 + 24, y0 + 24);
        let b = without.mean_rgb(x0, y0, x0 + 24, y0 + 24);
        for c in 0..3 {
            assert!(a[c] > 1e-3, "region ({x0},{y0}) is black");
            assert!(
                (a[c] / b[c] - 1.0).abs() < 0.03,
                "region ({x0},{y0}) channel {c}: NEE {} vs BSDF {}",
                a[c],
                b[c]
            );
        }
    }
}

/// Same seed, same bits, whatever the number of threads; a different seed differs.
#[test]
fn deterministic_across_thread_counts() {
    let scene = area_light_scene();
    let settings = Settings::new(4, 42, 6);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| render(&scene, &settings))
    };
    let one = run(1);
    let two = run(2);
    assert!(one
        .data
        .iter()
        .zip(&two.data)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    let other = render(&scene, &Settings::new(4, 43, 6));
    assert_ne!(one, other);
}

/// Caustic: light through a glass sphere reaches the floor only by paths that refract and
/// then hit the emitter, which must count (NEE cannot sample through a delta BSDF). The
/// focused spot below the sphere is brighter than the unfocused floor beside it.
#[test]
fn glass_sphere_focuses_a_caustic() {
    let scene = lit_floor(
        // Looking straight down from between the sphere and the light.
        Camera::look_at(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, Vec3::Y, 90.0, 32, 32),
        20.0,
        (Vec3::new(0.0, 0.0, 6.0), 40.0),
        (Vec3::new(0.0, 0.0, 1.0), 0.5),
        Material::Dielectric { ior: 1.5 },
    );
    let img = render(&scene, &Settings::new(64, 1, 8));
    assert!(img.data.iter().all(|v| v.is_finite() && *v >= 0.0));
    // The sphere covers the centre; the edge of the image sees open floor.
    let centre = img.mean_rgb(14, 14, 18, 18)[0];
    let edge = img.mean_rgb(0, 0, 4, 4)[0];
    assert!(centre > 1.5 * edge, "centre {centre} vs edge {edge}");
}
