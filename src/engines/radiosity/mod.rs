//! Radiosity on a quad mesh: patches from the scene's quads (spheres and rings rasterized),
//! form factors by exact point-to-patch integration with visibility rays through the `Accel`
//! against the original geometry, progressive refinement with the ambient term, and the
//! solved mesh seen from the camera in several visualization modes.

pub mod file;
pub mod hierarchical;
pub mod mesh;
pub mod patch;
pub mod progressive;
pub mod settings;
pub mod solver;

mod display;
mod export;
mod outside_lights;
pub use settings::{Display, RadiositySettings, SolverKind};

use rayon::prelude::*;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::OnceLock;

pub use display::{render_solution, Samples, SeenMesh};
use patch::Patch;
use solver::{FormFactorSampler, PatchLight, RadiositySolver, SolveLimits, Step, Stop};

use super::engine::{Budget, Engine, EngineKind, EnginePlan, PrePass, RenderSettings, Rendered};
use crate::accel::Accel;
use crate::engines::radiosity::mesh::{QuadMesh, NONE};
use crate::film::Film;
use crate::geometry::{Shape, Vec3};
use crate::render::{IndirectLight, RenderStats};
use crate::sampling::Rng;
use crate::scene::{Color, PrimKind, Scene, SurfaceHit};

/// A solved radiosity mesh.
#[derive(Clone, Debug)]
pub struct Solution {
    pub mesh: QuadMesh,
    pub patches: Vec<Patch>,
    /// For each mesh face, its patch (`NONE` for faces that were split).
    patch_of_face: Vec<u32>,
    /// The light the solver found on the patches.
    pub state: PatchLight,
    pub stop: Stop,
    /// Cohen's ambient term for the light not yet shot.
    pub ambient: Color,
    /// Whether form factors were tested for visibility, and why (not).
    pub visibility: bool,
    pub visibility_reason: &'static str,
    /// Visibility rays cast, over all rounds.
    pub rays: u64,
    /// The solver's own counters, for the summary line.
    pub solver_report: String,
    /// The same as named counters, for `--stats`.
    pub solver_counters: Vec<(&'static str, u64)>,
    /// The solver's warning, if it had one.
    pub solver_warning: Option<String>,
    /// Rounds of adaptive subdivision done.
    pub adaptive_rounds: u32,
    /// The faces split in each round where the lights without area light them unevenly, then
    /// in each round of adaptive subdivision, in order: with the scene and the settings, what
    /// rebuilds the mesh of a saved solution.
    pub splits: Vec<Vec<u32>>,
    /// How many times the scene's faces were split in four (`--subdivide`, or the level
    /// `subdivide_to_fit` reached).
    pub subdivide: u32,
    /// The solver that ran (`--radiosity-solver auto` resolved).
    pub solver: SolverKind,
    /// Patches that coincide with an earlier one (`patch::twins`), solved as one.
    pub twins: usize,
}

/// The patches a solver shoots between: the solution's, coincident twins given no area and
/// the light they reflect of the sky and of the lights without area added to their emission.
struct Shooters {
    patches: Vec<Patch>,
    /// For each patch, the earlier patch it coincides with (`NONE` for none).
    twin_of: Vec<u32>,
    /// Rays cast to find the light reflected of the sky and of the lights without area.
    outside_rays: u64,
    /// The form factors' ray anchors (`FormFactorSampler::anchors`) with the number of
    /// samples, the visibility and the seed they were found for: made by the first sampler,
    /// taken by the next ones (a solve shot on a shot at a time, as the viewer's Space does,
    /// makes a sampler a shot).
    anchors: OnceLock<((u32, bool, u64), Vec<Vec3>)>,
}

impl Shooters {
    /// The form factors between the patches.
    fn sampler<'a>(
        &'a self,
        scene: &'a Scene,
        accel: &'a dyn Accel,
        settings: &RenderSettings,
        visibility: bool,
    ) -> FormFactorSampler<'a> {
        let samples = settings.radiosity.num_form_factor_samples.max(1);
        let key = (samples, visibility, settings.seed);
        let (made_for, anchors) = self.anchors.get_or_init(|| {
            let anchors =
                FormFactorSampler::anchors(scene, &self.patches, samples, visibility, key.2);
            (key, anchors)
        });
        FormFactorSampler::new(
            scene,
            accel,
            &self.patches,
            samples,
            visibility,
            settings.seed,
            (*made_for == key).then_some(anchors.as_slice()),
        )
    }

    /// When the settings stop a solve of these patches.
    fn limits(&self, settings: &RenderSettings) -> SolveLimits {
        let r = &settings.radiosity;
        SolveLimits {
            tolerance: r.tolerance,
            iterations: r.iterations,
            cap: r
                .max_shots_per_patch
                .saturating_mul(self.patches.len() as u64),
            log: r.log_convergence,
            // The solve takes four fifths of what is left of `--time-limit`; the pixels
            // the rest.
            deadline: settings.deadline.map(|d| {
                let now = std::time::Instant::now();
                now + d.saturating_duration_since(now).mul_f64(0.8)
            }),
        }
    }
}

/// A progressive solve kept between images, as the viewer keeps it: shot on a few shots at a
/// time (`shoot_to`), each time shown (`solution`). After n shots in all, however they were
/// split, its solution is the one `Solution::solve` finds with `--radiosity-iterations n`,
/// bit for bit.
pub struct ProgressiveSolve {
    solution: Solution,
    shooters: Shooters,
    solver: progressive::Progressive,
    shooting: progressive::Shooting,
    /// Visibility rays the shots so far cast.
    form_factor_rays: u64,
}

