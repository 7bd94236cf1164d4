//! trilux: an offline renderer with three lighting engines (ray tracing, radiosity, photon
//! mapping) over one accelerated visibility core — Intel Embree or trilux's own BVH.
//!
//! The data flow: [`scene::Scene::load`] → [`plan::Plan`] → [`accel::build`] → an engine in
//! [`engines`] → [`film::Film`]. `docs/architecture.md` has the layers and where to change what.

// `unsafe` is for the Embree FFI alone (`accel::embree`, which allows it, each block with its
// `// SAFETY:` reason).
#![deny(unsafe_code)]

pub mod accel;
pub mod bench;
pub mod bytes;
pub mod camera;
pub mod cli;
pub mod color;
pub mod engines;
pub mod farm;
pub mod film;
pub mod generate;
pub mod geometry;
pub mod image_io;
pub mod interrupt;
pub mod output;
pub mod parallel;
pub mod plan;
pub mod progress;
pub mod render;
pub mod report;
pub mod sampling;
pub mod scene;
pub mod simd;
pub mod viewer;
