//! A small CPU path tracer: only what the paper's seven task scenes need.
//!
//! A [`Scene`] is plain data (camera, geometry, materials, lights); [`render`] turns it into
//! an [`Image`] deterministically from a seed.

pub mod camera;
pub mod film;
pub mod geometry;
pub mod integrator;
mod lanes;
mod last_segment;
pub mod light;
pub mod material;
mod packed;
mod pairs;
mod path_lanes;
pub mod rng;
mod tri_lanes;
mod wide;

#[cfg(test)]
mod pinned;
#[cfg(test)]
mod tests;

pub use camera::Camera;
pub use film::Image;
pub use geometry::{
    AaBox, BoxSet, BvhKind, Geometry, Mesh, MeshInstance, OrientedBox, Quad, Sphere,
};
pub use integrator::{render, render_counted, Settings, Work};
pub use light::{Lights, PointLight};
pub use material::{Material, Texture};

/// Everything needed to render one image.
pub struct Scene {
    /// The view.
    pub camera: Camera,
    /// The shapes.
    pub geometry: Geometry,
    /// Materials, indexed by the shapes' `material`.
    pub materials: Vec<Material>,
    /// Textures, indexed by `Material::Diffuse::texture`.
    pub textures: Vec<Texture>,
    /// The lights.
    pub lights: Lights,
}