impl ProgressiveSolve {
    /// The solve `settings` ask for, before its first shot; None where that solve cannot be
    /// taken a few shots at a time: another solver, a solution loaded or saved, adaptive
    /// subdivision (which solves again on a finer mesh), or a time limit (which makes the
    /// shots taken depend on the clock).
    pub fn new(
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Option<ProgressiveSolve> {
        let r = &settings.radiosity;
        if r.load.is_some()
            || r.save.is_some()
            || r.adaptive_threshold.is_some()
            || settings.deadline.is_some()
        {
            return None;
        }
        let (mut mesh, kind) = Solution::initial_mesh(scene, r, r.subdivide);
        if kind != SolverKind::Progressive {
            return None;
        }
        let lit = outside_lights::split_where_unevenly_lit(scene, accel, &mut mesh);
        let (mut solution, shooters) = Solution::unsolved(scene, accel, settings, mesh, kind);
        solution.splits = lit;
        let solver = progressive::Progressive {
            cache_bytes: r.ff_cache_mb << 20,
            relaxation: r.relaxation,
        };
        let shooting = solver.start(&shooters.patches);
        let mut solve = ProgressiveSolve {
            solution,
            shooters,
            solver,
            shooting,
            form_factor_rays: 0,
        };
        // The light before any shot, shown as zero shots.
        solve.shoot_to(
            scene,
            accel,
            &RenderSettings {
                radiosity: RadiositySettings {
                    iterations: Some(0),
                    ..r.clone()
                },
                ..settings.clone()
            },
        );
        Some(solve)
    }

    /// Shots taken so far.
    pub fn shots(&self) -> u64 {
        self.shooting.light().iterations
    }

    /// Shoots on until `settings` stop the solve, counting the shots already taken
    /// (`--radiosity-iterations` is the shots in all). The settings are those the solve was
    /// started with, but for the shots (and how the solution is shown).
    pub fn shoot_to(&mut self, scene: &Scene, accel: &dyn Accel, settings: &RenderSettings) {
        let shooters = &self.shooters;
        let sampler = shooters.sampler(scene, accel, settings, self.solution.visibility);
        let stop = self.solver.shoot(
            &mut self.shooting,
            &sampler,
            &shooters.limits(settings),
            &|_| {},
        );
        self.form_factor_rays += sampler.rays.load(Relaxed);
        self.solution.take_light(
            self.shooting.solved(stop),
            &self.shooters,
            self.form_factor_rays,
        );
    }

    /// The solution as the shots so far leave it.
    pub fn solution(&self) -> &Solution {
        &self.solution
    }
}

/// `subdivide_to_fit` stops here whatever the time: 4⁸ patches from each face.
const MAX_SUBDIVIDE_TO_FIT: u32 = 8;

/// Values over the patches of a solution, or over the leaf elements of a hierarchical one,
/// looked up at hits by `Solution::sample`.
#[derive(Clone, Debug)]
pub struct PatchField {
    values: Vec<Color>,
    corners: Option<Vec<[Color; 4]>>,
    /// `values` are per element of `PatchLight::elements` (shown at the leaves).
    per_element: bool,
}

/// For each mesh face, its patch (`NONE` for faces that were split).
fn patch_of_face(mesh: &QuadMesh, patches: &[Patch]) -> Vec<u32> {
    let mut of_face = vec![NONE; mesh.faces.len()];
    for (k, p) in patches.iter().enumerate() {
        of_face[p.face as usize] = k as u32;
    }
    of_face
}

/// Whether every quad of the scene lies in front of (or on) every other quad's plane and there
/// is nothing else: then the scene is the inside of a convex polyhedron and no segment between
/// two of its points can be blocked. Scenes of more than `LIMIT` quads are not checked.
pub fn convex_enclosure(scene: &Scene) -> bool {
    const LIMIT: usize = 4096;
    if !scene.triangles.is_empty()
        || !scene.instancing.instances.is_empty()
        || !scene.shapes.is_empty()
        || scene.quads.is_empty()
        || scene.quads.len() > LIMIT
    {
        return false;
    }
    let scale = scene.bounds().extent().length();
    scene.quads.iter().all(|q| {
        scene.quads.iter().all(|o| {
            o.vertices
                .iter()
                .all(|&p| (p - q.vertices[0]).dot(q.normal) >= -1e-5 * scale)
        })
    })
}

/// The solver of `kind` (resolved from `--radiosity-solver`) with the settings' parameters.
fn solver(r: &RadiositySettings, kind: SolverKind) -> Box<dyn RadiositySolver> {
    match kind {
        SolverKind::Hierarchical => Box::new(hierarchical::Hierarchical {
            link_error: r.link_error,
            min_element_area: r.min_element_area,
            cluster_above: r.cluster_above,
            memory_budget: r.memory_budget,
        }),
        _ => Box::new(progressive::Progressive {
            cache_bytes: r.ff_cache_mb << 20,
            relaxation: r.relaxation,
        }),
    }
}

impl Solution {
    /// Builds the mesh, solves, and (with `--adaptive-subdivide`) refines and solves again;
    /// or, with `subdivide_to_fit`, solves at finer levels while the time allows.
    pub fn solve(
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
        on_progress: impl Fn(f32),
    ) -> Solution {
        let r = &settings.radiosity;
        let (mesh, kind) = Solution::initial_mesh(scene, r, r.subdivide);
        match (settings.deadline, r.subdivide_to_fit) {
            (Some(deadline), Some(share)) if kind == SolverKind::Progressive => {
                Solution::solve_finest_in_time(
                    scene,
                    accel,
                    settings,
                    (mesh, share),
                    deadline,
                    on_progress,
                )
            }
            _ => {
                let mut mesh = mesh;
                let lit = outside_lights::split_where_unevenly_lit(scene, accel, &mut mesh);
                Solution::solve_adaptively(scene, accel, settings, (mesh, lit), kind, on_progress)
            }
        }
    }

