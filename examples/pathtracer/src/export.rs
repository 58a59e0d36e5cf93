//! A task's scene at given parameters, written for another renderer to read.
//!
//! `pathtracer export TASK --out DIR` writes `DIR/scene.json` (and, for a triangle mesh or a
//! texture, `DIR/mesh-<k>.obj` and `DIR/texture-<k>.exr`), made from the very [`Scene`] our
//! renderer draws, so that nothing about a scene is written twice:
//! `python/examples/mitsuba_export.py` turns it into a Mitsuba 3 scene. The format
//! (`"format": "pathtracer-scene 1"`, described in docs/mitsuba.md):
//!
//! - `film`: `width`, `height`; a box pixel filter (uniform jitter inside the pixel);
//! - `camera`: `origin`, unit `forward` and `up` (image right = forward x up), `hfov_degrees`;
//! - `spp`, `max_depth` (path segments, Mitsuba's convention), `task`, `params` (`start`,
//!   `target` or `given`) and `theta` (for tasks of up to [`THETA_INLINE`] parameters; a
//!   larger task's are in the side file `theta_file`, `theta.json`, a JSON array that
//!   `--params-file` reads back);
//! - `materials`: `{"type": "diffuse", "albedo": [r, g, b]}` (two-sided Lambertian), with
//!   `"texture": k` when textured, or `{"type": "dielectric", "ior": x}` (IOR inside, the
//!   shape's normal pointing out);
//! - `textures`: `{"file", "width", "height"}`: linear RGB in [0, 1], row 0 at v = 0,
//!   bilinear, clamped at the edges, texel centres at half-integers;
//! - `defaults`: the task's supplemental Table 1 row (`samples`, `sigma0`, `spp`, `lr`,
//!   `iterations`), `unit_box` (theta in [0, 1]^n, else unbounded) and `periodic` (the
//!   indices of angles of period 1, whose box is [-1, 2] and whose error is read on the
//!   circle: GI's box rotation);
//! - `paper` (all tasks but TEXTURE): the paper's results, main paper Table 2 (`image_mse`,
//!   `param_mse`, `mitsuba_image_mse`, `mitsuba_param_mse`) and Table 3
//!   (`seconds_per_iteration`, GPU);
//! - `shapes`: `sphere` (`center`, `radius`), `quad` (corner `origin`, edges `u`, `v`, normal
//!   u x v, texture uv = the edge fractions, `emission` for a one-sided area light facing the
//!   normal), `box` (`to_world`: the map from the cube [-1, 1]^3) and `mesh` (`file`, an OBJ of
//!   unshared triangles, flat normals, and its `to_world`); each with `material`; a
//!   `to_world` is three rows of four numbers (a 3x4 affine matrix);
//! - `point_lights` (`position`, radiant `intensity`) and `environment` (constant radiance).

use std::fmt::Write as _;
use std::path::Path;

use glam::{Affine3A, Vec3A};
use serde_json::{json, Value};

use crate::render::{Image, Material, Scene, Settings};
use crate::tasks::{Defaults, Paper};

/// The format's name and version, the first key of `scene.json`.
pub const FORMAT: &str = "pathtracer-scene 1";

/// Tasks with at most this many parameters list them in `scene.json`; a larger task's
/// (TEXTURE's 49,152) go to the side file `theta.json`.
pub const THETA_INLINE: usize = 1000;

/// What `scene.json` says besides the scene: the task, which parameters, the render settings.
pub struct Header<'a> {
    /// The task's name.
    pub task: &'a str,
    /// `start`, `target` or `given`.
    pub params: &'a str,
    /// The parameters.
    pub theta: &'a [f64],
    /// Samples per pixel and longest path.
    pub settings: Settings,
    /// The task's hyperparameters (supplemental Table 1), whether theta lives in [0, 1]^n,
    /// and which parameters are angles of period 1 ([`crate::tasks::Task::periodic`]).
    pub defaults: Option<(Defaults, bool, &'a [usize])>,
    /// The paper's results for the task (main paper Table 2, Table 3's seconds), if it has them.
    pub paper: Option<Paper>,
}

/// Writes `scene.json` and its mesh and texture files into `dir` (which must exist).
pub fn write(dir: &Path, header: &Header, scene: &Scene) -> std::io::Result<()> {
    let mut files = Vec::new();
    let value = describe(header, scene, &mut files);
    for (name, contents) in files {
        match contents {
            File::Text(text) => std::fs::write(dir.join(name), text)?,
            File::Texture(image) => image
                .save_exr(&dir.join(name))
                .map_err(|e| std::io::Error::other(e.to_string()))?,
        }
    }
    let text = serde_json::to_string_pretty(&value).map_err(std::io::Error::other)?;
    std::fs::write(dir.join("scene.json"), text + "\n")
}

