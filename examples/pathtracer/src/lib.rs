//! The paper's inverse-rendering tasks, solved with the plateau-free gradient of the
//! [`plateau_free`] crate on a small CPU path tracer.
//!
//! - [`render`]: the path tracer (camera, geometry, materials, lights, integrator, film).
//! - [`tasks`]: the paper's seven scenes behind one [`tasks::Task`] trait.
//! - [`run`]: one optimisation of a task, with its outputs.
//! - [`report`]: plots, CSV, JSON and markdown tables.
//! - [`experiments`]: the supplemental's experiments, one page each.
//! - [`export`]: a task's scene written for another renderer (Mitsuba 3).
//! - [`cli`]: the command line.

pub mod cli;
pub mod experiments;
pub mod export;
pub mod render;
pub mod report;
pub mod run;
pub mod tasks;