    /// Solves on `mesh`, split already in the rounds of `splits` (where the lights without
    /// area light it unevenly), then, with `--adaptive-subdivide`, splits the patches whose
    /// radiance differs from a neighbour's and solves again, `--adaptive-rounds` times.
    fn solve_adaptively(
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
        (mut mesh, mut splits): (QuadMesh, Vec<Vec<u32>>),
        kind: SolverKind,
        on_progress: impl Fn(f32),
    ) -> Solution {
        let r = &settings.radiosity;
        let mut rays = 0;
        let lit_rounds = splits.len();
        loop {
            let mut solution =
                Solution::solve_mesh(scene, accel, settings, mesh, kind, &on_progress);
            rays += solution.rays;
            solution.rays = rays;
            solution.splits = splits.clone();
            let adaptive_rounds = splits.len() - lit_rounds;
            solution.adaptive_rounds = adaptive_rounds as u32;
            let Some(threshold) = r.adaptive_threshold else {
                return solution;
            };
            let split = if adaptive_rounds < r.adaptive_rounds as usize {
                solution.patches_to_split(threshold)
            } else {
                Vec::new()
            };
            if split.is_empty() {
                return solution;
            }
            mesh = solution.mesh;
            mesh.split_many(&split);
            splits.push(split);
        }
    }

    /// `subdivide_to_fit`: solves on `mesh`, then subdivided once more while the solve
    /// converged and the next one is predicted to fit in `share` of the time left before
    /// `deadline`. The prediction is 16× the last solve's time: a progressive solve
    /// shoots a number of times that grows with the patches, and each shot reaches every
    /// patch (measured on the Cornell box with visibility: 8.4× from 864 to 3,456 patches,
    /// so 16× errs on the side of the time left for the pixels). The coarser solves cost
    /// about a fifteenth of the one kept.
    fn solve_finest_in_time(
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
        (mut unsplit, share): (QuadMesh, f64),
        deadline: std::time::Instant,
        on_progress: impl Fn(f32),
    ) -> Solution {
        let mut level = settings.radiosity.subdivide;
        let mut rays = 0;
        let lights_without_area = !scene.delta_lights.is_empty();
        loop {
            let started = std::time::Instant::now();
            // Each level is split anew where lights without area light it unevenly (the
            // splits a saved solution replays on the mesh of its level).
            let (mesh, lit) = if lights_without_area {
                let mut mesh = unsplit.clone();
                let lit = outside_lights::split_where_unevenly_lit(scene, accel, &mut mesh);
                (mesh, lit)
            } else {
                (std::mem::take(&mut unsplit), Vec::new())
            };
            let mut solution = Solution::solve_mesh(
                scene,
                accel,
                settings,
                mesh,
                SolverKind::Progressive,
                &on_progress,
            );
            rays += solution.rays;
            solution.rays = rays;
            solution.subdivide = level;
            solution.splits = lit;
            let predicted = started.elapsed().mul_f64(16.0);
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            if solution.stop != Stop::Converged
                || level >= MAX_SUBDIVIDE_TO_FIT
                || predicted > left.mul_f64(share)
            {
                return solution;
            }
            // The solve keeps its mesh as it was given: without light splits, split that
            // once more.
            if !lights_without_area {
                unsplit = solution.mesh;
            }
            unsplit.subdivide(1);
            level += 1;
        }
    }

    /// One solve of `kind` on `mesh`.
    fn solve_mesh(
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
        mesh: QuadMesh,
        kind: SolverKind,
        on_progress: &impl Fn(f32),
    ) -> Solution {
        let (mut solution, shooters) = Solution::unsolved(scene, accel, settings, mesh, kind);
        let sampler = shooters.sampler(scene, accel, settings, solution.visibility);
        let limits = shooters.limits(settings);
        let solved = solver(&settings.radiosity, kind).solve(&sampler, &limits, on_progress);
        solution.take_light(solved, &shooters, sampler.rays.load(Relaxed));
        solution
    }

    /// A solution on `mesh` before its solver has run (no light yet), and the patches the
    /// solver shoots between.
    fn unsolved(
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
        mesh: QuadMesh,
        kind: SolverKind,
    ) -> (Solution, Shooters) {
        let (visibility, visibility_reason) = Solution::visibility(scene, settings);
        let patches = patch::patches(scene, &mesh);
        // Coincident twins take no part: the solvers see them with no area.
        let twin_of = patch::twins(&patches);
        let twins = twin_of.iter().filter(|&&t| t != NONE).count();
        let mut solved_patches = patches.clone();
        for (p, &t) in solved_patches.iter_mut().zip(&twin_of) {
            if t != NONE {
                p.area = 0.0;
            }
        }
        // The light the patches reflect of the sky and of the lights without area enters
        // the solve as their own emission.
        let mut outside_rays = 0;
        if outside_lights::any(scene) {
            let (reflected, rays) =
                outside_lights::reflected(scene, accel, &solved_patches, settings.seed);
            for (p, r) in solved_patches.iter_mut().zip(reflected) {
                p.emitted += r;
            }
            outside_rays = rays;
        }
        let solution = Solution {
            patch_of_face: patch_of_face(&mesh, &patches),
            mesh,
            patches,
            state: PatchLight::default(),
            stop: Stop::NoLight,
            ambient: Vec3::ZERO,
            visibility,
            visibility_reason,
            rays: outside_rays,
            solver_report: String::new(),
            solver_counters: Vec::new(),
            solver_warning: None,
            adaptive_rounds: 0,
            splits: Vec::new(),
            subdivide: settings.radiosity.subdivide,
            solver: kind,
            twins,
        };
        let shooters = Shooters {
            patches: solved_patches,
            twin_of,
            outside_rays,
            anchors: OnceLock::new(),
        };
        (solution, shooters)
    }