/// A side file of the description: an OBJ mesh, or a texture as an image.
pub enum File {
    /// Text (an OBJ mesh, the parameters as JSON).
    Text(String),
    /// A texture's texels as a linear image.
    Texture(Image),
}

/// The description of `scene` as JSON; the mesh and texture files it names go to `files`.
pub fn describe(header: &Header, scene: &Scene, files: &mut Vec<(String, File)>) -> Value {
    let camera = &scene.camera;
    let textures: Vec<Value> = scene
        .textures
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let name = format!("texture-{k}.exr");
            let mut image = Image::new(t.width(), t.height());
            for (i, texel) in t.texels().iter().enumerate() {
                image.data[3 * i..3 * i + 3].copy_from_slice(&texel.to_array());
            }
            files.push((name.clone(), File::Texture(image)));
            json!({"file": name, "width": t.width(), "height": t.height()})
        })
        .collect();
    let mut value = json!({
        "format": FORMAT,
        "task": header.task,
        "params": header.params,
        "spp": header.settings.spp.max(1),
        "max_depth": header.settings.max_depth,
        "film": {"width": camera.width, "height": camera.height, "filter": "box"},
        "camera": {
            "origin": v3(camera.origin()),
            "forward": v3(camera.forward()),
            "up": v3(camera.up()),
            "hfov_degrees": camera.hfov_degrees(),
        },
        "materials": scene.materials.iter().map(material).collect::<Vec<_>>(),
        "textures": textures,
        "shapes": shapes(scene, files),
        "point_lights": scene.lights.points.iter()
            .map(|l| json!({"position": v3(l.position), "intensity": v3(l.intensity)}))
            .collect::<Vec<_>>(),
        "environment": v3(scene.lights.environment),
    });
    if header.theta.len() <= THETA_INLINE {
        value["theta"] = json!(header.theta);
    } else {
        let name = "theta.json".to_string();
        files.push((name.clone(), File::Text(json!(header.theta).to_string())));
        value["theta_file"] = json!(name);
    }
    if let Some((d, unit_box, periodic)) = header.defaults {
        value["defaults"] = json!({
            "samples": d.samples, "sigma0": d.sigma0, "spp": d.spp, "lr": d.lr,
            "iterations": d.iterations, "unit_box": unit_box, "periodic": periodic,
        });
    }
    if let Some(p) = header.paper {
        value["paper"] = json!({
            "image_mse": p.image_mse, "param_mse": p.param_mse,
            "seconds_per_iteration": p.seconds_per_iteration,
            "mitsuba_image_mse": p.mitsuba_image_mse, "mitsuba_param_mse": p.mitsuba_param_mse,
        });
    }
    value
}

/// A vector as three JSON numbers.
fn v3(v: Vec3A) -> [f32; 3] {
    v.to_array()
}

/// An affine map as three rows of four numbers.
fn rows(m: Affine3A) -> [[f32; 4]; 3] {
    let (a, t) = (m.matrix3, m.translation);
    [0, 1, 2].map(|r| {
        let row = a.row(r);
        [row.x, row.y, row.z, t[r]]
    })
}

fn material(m: &Material) -> Value {
    match *m {
        Material::Diffuse { albedo, texture } => match texture {
            Some(k) => json!({"type": "diffuse", "albedo": v3(albedo), "texture": k}),
            None => json!({"type": "diffuse", "albedo": v3(albedo)}),
        },
        Material::Dielectric { ior } => json!({"type": "dielectric", "ior": ior}),
    }
}

/// Every shape, in the order spheres, quads, boxes, the box set's boxes, mesh instances.
fn shapes(scene: &Scene, files: &mut Vec<(String, File)>) -> Vec<Value> {
    let g = &scene.geometry;
    let mut out: Vec<Value> = g
        .spheres
        .iter()
        .map(|s| json!({"type": "sphere", "center": v3(s.center), "radius": s.radius, "material": s.material}))
        .collect();
    for q in &g.quads {
        let mut quad = json!({"type": "quad", "origin": v3(q.origin), "u": v3(q.u), "v": v3(q.v), "material": q.material});
        if q.emission != Vec3A::ZERO {
            quad["emission"] = json!(v3(q.emission));
        }
        out.push(quad);
    }
    for b in &g.boxes {
        out.push(json!({"type": "box", "to_world": rows(b.to_world()), "material": b.material}));
    }
    for b in g.box_set.iter().flat_map(|set| set.boxes()) {
        let half = 0.5 * (b.max - b.min);
        let m = Affine3A::from_scale_rotation_translation(
            half.into(),
            glam::Quat::IDENTITY,
            (b.min + half).into(),
        );
        out.push(json!({"type": "box", "to_world": rows(m), "material": b.material}));
    }
    for (k, inst) in g.instances.iter().enumerate() {
        let name = format!("mesh-{k}.obj");
        files.push((name.clone(), File::Text(obj(inst.mesh().triangles()))));
        out.push(json!({"type": "mesh", "file": name, "to_world": rows(inst.to_world()), "material": inst.material}));
    }
    out
}

