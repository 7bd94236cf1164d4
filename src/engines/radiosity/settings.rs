//! What the radiosity engine reads besides the scene and the common settings: its flags'
//! values, with their defaults (the course program's where it has one). A leaf: it imports
//! nothing of the engines, so the common settings can hold it.

/// Settings only the radiosity engine reads. Defaults are the course program's where it has one.
#[derive(Clone, Debug, PartialEq)]
pub struct RadiositySettings {
    /// Point pairs per form factor (`-num_form_factor_samples`, default 1: the patch centres).
    pub num_form_factor_samples: u32,
    /// Sphere tessellation H V (`-sphere_rasterization`, default 8 6).
    pub sphere_rasterization: (u32, u32),
    /// Ring tessellation around the axis (`-cylinder_ring_rasterization`, default 20).
    pub cylinder_ring_rasterization: u32,
    /// Split every quad into four this many times (`--subdivide`, default 0).
    pub subdivide: u32,
    /// Subdivide further, as far as the time left allows: the progressive solver solves
    /// at `subdivide`, then once more subdivided while the next solve (predicted as 16× the
    /// last: four times the patches, each reaching four times as many) fits in this share
    /// of the time left (set by `--time-limit` when `--subdivide` is not given; default
    /// None: solve at `subdivide`).
    pub subdivide_to_fit: Option<f64>,
    /// Smooth display: values interpolated from the patches around each vertex
    /// (`-interpolate`, default off: flat patches).
    pub interpolate: bool,
    /// Stop when undistributed power / emitted power falls to this (`--radiosity-tolerance`,
    /// default 1e-3).
    pub tolerance: f32,
    /// Stop after exactly this many shots (`--radiosity-iterations`, default: none).
    pub iterations: Option<u64>,
    /// Safety cap on shots per patch when no iteration count is given
    /// (`--radiosity-max-shots-per-patch`, default 1000); reaching it is reported.
    pub max_shots_per_patch: u64,
    /// Over-relaxation of each shot (`--radiosity-relaxation auto|ω`, default auto: ω from
    /// how much of each shot comes back; 1 is plain progressive refinement; see
    /// `Relaxation`).
    pub relaxation: Relaxation,
    /// Memory for cached form-factor rows, MiB (`--ff-cache-mb`, default 1024).
    pub ff_cache_mb: usize,
    /// Split patches whose radiance differs from a neighbour's by more than this (largest
    /// channel) and solve again (`--adaptive-subdivide`, default: off).
    pub adaptive_threshold: Option<f32>,
    /// Rounds of adaptive splitting (`--adaptive-rounds`, default 3).
    pub adaptive_rounds: u32,
    /// Patch outlines over the image (`--wireframe`).
    pub wireframe: bool,
    /// The patch whose form factors `--visualize form-factors` shows (`--ff-source`,
    /// default: the patch with the most undistributed light).
    pub ff_source: Option<u32>,
    /// Keep a record of every shot (`--log-convergence`).
    pub log_convergence: bool,
    /// What the image shows (`--visualize`, default radiance: the solution).
    pub display: Display,
    /// Write the solved patches to this PLY file (`--export-radiosity`, default: none).
    pub export: Option<std::path::PathBuf>,
    /// Write the solution to this file after solving (`--save-radiosity`, default: none).
    pub save: Option<std::path::PathBuf>,
    /// Read the solution from this file instead of solving (`--load-radiosity`, default:
    /// none); refused if made for another scene or other settings.
    pub load: Option<std::path::PathBuf>,
    /// Which solver (`--radiosity-solver`, default auto: hierarchical above
    /// `HIERARCHICAL_ABOVE` input patches, progressive up to it).
    pub solver: SolverKind,
    /// Hierarchical: refine a link that carries more than this fraction of the largest
    /// emitted power (`--link-error`, default 1e-4).
    pub link_error: f32,
    /// Hierarchical: elements smaller than this fraction of the scene's area are not split
    /// (`--min-element-area`, default 1e-5).
    pub min_element_area: f32,
    /// Hierarchical: with more input patches than this, linking starts from the root
    /// cluster linked to itself; up to it, from every pair of patches, which needs no
    /// cluster estimate (`--cluster-above`, default 2000).
    pub cluster_above: usize,
    /// Hierarchical: bytes the links and elements may take; refinement stops splitting
    /// there, with a warning (the command line gives what `--max-memory` leaves after the
    /// plan's estimate of the rest; default: no limit).
    pub memory_budget: u64,
}

/// Shadow rays a light when `-num_shadow_samples` is not given (and neither `--time-limit`
/// nor the scene file chooses): one, which turns on visibility in the form factors, as
/// RenderPark always computes it. Without it patches see light through one another: on the
/// Cornell box with the diffuse sphere the mean is 24% above the path tracer's (2.6% with
/// it, both in 0.01 s), and in a room of boxes (`render gen-room 3000`) the light that goes
/// round grows without bound, until the solve stops as diverged (1.7 s; with visibility it
/// converges in 1.1 s).
pub const SHADOW_SAMPLES: u32 = 1;