    /// Takes the light a solver found on `shooters`, which cast `form_factor_rays`
    /// visibility rays for it.
    fn take_light(&mut self, solved: solver::Solved, shooters: &Shooters, form_factor_rays: u64) {
        let mut state = solved.light;
        state.copy_twins(&shooters.twin_of);
        self.ambient = solver::ambient(&shooters.patches, &state.undistributed);
        self.state = state;
        self.stop = solved.stop;
        self.rays = form_factor_rays + shooters.outside_rays;
        self.solver_report = solved.report;
        self.solver_counters = solved.counters;
        self.solver_warning = solved.warning;
    }

    /// The mesh a solve starts from: the scene's faces, subdivided `subdivide` times; and
    /// the solver `auto` chooses for it, by the scene's own faces (before subdividing).
    fn initial_mesh(
        scene: &Scene,
        r: &RadiositySettings,
        subdivide: u32,
    ) -> (QuadMesh, SolverKind) {
        let mut mesh = QuadMesh::from_scene(scene, r.tessellation());
        let kind = r.solver.resolve(mesh.leaves.len());
        mesh.subdivide(subdivide);
        (mesh, kind)
    }

    /// Whether form factors are tested for visibility, and why (not).
    fn visibility(scene: &Scene, settings: &RenderSettings) -> (bool, &'static str) {
        if settings.num_shadow_samples == 0 {
            (false, "off (-num_shadow_samples 0)")
        } else if convex_enclosure(scene) {
            (false, "skipped: the scene is a convex enclosure")
        } else {
            (true, "one occlusion ray per point pair")
        }
    }

    /// Faces of patches whose radiance differs from a neighbour's (across an edge or a corner)
    /// by more than `threshold` in some channel.
    fn patches_to_split(&self, threshold: f32) -> Vec<u32> {
        let around = self.mesh.vertex_leaves();
        let radiance = &self.state.radiance;
        let differs = |a: usize, b: u32| {
            let q = self.patch_of_face[b as usize];
            q != NONE && (radiance[a] - radiance[q as usize]).abs().max_element() > threshold
        };
        self.patches
            .iter()
            .enumerate()
            .filter(|(k, p)| {
                p.area > 0.0
                    && (self.mesh.edge_neighbours(p.face).any(|f| differs(*k, f))
                        || self
                            .mesh
                            .face_vertex_ids(p.face)
                            .iter()
                            .any(|&v| around[v as usize].iter().any(|&f| differs(*k, f))))
            })
            .map(|(_, p)| p.face)
            .collect()
    }

    /// The radiance shown for each patch: solved radiance plus the ambient term reflected.
    pub fn display_radiance(&self) -> Vec<Color> {
        self.patches
            .iter()
            .zip(&self.state.radiance)
            .map(|(p, l)| *l + p.albedo * self.ambient)
            .collect()
    }

    /// Indirect incident radiance (irradiance / π not straight from emitters) for each patch,
    /// the ambient term included: what a ray tracer adds at diffuse hits instead of
    /// `-ambient_light` (`--indirect radiosity`).
    pub fn indirect_incident(&self) -> Vec<Color> {
        self.state
            .incident
            .iter()
            .zip(&self.state.incident_direct)
            .map(|(i, d)| (*i - *d).max(Vec3::ZERO) + self.ambient)
            .collect()
    }

    /// The patch under a surface hit seen from the side `toward` points to (a polygon's back
    /// with `--two-sided`), and the hit's parameters within that patch. None behind a polygon
    /// whose material is a one-sided Mitsuba BSDF: its back reflects nothing and emits
    /// nothing, as the path tracer shows it (the front's patch showed a lamp seen from above
    /// as lit).
    pub fn locate(
        &self,
        scene: &Scene,
        hit: &SurfaceHit,
        toward: Vec3,
    ) -> Option<(usize, f32, f32)> {
        let behind = hit.prim.kind != PrimKind::Shape && hit.geometric_normal.dot(toward) < 0.0;
        let side = match (behind, scene.lit_behind(hit.material)) {
            (true, true) => mesh::BACK,
            (true, false) if scene.materials[hit.material as usize].black_behind() => return None,
            _ => 0,
        };
        let parameters = scene.parameters(hit);
        let (u, v, part) = match hit.prim.kind {
            PrimKind::Quad => {
                let q = &scene.quads[hit.prim.index as usize];
                let (u, v) =
                    inverse_bilinear(&q.vertices, q.normal, hit.point).unwrap_or(parameters);
                (u, v, side)
            }
            PrimKind::Triangle | PrimKind::Instanced => {
                let (b1, b2) = parameters;
                let u = if b2 < 1.0 { b1 / (1.0 - b2) } else { 0.0 };
                (u, b2, side)
            }
            PrimKind::Shape => (parameters.0, parameters.1, hit.part),
        };
        let (face, s, t) = self.mesh.locate(hit.prim, part, u, v)?;
        let k = self.patch_of_face[face as usize];
        (k != NONE).then_some((k as usize, s, t))
    }

    /// Per-patch values ready for lookups at hits: flat, or with corner values for bilinear
    /// interpolation.
    pub fn field(&self, values: Vec<Color>, interpolate: bool) -> PatchField {
        let corners = interpolate.then(|| self.corner_values(&values));
        PatchField {
            values,
            corners,
            per_element: false,
        }
    }

