//! The one interface every engine asks its visibility questions of, and its two
//! implementations: Intel Embree (feature `embree`) and trilux's own BVH.

pub mod bvh;
#[cfg(feature = "embree")]
#[allow(unsafe_code)]
pub mod embree;
mod lanes;
mod pages;
mod tri4;

use std::fmt;

use crate::geometry::Ray;
pub use crate::scene::{PrimHit, SurfaceHit};
use crate::scene::{PrimKind, PrimRef, Scene};

/// Visibility queries over one scene's primitives. Implementations are immutable once built
/// and safe to query from many threads at once.
pub trait Accel: Send + Sync {
    /// Which backend this is ("embree" or "bvh").
    fn name(&self) -> &'static str;

    /// The closest hit of `ray` in `(ray.t_min, ray.t_max)`.
    fn intersect(&self, ray: &Ray) -> Option<PrimHit>;

    /// Whether anything is hit in `(ray.t_min, ray.t_max)`.
    fn occluded(&self, ray: &Ray) -> bool;

    /// `intersect` for many rays; `hits` must be as long as `rays`.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<PrimHit>]) {
        for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
            *hit = self.intersect(ray);
        }
    }

    /// `occluded` for many rays; `occluded` must be as long as `rays`.
    fn occluded_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        for (ray, o) in rays.iter().zip(occluded.iter_mut()) {
            *o = self.occluded(ray);
        }
    }
}

/// The closest hit of `ray` with its full surface (point, normals, texture coordinates).
pub fn closest_surface(accel: &dyn Accel, scene: &Scene, ray: &Ray) -> Option<SurfaceHit> {
    accel.intersect(ray).map(|h| scene.surface(ray, &h))
}

/// Which backend to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum AccelKind {
    Embree,
    Bvh,
}

/// Scenes of at most this many primitives get the BVH when `--accel` is not given. Up to here
/// the BVH was as fast as Embree or faster in every engine measured (BENCHMARKS.md, "Which
/// Accel by default"): the path tracer 1.25× on 1,000 quads and 1.66× on the Cornell box,
/// whose sphere Embree reaches through a user-geometry callback; above it Embree's build and
/// traversal win for the engines that follow rays (the path tracer on Mitsuba's 130,050
/// triangles, 1.09×). Radiosity's visibility rays are the exception (`default_for`).
pub const BVH_UP_TO_PRIMITIVES: usize = 1_000;

impl AccelKind {
    /// Embree when this build has it, else the BVH.
    pub fn default_available() -> AccelKind {
        if cfg!(feature = "embree") {
            AccelKind::Embree
        } else {
            AccelKind::Bvh
        }
    }

    /// The backend when `--accel` is not given: the BVH for a scene of at most
    /// `BVH_UP_TO_PRIMITIVES` primitives, and for the visibility between radiosity's patches
    /// (`patch_visibility`) at any size, else `default_available`. On radiosity the BVH took
    /// Embree's time within 4% on the hospital, office3 and the classroom (either solver),
    /// 1.09× on soda and 0.77× on sixteen hospitals, where Embree's time grew 16.8-fold to the
    /// BVH's 12.8-fold (BENCHMARKS.md, "Sixteen hospitals").
    pub fn default_for(scene: &Scene, patch_visibility: bool) -> AccelKind {
        if patch_visibility || scene.primitive_count() <= BVH_UP_TO_PRIMITIVES {
            AccelKind::Bvh
        } else {
            AccelKind::default_available()
        }
    }
}

impl fmt::Display for AccelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            AccelKind::Embree => "embree",
            AccelKind::Bvh => "bvh",
        })
    }
}

/// Embree's build quality (`--embree-quality`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum EmbreeQuality {
    Low,
    #[default]
    Medium,
    High,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AccelOptions {
    /// Embree's build quality (default medium).
    pub embree_quality: EmbreeQuality,
    /// Embree's robust (watertight) mode (default on). Off, Embree is a little faster but
    /// lets rays through the diagonal of a quad and through shared edges: visible as single
    /// background pixels on the walls of the course's Cornell box, and a light leak.
    pub embree_robust: bool,
    /// Embree's candidate hits decided by trilux's exact routines, the BVH's (default on):
    /// both backends then answer the same primitive at the same t for every ray, and render
    /// the same images. Off, Embree's own test decides, and a ray through an edge two
    /// primitives share may land on the other one (one pixel in 65,536 of the course's
    /// Cornell box, path traced); Embree is then faster (BENCHMARKS.md, "`--embree-exact`").
    pub embree_exact: bool,
}

impl Default for AccelOptions {
    fn default() -> Self {
        AccelOptions {
            embree_quality: EmbreeQuality::Medium,
            embree_robust: true,
            embree_exact: true,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum AccelError {
    #[error("{0}")]
    Embree(String),
    #[error("this build of trilux has no Embree backend (built without the `embree` feature); use --accel bvh")]
    EmbreeUnavailable,
    #[error("the scene has too many primitives for one acceleration structure ({0})")]
    TooLarge(usize),
}

/// Builds the chosen backend over the scene's primitives.
pub fn build(
    scene: &Scene,
    kind: AccelKind,
    options: &AccelOptions,
) -> Result<Box<dyn Accel>, AccelError> {
    match kind {
        AccelKind::Bvh => Ok(Box::new(bvh::Bvh::build(scene)?)),
        #[cfg(feature = "embree")]
        AccelKind::Embree => Ok(Box::new(embree::EmbreeAccel::build(scene, options)?)),
        #[cfg(not(feature = "embree"))]
        AccelKind::Embree => {
            // The options are Embree's alone.
            let _ = options;
            Err(AccelError::EmbreeUnavailable)
        }
    }
}

/// Primitive references packed in 32 bits: the kind in the top `KIND_BITS` bits, the index
/// below. A kind that does not fit stops the build (the assertion below), rather than being
/// decoded as another.
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(transparent)]
pub(crate) struct PackedPrim(u32);

/// Bits of a packed primitive that hold its kind.
const KIND_BITS: u32 = 2;
const _: () = assert!(PrimKind::ALL.len() <= 1 << KIND_BITS);

impl PackedPrim {
    pub const MAX_INDEX: u32 = (1 << (32 - KIND_BITS)) - 1;

    pub fn new(prim: PrimRef) -> PackedPrim {
        PackedPrim((prim.kind as u32) << (32 - KIND_BITS) | prim.index)
    }
    #[inline]
    pub fn kind(self) -> PrimKind {
        PrimKind::ALL[(self.0 >> (32 - KIND_BITS)) as usize]
    }
    #[inline]
    pub fn index(self) -> u32 {
        self.0 & Self::MAX_INDEX
    }
    /// The packed bits: the order both backends break ties in (kind, then index).
    #[inline]
    pub fn raw(self) -> u32 {
        self.0
    }
    #[inline]
    pub fn unpack(self) -> PrimRef {
        PrimRef {
            kind: self.kind(),
            index: self.index(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_primitive_kind_packs_and_unpacks_as_itself() {
        for (k, &kind) in PrimKind::ALL.iter().enumerate() {
            assert_eq!(kind as usize, k, "PrimKind::ALL is in discriminant order");
            for index in [0, 1, PackedPrim::MAX_INDEX] {
                let prim = PrimRef { kind, index };
                assert_eq!(PackedPrim::new(prim).unpack(), prim);
            }
        }
    }
}