/// A Wavefront OBJ of unshared triangles (`{}` prints an f32 so that it reads back exactly).
fn obj(tris: &[obvhs::triangle::Triangle]) -> String {
    let mut s = String::from("# pathtracer export: unshared triangles, flat shading\n");
    for t in tris {
        for v in [t.v0, t.v1, t.v2] {
            let _ = writeln!(s, "v {} {} {}", v.x, v.y, v.z);
        }
    }
    for i in 0..tris.len() {
        let _ = writeln!(s, "f {} {} {}", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tasks::{self, View};

    /// Every task describes itself: the camera's frame and field of view come back, every
    /// shape names a material that exists, and the side files are the ones named (theta's
    /// too, for TEXTURE).
    #[test]
    fn every_task_describes_its_scene() {
        for task in tasks::all() {
            let theta = task.target();
            let scene = task.scene(&theta, View::default());
            let header = Header {
                task: task.name(),
                params: "target",
                theta: &theta,
                settings: Settings::new(4, 0, task.max_depth()),
                defaults: Some((task.defaults(), task.bounds().is_some(), task.periodic())),
                paper: task.paper(),
            };
            let mut files = Vec::new();
            let v = describe(&header, &scene, &mut files);
            assert_eq!(v["format"], FORMAT);
            assert_eq!(v["max_depth"], task.max_depth());
            let materials = v["materials"].as_array().unwrap().len() as u64;
            for shape in v["shapes"].as_array().unwrap() {
                assert!(
                    shape["material"].as_u64().unwrap() < materials,
                    "{}",
                    task.name()
                );
            }
            let named: Vec<&str> = v["shapes"]
                .as_array()
                .unwrap()
                .iter()
                .filter_map(|s| s["file"].as_str())
                .chain(
                    v["textures"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .filter_map(|t| t["file"].as_str()),
                )
                .chain(v["theta_file"].as_str())
                .collect();
            let written: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
            assert_eq!(named, written, "{}", task.name());
            assert_eq!(v.get("theta").is_some(), task.dim() <= THETA_INLINE);
            assert_eq!(v.get("theta_file").is_some(), task.dim() > THETA_INLINE);
            assert_eq!(v["defaults"]["samples"], task.defaults().samples);
            assert_eq!(v["defaults"]["unit_box"], task.bounds().is_some());
            assert_eq!(v["defaults"]["periodic"], json!(task.periodic()));
            assert_eq!(v.get("paper").is_some(), task.name() != "texture");
        }
    }

    /// SHADOW's numbers as the scene states them (SPEC section 2).
    #[test]
    fn shadow_reads_back_its_numbers() {
        let task = tasks::by_name("shadow").unwrap();
        let theta = task.target();
        let scene = task.scene(&theta, View::default());
        let header = Header {
            task: "shadow",
            params: "target",
            theta: &theta,
            settings: Settings::new(32, 0, 6),
            defaults: None,
            paper: None,
        };
        let v = describe(&header, &scene, &mut Vec::new());
        let hfov = v["camera"]["hfov_degrees"].as_f64().unwrap();
        assert!((hfov - 39.597755).abs() < 1e-4, "{hfov}");
        assert_eq!(v["film"]["width"], 256);
        let sphere = &v["shapes"][0];
        assert_eq!(sphere["type"], "sphere");
        let y = sphere["center"][1].as_f64().unwrap();
        assert!((y - (8.05 - 1.5)).abs() < 1e-5, "{y}");
        assert!((v["point_lights"][0]["intensity"][0].as_f64().unwrap() - 1715.0).abs() < 1e-9);
    }

    /// A box's `to_world` sends the cube's corners to the box's.
    #[test]
    fn box_rows_map_the_unit_cube() {
        let b = crate::render::OrientedBox::new(
            glam::Vec3::new(1.0, 2.0, 3.0),
            glam::Vec3::new(0.5, 1.0, 2.0),
            glam::Vec3::Y,
            std::f32::consts::FRAC_PI_2,
            0,
        );
        let r = rows(b.to_world());
        // The corner (1, 1, 1) turned a quarter about y: local x -> -z, local z -> +x.
        let p: Vec<f32> = (0..3)
            .map(|i| r[i][0] + r[i][1] + r[i][2] + r[i][3])
            .collect();
        let want = [1.0 + 2.0, 2.0 + 1.0, 3.0 - 0.5];
        for i in 0..3 {
            assert!((p[i] - want[i]).abs() < 1e-5, "{p:?}");
        }
    }
}