    /// Per-element values (one for each of `state.elements`), shown at the leaves: flat, or
    /// with `interpolate` bilinear between corner values (`element_corner_values`, which
    /// takes the patches' own values, `patch_values`, at their corners).
    pub fn element_field(
        &self,
        values: Vec<Color>,
        patch_values: &[Color],
        interpolate: bool,
    ) -> PatchField {
        let corners = interpolate.then(|| self.element_corner_values(&values, patch_values));
        PatchField {
            values,
            corners,
            per_element: true,
        }
    }

    /// Values at the four corners of every leaf element (indexed as `state.elements`; zero at
    /// the others) for smooth display of a hierarchical solution: inside its patch a corner
    /// takes the mean of the leaves around it, and a patch's own corners are
    /// `corner_values`', shared with the patches around. Smoothing the patches' means
    /// instead showed a wall of one patch as one gradient, its elements' shadows gone.
    fn element_corner_values(&self, values: &[Color], patch_values: &[Color]) -> Vec<[Color; 4]> {
        let patch_corners = self.corner_values(patch_values);
        let light = &self.state;
        // The leaves of each patch with the square of parameters each covers.
        let per_patch: Vec<Vec<(usize, [Color; 4])>> = (0..self.patches.len())
            .into_par_iter()
            .map(|k| {
                let mut leaves = Vec::new();
                let mut pending = vec![(k, [0.0f32, 0.0, 1.0, 1.0])];
                while let Some((e, [s0, t0, s1, t1])) = pending.pop() {
                    let children = light.elements[e].children;
                    if children != NONE {
                        let (sm, tm) = (0.5 * (s0 + s1), 0.5 * (t0 + t1));
                        let quarters = [
                            [s0, t0, sm, tm],
                            [sm, t0, s1, tm],
                            [sm, tm, s1, t1],
                            [s0, tm, sm, t1],
                        ];
                        for (c, q) in quarters.into_iter().enumerate() {
                            pending.push((children as usize + c, q));
                        }
                        continue;
                    }
                    let corner = |index: usize, s: f32, t: f32| {
                        let on_corner = (s == 0.0 || s == 1.0) && (t == 0.0 || t == 1.0);
                        if on_corner {
                            return patch_corners[k][index];
                        }
                        // The leaves just around (s, t) within the patch.
                        const NEAR: f32 = 1e-6;
                        let (mut sum, mut n) = (Vec3::ZERO, 0.0f32);
                        for (ds, dt) in [(-NEAR, -NEAR), (NEAR, -NEAR), (NEAR, NEAR), (-NEAR, NEAR)]
                        {
                            let (a, b) = (s + ds, t + dt);
                            if (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) {
                                sum += values[light.leaf_at(k, a, b).0];
                                n += 1.0;
                            }
                        }
                        sum / n
                    };
                    let corners = [
                        corner(0, s0, t0),
                        corner(1, s1, t0),
                        corner(2, s1, t1),
                        corner(3, s0, t1),
                    ];
                    leaves.push((e, corners));
                }
                leaves
            })
            .collect();
        let mut corners = vec![[Vec3::ZERO; 4]; values.len()];
        for (e, c) in per_patch.into_iter().flatten() {
            corners[e] = c;
        }
        corners
    }

    /// The patch under a hit seen from `toward`, and what `--wireframe` outlines there: its
    /// leaf element where the solver made elements, else the patch again.
    pub fn cell_at(&self, scene: &Scene, hit: &SurfaceHit, toward: Vec3) -> Option<(u32, u32)> {
        let (k, u, v) = self.locate(scene, hit, toward)?;
        Some((k as u32, self.state.leaf_at(k, u, v).0 as u32))
    }

    /// The value of `field` at a surface hit seen from `toward` (None where no patch lies,
    /// e.g. a triangle of a scene whose mesh left it out).
    pub fn sample(
        &self,
        scene: &Scene,
        hit: &SurfaceHit,
        toward: Vec3,
        field: &PatchField,
    ) -> Option<Color> {
        let (k, u, v) = self.locate(scene, hit, toward)?;
        Some(self.value_at(field, (k, u, v)))
    }

    /// The value of `field` at the parameters (u, v) of patch k (as `locate` finds them).
    pub fn value_at(&self, field: &PatchField, (k, u, v): (usize, f32, f32)) -> Color {
        let (cell, u, v) = if field.per_element {
            self.state.leaf_at(k, u, v)
        } else {
            (k, u, v)
        };
        match &field.corners {
            Some(c) => {
                let c = &c[cell];
                c[0] * ((1.0 - u) * (1.0 - v))
                    + c[1] * (u * (1.0 - v))
                    + c[2] * (u * v)
                    + c[3] * ((1.0 - u) * v)
            }
            None => field.values[cell],
        }
    }