/// Shadow rays a light for the ray tracer with a radiosity solution as its indirect light
/// (`--indirect radiosity`) when `-num_shadow_samples` is not given (and neither
/// `--time-limit` nor the scene file chooses): 16, as `--time-limit` chooses, soft shadows
/// and visibility in the solve, where the course's 0 leaves both out. relMSE against the
/// path tracer: the Cornell box with the diffuse sphere 0.55 with 0 (mean 27% high), 9.7e-2
/// with 1, 5.1e-2 with 16 (0.10 s); a room of boxes (`render gen-room 300`) diverged with 0,
/// 5.9e-2 with 1 (0.03 s), 4.8e-2 with 16 (0.13 s).
pub const INDIRECT_SHADOW_SAMPLES: u32 = 16;

/// `--radiosity-solver auto` chooses the hierarchical solver for scenes of more input
/// patches (their own faces, before `--subdivide`) than this: the course's scenes (a few
/// hundred) keep the progressive solver and their images, buildings get the one whose cost
/// grows about linearly.
pub const HIERARCHICAL_ABOVE: usize = 5000;

/// The radiosity solvers (`--radiosity-solver`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum SolverKind {
    /// Hierarchical above `HIERARCHICAL_ABOVE` input patches, progressive up to it.
    #[default]
    Auto,
    /// Progressive refinement: shoot the patch with the most undistributed power, N² form
    /// factors at most; the course's solver.
    Progressive,
    /// Hierarchical radiosity with clustering: links between clusters and element
    /// quadtrees refined by the power they carry, Jacobi sweeps over them.
    Hierarchical,
}

impl SolverKind {
    /// The solver that runs on a mesh of `patches` input patches.
    pub fn resolve(self, patches: usize) -> SolverKind {
        match self {
            SolverKind::Auto if patches > HIERARCHICAL_ABOVE => SolverKind::Hierarchical,
            SolverKind::Auto => SolverKind::Progressive,
            chosen => chosen,
        }
    }
}

impl std::fmt::Display for SolverKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SolverKind::Auto => "auto",
            SolverKind::Progressive => "progressive",
            SolverKind::Hierarchical => "hierarchical",
        })
    }
}

impl RadiositySettings {
    /// How finely the mesh approximates the scene's analytic shapes.
    pub fn tessellation(&self) -> crate::geometry::Tessellation {
        crate::geometry::Tessellation {
            sphere: self.sphere_rasterization,
            ring: self.cylinder_ring_rasterization,
        }
    }
}

impl Default for RadiositySettings {
    fn default() -> Self {
        RadiositySettings {
            num_form_factor_samples: 1,
            sphere_rasterization: (8, 6),
            cylinder_ring_rasterization: 20,
            subdivide: 0,
            subdivide_to_fit: None,
            interpolate: false,
            tolerance: 1e-3,
            iterations: None,
            max_shots_per_patch: 1000,
            relaxation: Relaxation::Auto,
            ff_cache_mb: 1024,
            adaptive_threshold: None,
            adaptive_rounds: 3,
            wireframe: false,
            ff_source: None,
            log_convergence: false,
            save: None,
            load: None,
            display: Display::Radiance,
            export: None,
            solver: SolverKind::Auto,
            link_error: 1e-4,
            min_element_area: 1e-5,
            cluster_above: 2000,
            memory_budget: u64::MAX,
        }
    }
}

/// What the radiosity engine shows (`--visualize`): the solution, or one of the course's
/// views of the mesh and the solver's state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Display {
    /// The solution: radiance of each patch plus the ambient term for light not yet shot.
    #[default]
    Radiance,
    /// Each patch's albedo.
    Materials,
    /// Form factors from one patch (`--ff-source`) to every other, grey by relative size.
    FormFactors,
    /// Emitted radiance.
    Lights,
    /// Radiance received but not yet shot.
    Undistributed,
    /// Radiance absorbed: (1 − ρ) × incident.
    Absorbed,
}

/// The over-relaxation factor ω of each shot (`--radiosity-relaxation`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Relaxation {
    /// ω from the solve itself: the fraction μ of a shot's power that comes back as unshot
    /// power (a running mean over the shots: ρ in a furnace, less where light escapes) gives
    /// successive over-relaxation's ω = 2 / (1 + √(1 − μ²)), at most 1.95. Open and dark
    /// scenes get ω near 1 (plain shooting); bright closed rooms get ω near 2.
    Auto,
    /// A fixed ω in [1, 2); 1 is plain progressive refinement.
    Fixed(f32),
}

impl std::fmt::Display for Relaxation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Relaxation::Auto => f.write_str("auto"),
            Relaxation::Fixed(w) => write!(f, "{w}"),
        }
    }
}

impl std::str::FromStr for Relaxation {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "auto" {
            return Ok(Relaxation::Auto);
        }
        match s.parse::<f32>() {
            Ok(w) if (1.0..2.0).contains(&w) => Ok(Relaxation::Fixed(w)),
            _ => Err(format!("expected auto or a number in [1, 2), found {s}")),
        }
    }
}