    /// Values at the four corners of every patch for smooth display: each corner takes the
    /// area-weighted mean of the patches around its vertex that face nearly the same way
    /// (so a room's corners stay sharp).
    pub fn corner_values(&self, values: &[Color]) -> Vec<[Color; 4]> {
        let around = self.mesh.vertex_leaves();
        self.patches
            .iter()
            .map(|p| {
                self.mesh.face_vertex_ids(p.face).map(|v| {
                    let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
                    for &f in &around[v as usize] {
                        let q = self.patch_of_face[f as usize];
                        if q == NONE {
                            continue;
                        }
                        let other = &self.patches[q as usize];
                        if other.normal.dot(p.normal) > 0.9 && other.area > 0.0 {
                            sum += values[q as usize] * other.area;
                            weight += other.area;
                        }
                    }
                    if weight > 0.0 {
                        sum * weight.recip()
                    } else {
                        values[self.patch_of_face[p.face as usize] as usize]
                    }
                })
            })
            .collect()
    }
}

/// Parameters (u, v) of point `p` on the planar quad `q` under its bilinear map
/// q0 + (q1−q0)u + (q3−q0)v + (q0−q1+q2−q3)uv (Quilez), solved in the plane of the quad's
/// two largest normal-free axes.
fn inverse_bilinear(q: &[Vec3; 4], normal: Vec3, p: Vec3) -> Option<(f32, f32)> {
    let axis = normal.abs().max_position();
    let flat = |v: Vec3| {
        let a = v.to_array();
        match axis {
            0 => (a[1], a[2]),
            1 => (a[2], a[0]),
            _ => (a[0], a[1]),
        }
    };
    let sub = |a: (f32, f32), b: (f32, f32)| (a.0 - b.0, a.1 - b.1);
    let cross = |a: (f32, f32), b: (f32, f32)| a.0 * b.1 - a.1 * b.0;
    let [a, b, c, d] = q.map(flat);
    let e = sub(b, a);
    let f = sub(d, a);
    let g = sub(sub(a, b), sub(d, c));
    let h = sub(flat(p), a);
    let k2 = cross(g, f);
    let k1 = cross(e, f) + cross(h, g);
    let k0 = cross(h, e);
    let v = if k2.abs() < 1e-6 * k1.abs().max(f32::MIN_POSITIVE) {
        -k0 / k1
    } else {
        let w = k1 * k1 - 4.0 * k0 * k2;
        if w < 0.0 {
            return None;
        }
        let w = w.sqrt();
        let v1 = (-k1 - w) / (2.0 * k2);
        let v2 = (-k1 + w) / (2.0 * k2);
        if (-1e-3..=1.0 + 1e-3).contains(&v1) {
            v1
        } else {
            v2
        }
    };
    let den = (e.0 + g.0 * v, e.1 + g.1 * v);
    let u = if den.0.abs() > den.1.abs() {
        (h.0 - f.0 * v) / den.0
    } else {
        (h.1 - f.1 * v) / den.1
    };
    (u.is_finite() && v.is_finite()).then(|| (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0)))
}

/// Solves and renders with the radiosity engine.
pub fn render(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
) -> Result<(Film, RenderStats, Solution), String> {
    let solution = solve_with_progress(scene, accel, settings)?;
    let (film, stats) = render_solved(scene, accel, settings, &solution, Samples::Traced);
    Ok((film, stats, solution))
}

/// The image of a solution already solved, as the engine renders it after its solve (the
/// viewer keeps a solution between images of it, and what their camera samples saw: see
/// `Samples`).
pub fn render_solved(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
    solution: &Solution,
    samples: Samples,
) -> (Film, RenderStats) {
    let (film, stats) = render_solution(scene, accel, settings, solution, samples);
    stats.form_factor_rays.store(solution.rays, Relaxed);
    (film, stats)
}

/// A solution's indirect light for the ray tracer (`--indirect radiosity`): the incident
/// radiance of the light reflected at least once, at the patch a ray hits, flat or
/// interpolated.
pub struct RadiosityIndirect<'a> {
    solution: &'a Solution,
    field: PatchField,
}

impl<'a> RadiosityIndirect<'a> {
    pub fn new(solution: &'a Solution, interpolate: bool) -> RadiosityIndirect<'a> {
        RadiosityIndirect {
            solution,
            field: solution.field(solution.indirect_incident(), interpolate),
        }
    }
}

impl IndirectLight for RadiosityIndirect<'_> {
    fn incident(
        &self,
        scene: &Scene,
        _: &dyn Accel,
        s: &SurfaceHit,
        (n, _): (Vec3, Option<&crate::scene::medium::Medium>),
        _: u32,
        _: &mut Rng,
    ) -> Color {
        self.solution
            .sample(scene, s, n, &self.field)
            .unwrap_or(Vec3::ZERO)
    }
}

/// Solves with a progress bar (the bar fills as log(residual) approaches log(tolerance)), or
/// reads the solution `--load-radiosity` names; writes it where `--save-radiosity` asks.
pub fn solve_with_progress(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
) -> Result<Solution, String> {
    const STEPS: u64 = 1000;
    let r = &settings.radiosity;
    let solution = match &r.load {
        Some(path) => Solution::load(path, scene, settings)?,
        None => {
            let bar = crate::progress::bar(STEPS, "radiosity", settings.quiet);
            let tolerance = r.tolerance.clamp(1e-30, 0.5);
            let solution = Solution::solve(scene, accel, settings, |residual| {
                if residual > 0.0 && residual.is_finite() {
                    let done = (residual.ln() / tolerance.ln()).clamp(0.0, 1.0);
                    bar.set_position((done * STEPS as f32) as u64);
                }
            });
            bar.finish_and_clear();
            solution
        }
    };
    // A solve Ctrl-C cut short is not saved: a farm's tasks must not take it as the solution.
    if let (Some(path), false) = (&r.save, crate::interrupt::requested()) {
        solution
            .save(path, file::fingerprint(scene, settings))
            .map_err(|e| e.to_string())?;
    }
    Ok(solution)
}

/// The radiosity solution as a render farm's pre-pass.
pub fn pre_pass(settings: &RenderSettings) -> PrePass {
    PrePass {
        name: "radiosity solution",
        save_flag: "--save-radiosity",
        load_flag: "--load-radiosity",
        saved: settings.radiosity.save.is_some(),
    }
}

/// Solves (or loads) and saves the solution, for `--pre-pass-only`: its summary.
pub fn run_pre_pass(
    scene: &Scene,
    accel: &dyn Accel,
    settings: &RenderSettings,
) -> Result<Vec<String>, String> {
    let solution = solve_with_progress(scene, accel, settings)?;
    Ok(vec![solution.summary(settings)])
}

/// Bytes per radiosity patch: mesh face and its links, patch, solver state, interpolation.
const PATCH_BYTES: u64 = 640;

/// The radiosity engine (`--engine radiosity`): the solution seen from the camera, or one of
/// its display modes.
pub struct RadiosityEngine;

impl Engine for RadiosityEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Radiosity
    }

    fn structures(&self) -> &'static [&'static str] {
        &["radiosity mesh"]
    }

    fn unread_flags(&self) -> &'static [&'static str] {
        // The display reads the camera flags, and -num_shadow_samples turns on visibility in
        // the form factors.
        &["num_bounces", "ambient_light", "light_sampling", "indirect"]
    }

    fn plan(&self, scene: &Scene, settings: &RenderSettings) -> EnginePlan {
        mesh_plan(scene, settings)
    }

    /// The outlines of `--wireframe` and of the form factors' source are drawn over the
    /// samples.
    fn samples_pixels(&self, settings: &RenderSettings) -> bool {
        let r = &settings.radiosity;
        !r.wireframe && r.display != Display::FormFactors
    }

    fn pre_pass(&self, settings: &RenderSettings) -> Option<PrePass> {
        Some(pre_pass(settings))
    }

    fn run_pre_pass(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Vec<String>, String> {
        run_pre_pass(scene, accel, settings)
    }

    fn render(
        &self,
        scene: &Scene,
        accel: &dyn Accel,
        settings: &RenderSettings,
    ) -> Result<Rendered, String> {
        let (film, stats, solution) = render(scene, accel, settings)?;
        solution.rendered(film, stats, settings)
    }

    /// Radiosity with visibility and interpolation, the mesh subdivided once more at each
    /// level (4× the patches) and the pixel samples 4× too.
    fn budget(&self, level: u32, base: &RenderSettings) -> Option<Budget> {
        if level > 5 {
            return None;
        }
        let mut s = base.clone();
        s.num_shadow_samples = 1;
        s.num_antialias_samples = (1u32 << (2 * level)).min(256);
        s.radiosity.subdivide = level;
        s.radiosity.interpolate = true;
        s.radiosity.num_form_factor_samples = 4;
        Some(Budget {
            counts: "subdivide",
            value: level as u64,
            settings: s,
        })
    }

    fn colour(&self) -> (u8, u8, u8) {
        (44, 160, 44)
    }
}

/// What a radiosity solve builds, for `--plan`: the mesh (its patches before adaptive
/// subdivision, and whether form factors cast visibility rays) and the form-factor cache.
pub fn mesh_plan(scene: &Scene, settings: &RenderSettings) -> EnginePlan {
    let input_patches = planned_input_patches(scene, &settings.radiosity);
    let patches = input_patches.saturating_mul(4u64.saturating_pow(settings.radiosity.subdivide));
    let visibility = if settings.num_shadow_samples == 0 {
        "off (-num_shadow_samples 0)"
    } else if convex_enclosure(scene) {
        "skipped: the scene is a convex enclosure"
    } else {
        "one occlusion ray per point pair"
    };
    let solver = settings.radiosity.solver.resolve(input_patches as usize);
    // Only the progressive solver caches rows of form factors.
    let cache = match solver {
        SolverKind::Progressive => patches
            .saturating_mul(patches)
            .saturating_mul(4)
            .min((settings.radiosity.ff_cache_mb as u64).saturating_mul(1 << 20)),
        _ => 0,
    };
    // How far the mesh is split where lights without area light it unevenly is found by
    // shadow rays, in the solve.
    let split = if scene.delta_lights.is_empty() {
        ""
    } else {
        " before the splits where lights without area light it unevenly"
    };
    EnginePlan {
        structures: vec![(
            "radiosity mesh",
            format!("yes ({patches} patches{split}, {solver} solver; visibility: {visibility})"),
        )],
        memory: vec![
            ("radiosity mesh", patches.saturating_mul(PATCH_BYTES)),
            ("form-factor cache", cache),
        ],
    }
}

/// Input patches of the radiosity mesh: every primitive's top-level faces, the back too of a
/// polygon lit behind (`Scene::lit_behind`; each `--subdivide` makes four of one).
fn planned_input_patches(scene: &Scene, r: &RadiositySettings) -> u64 {
    let tessellation = r.tessellation();
    let instanced =
        (0..scene.instancing.triangle_count()).map(|i| scene.instancing.material(i as u32));
    (scene.quads.iter().map(|q| q.material))
        .chain(scene.triangles.materials.iter().copied())
        .chain(instanced)
        .map(|m| 1 + scene.lit_behind(m) as u64)
        .sum::<u64>()
        + scene
            .shapes
            .iter()
            .map(|s| {
                let (cols, rows) = s.shape.grid(&tessellation);
                s.shape.part_count() as u64 * cols as u64 * rows as u64
            })
            .sum::<u64>()
}

impl Solution {
    /// The render of an engine that solved this: its summary line, the cap's warning and
    /// the convergence log; the solution exported first when `--export-radiosity` asks.
    pub fn rendered(
        &self,
        film: Film,
        stats: RenderStats,
        settings: &RenderSettings,
    ) -> Result<Rendered, String> {
        if self.stop == Stop::Diverged {
            return Err(format!(
                "radiosity diverged after {} shots: the light its patches pass on grew without bound{}",
                self.state.iterations,
                Solution::through_one_another(settings)
            ));
        }
        let mut summary = vec![self.summary(settings)];
        if let Some(path) = &settings.radiosity.export {
            self.write_ply(path).map_err(|e| e.to_string())?;
            summary.push(format!(
                "wrote {} ({} patches, linear radiance as vertex colours)",
                path.display(),
                self.patches.len()
            ));
        }
        Ok(Rendered {
            summary,
            warnings: self
                .cap_warning(settings)
                .into_iter()
                .chain(self.solver_warning.clone())
                .collect(),
            convergence_log: Some(self.convergence_csv()),
            counters: Some(("radiosity", self.counters())),
            ..Rendered::plain(film, stats)
        })
    }

    /// Named counters for `--stats`: the mesh's, then the solver's.
    pub fn counters(&self) -> Vec<(&'static str, u64)> {
        let mut counters = vec![
            ("input patches", self.patches.len() as u64),
            ("coincident twins", self.twins as u64),
            ("visibility rays", self.rays),
        ];
        counters.extend_from_slice(&self.solver_counters);
        counters
    }

    /// One paragraph on how the solve went.
    pub fn summary(&self, settings: &RenderSettings) -> String {
        let r = &settings.radiosity;
        let state = &self.state;
        let steps = match self.solver {
            SolverKind::Hierarchical => "sweeps",
            _ => "shots",
        };
        let stop = match self.stop {
            Stop::Converged => format!("converged to tolerance {:.1e}", r.tolerance),
            Stop::Iterations => format!("stopped after {} {steps} as asked", state.iterations),
            Stop::NoLight => "nothing emits".to_string(),
            Stop::Interrupted => format!("interrupted after {} {steps}", state.iterations),
            Stop::TimeLimit => format!(
                "stopped by the time limit after {} {steps}",
                state.iterations
            ),
            Stop::Cap => String::new(),
            Stop::Diverged => format!("diverged after {} {steps}", state.iterations),
        };
        let mut mesh_notes = if self.adaptive_rounds > 0 {
            format!(", {} adaptive rounds", self.adaptive_rounds)
        } else {
            String::new()
        };
        if r.subdivide_to_fit.is_some() {
            mesh_notes += &format!(
                " (faces split in four {} times: as far as the time allowed)",
                self.subdivide
            );
        }
        if self.twins > 0 {
            mesh_notes += &format!(" ({} coincident twins solved as one)", self.twins);
        }
        format!(
            "radiosity: {} patches{mesh_notes}, {} solver, {} {steps}, residual {:.3e}{}{stop}; visibility {}; {} visibility rays; {}",
            self.patches.len(),
            self.solver,
            state.iterations,
            state.residual,
            if stop.is_empty() { "" } else { ", " },
            self.visibility_reason,
            self.rays,
            self.solver_report
        )
    }

    /// A solve stopped by the safety cap is a warning (its image still holds the ambient
    /// estimate of the light not yet shot).
    pub fn cap_warning(&self, settings: &RenderSettings) -> Option<String> {
        let r = &settings.radiosity;
        (self.stop == Stop::Cap).then(|| format!(
            "radiosity stopped at its cap of {} shots ({} per patch) with residual {:.3e} above the tolerance {:.1e}; the image adds the ambient estimate of the rest (raise --radiosity-max-shots-per-patch to go on){}",
            self.state.iterations, r.max_shots_per_patch, self.state.residual, r.tolerance,
            Solution::through_one_another(settings)
        ))
    }

    /// Why a solve may not converge, when visibility was off by request: what to add to the
    /// message of a solve that did not.
    fn through_one_another(settings: &RenderSettings) -> &'static str {
        if settings.num_shadow_samples == 0 {
            "; with visibility off (-num_shadow_samples 0) patches see light through one another, more than they could in a scene, and it may go round without end: -num_shadow_samples 1 tests visibility"
        } else {
            ""
        }
    }

    /// `--log-convergence`: one CSV line per shot (progressive) or sweep (hierarchical).
    pub fn convergence_csv(&self) -> String {
        use std::fmt::Write;
        let mut csv = String::from(match self.solver {
            SolverKind::Hierarchical => "sweep,round,links,elements,residual,seconds,rays\n",
            _ => "shot,patch,residual,seconds,rays\n",
        });
        for r in &self.state.log {
            let _ = match r.step {
                Step::Shot { patch } => write!(csv, "{},{patch}", r.shot),
                Step::Sweep {
                    round,
                    links,
                    elements,
                } => write!(csv, "{},{round},{links},{elements}", r.shot),
            };
            let _ = writeln!(csv, ",{:.6e},{:.6},{}", r.residual, r.seconds, r.rays);
        }
        csv
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::vec3;

    #[test]
    fn inverse_bilinear_recovers_parameters_of_a_trapezoid() {
        let q = [
            vec3(0.0, 0.0, 0.0),
            vec3(4.0, 0.0, 0.0),
            vec3(3.0, 2.0, 0.0),
            vec3(1.0, 2.0, 0.0),
        ];
        for (u, v) in [(0.25f32, 0.5f32), (0.9, 0.1), (0.5, 0.5), (0.0, 1.0)] {
            let p = q[0]
                + (q[1] - q[0]) * u
                + (q[3] - q[0]) * v
                + (q[0] - q[1] + q[2] - q[3]) * (u * v);
            let (a, b) = inverse_bilinear(&q, vec3(0.0, 0.0, 1.0), p).unwrap();
            assert!(
                (a - u).abs() < 1e-5 && (b - v).abs() < 1e-5,
                "{u} {v} -> {a} {b}"
            );
        }
    }
}
