//! Shared by the integration tests: the project's own scenes, every available backend, and a
//! brute-force oracle that tests every primitive for every ray.
#![allow(dead_code)]

pub mod references;
pub mod shape_oracle;
pub mod vec64;

use std::path::{Path, PathBuf};

use trilux::accel::{Accel, AccelKind, PrimHit};
use trilux::geometry::{intersect_quad, intersect_triangle, Ray};
use trilux::scene::{PrimKind, PrimRef, Scene};

/// The largest relative error of the red channel of `values` against `truth` (the furnaces
/// are grey, so one channel tells).
pub fn worst_relative_error(values: &[trilux::scene::Color], truth: f32) -> f32 {
    values
        .iter()
        .map(|l| (l.x / truth - 1.0).abs())
        .fold(0.0f32, f32::max)
}

/// A fresh folder `trilux-<name>-<pid>` in the system's temporary directory (the process id
/// keeps test binaries apart; `name` keeps the tests of one binary apart).
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("trilux-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The project's own scenes in `scenes/` (never none: a test looping over them tests
/// something).
pub fn own_scenes() -> Vec<PathBuf> {
    let scenes = obj_files(&own_scene_dir());
    assert!(scenes.len() >= 8, "scenes/ holds our eight scenes");
    scenes
}

/// The project's own scene folder, `scenes/`.
pub fn own_scene_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// One of `scenes/`, loaded.
pub fn own_scene(name: &str) -> Scene {
    let path = own_scene_dir().join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A course command line's arguments, its scene file found in `dir` (`scenes/`, or the
/// course's folder).
pub fn scene_args(dir: &Path, line: &str) -> Vec<String> {
    line.split(' ')
        .map(|a| {
            if a.ends_with(".obj") {
                dir.join(a).to_string_lossy().into_owned()
            } else {
                a.to_string()
            }
        })
        .collect()
}

/// Every `.obj` of `dir`, sorted.
pub fn obj_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    files.sort();
    files
}

pub fn backends() -> Vec<AccelKind> {
    let mut kinds = vec![AccelKind::Bvh];
    if cfg!(feature = "embree") {
        kinds.push(AccelKind::Embree);
    }
    kinds
}

/// Tests every primitive: the oracle for traversal, and (through `shape_oracle`, in f64) for
/// the spheres' and rings' intersection.
pub struct BruteForce<'a> {
    pub scene: &'a Scene,
}

impl BruteForce<'_> {
    fn hit(&self, ray: &Ray, prim: PrimRef, t_max: f32) -> Option<f32> {
        let s = self.scene;
        let i = prim.index as usize;
        match prim.kind {
            PrimKind::Quad => {
                let q = &s.quads[i];
                if !s.culled_backs().meets(prim.kind, q.normal, ray.direction) {
                    return None;
                }
                intersect_quad(ray, t_max, &q.vertices).map(|h| h.0)
            }
            PrimKind::Triangle => {
                let [a, b, c] = s.triangles.vertices(i);
                let normal = (b - a).cross(c - a);
                if !s.culled_backs().meets(prim.kind, normal, ray.direction) {
                    return None;
                }
                intersect_triangle(ray, t_max, a, b, c).map(|h| h.0)
            }
            PrimKind::Shape => shape_oracle::hit(&s.shapes[i].shape, ray, t_max).map(|t| t as f32),
            PrimKind::Instanced => {
                let [a, b, c] = s.instanced_vertices(prim.index);
                intersect_triangle(ray, t_max, a, b, c).map(|h| h.0)
            }
        }
    }

    fn prims(&self) -> impl Iterator<Item = PrimRef> + '_ {
        let s = self.scene;
        let of = |kind, n: usize| (0..n as u32).map(move |index| PrimRef { kind, index });
        of(PrimKind::Quad, s.quads.len())
            .chain(of(PrimKind::Triangle, s.triangles.len()))
            .chain(of(PrimKind::Shape, s.shapes.len()))
            .chain(of(PrimKind::Instanced, s.instancing.triangle_count()))
    }
}

impl Accel for BruteForce<'_> {
    fn name(&self) -> &'static str {
        "brute force"
    }
    fn intersect(&self, ray: &Ray) -> Option<PrimHit> {
        let mut best: Option<PrimHit> = None;
        for prim in self.prims() {
            let t_max = best.map_or(ray.t_max, |b| b.t);
            if let Some(t) = self.hit(ray, prim, t_max) {
                best = Some(PrimHit {
                    t,
                    prim,
                    u: 0.0,
                    v: 0.0,
                    exact: false,
                });
            }
        }
        best
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.prims().any(|p| self.hit(ray, p, ray.t_max).is_some())
    }
}

/// Same primitive and the same t, or both miss. t agrees within 1e-5 relative, plus what
/// rounding the coordinates (8 ULPs of the largest of the origin's and the hit point's) moves
/// t by along a ray that meets the surface at angle θ to its normal: that over |d| |cos θ|
/// (|cos θ| held above 1e-3, within 0.06° of tangent). A ray that starts 1e-6 from a surface
/// cannot have its t known to 1e-5 of 1e-6, and one that grazes a sphere's silhouette is
/// within rounding of the surface over a long stretch of itself (measured: 2.1e-5 relative
/// between f64 and the shape's f32 routine at |cos θ| = 0.006, both points within 1.3e-7 of
/// the sphere of radius 4).
pub fn same_hit(scene: &Scene, ray: &Ray, x: &Option<PrimHit>, y: &Option<PrimHit>) -> bool {
    match (x, y) {
        (Some(x), Some(y)) => {
            if x.prim != y.prim {
                return false;
            }
            let off = (x.t - y.t).abs() - 1e-5 * x.t.abs().max(y.t.abs());
            if off <= 0.0 {
                return true;
            }
            // Only now the surface, for its angle to the ray: most pairs agree closely.
            let point = ray.at(x.t);
            let magnitude = ray
                .origin
                .abs()
                .max_element()
                .max(point.abs().max_element());
            let cos = scene
                .surface(ray, x)
                .geometric_normal
                .dot(ray.direction.normalize())
                .abs()
                .max(1e-3);
            off <= 8.0 * f32::EPSILON * magnitude / (ray.direction.length() * cos)
        }
        (None, None) => true,
        _ => false,
    }
}

/// Compares two backends' answers on a ray set; returns the number of rays on which they
/// disagree (not `same_hit`, or different occlusion).
pub fn disagreements(
    scene: &Scene,
    a: &dyn Accel,
    b: &dyn Accel,
    rays: &[Ray],
    occlusion_rays: &[Ray],
) -> (usize, usize) {
    let mut closest = 0;
    let mut ha = vec![None; rays.len()];
    let mut hb = vec![None; rays.len()];
    a.intersect_batch(rays, &mut ha);
    b.intersect_batch(rays, &mut hb);
    for ((x, y), ray) in ha.iter().zip(&hb).zip(rays) {
        closest += usize::from(!same_hit(scene, ray, x, y));
    }
    let mut oa = vec![false; occlusion_rays.len()];
    let mut ob = vec![false; occlusion_rays.len()];
    a.occluded_batch(occlusion_rays, &mut oa);
    b.occluded_batch(occlusion_rays, &mut ob);
    let occluded = oa.iter().zip(&ob).filter(|(x, y)| x != y).count();
    (closest, occluded)
}

/// A closed cube of six inward-facing quads, all of albedo ρ and emitting Le = 1, seen from
/// a camera inside it (every pixel sees a wall; the black background cannot be seen).
pub fn furnace(rho: f32) -> Scene {
    furnace_and(rho, "")
}

/// `furnace` with more of the scene after it, in the course dialect (e.g. a medium).
pub fn furnace_and(rho: f32, more: &str) -> Scene {
    let text = format!(
        "material\ndiffuse {rho} {rho} {rho}\nemitted 1 1 1\n\
         v -1 -1 -1\nv 1 -1 -1\nv -1 1 -1\nv 1 1 -1\nv -1 -1 1\nv 1 -1 1\nv -1 1 1\nv 1 1 1\n\
         m 0\nf 5 7 8 6\nf 1 2 4 3\nf 3 4 8 7\nf 1 5 6 2\nf 1 3 7 5\nf 2 6 8 4\n\
         background_color 0 0 0\n\
         PerspectiveCamera {{\ncamera_position 0.1 0.2 0.5\npoint_of_interest 0 0 -1\nup 0 1 0\nangle 1.2\n}}\n{more}"
    );
    Scene::parse_dialect(Path::new("furnace.obj"), &text).expect("furnace parses")
}

/// A unit square light of radiance `le` at height 1 facing down over a large floor of albedo
/// `rho`, seen from above through the light's back side (quads are one-sided) by a tiny
/// orthographic camera at the point right under the light's centre. The floor's radiance
/// there is ρ·Le·F, F = 0.239456 (point-to-square form factor).
pub fn square_light(le: f32, rho: f32) -> Scene {
    square_light_and(le, rho, "")
}

/// `square_light` with more of the scene: `more`, in the course dialect, after it (its
/// materials numbered from 2, its vertices from 9).
pub fn square_light_and(le: f32, rho: f32, more: &str) -> Scene {
    let text = format!(
        "material\ndiffuse 0 0 0\nemitted {le} {le} {le}\n\
         material\ndiffuse {rho} {rho} {rho}\n\
         m 0\nv -0.5 1 0.5\nv -0.5 1 -0.5\nv 0.5 1 -0.5\nv 0.5 1 0.5\nf 1 2 3 4\n\
         m 1\nv -50 0 -50\nv -50 0 50\nv 50 0 50\nv 50 0 -50\nf 5 6 7 8\n\
         background_color 0 0 0\n\
         OrthographicCamera {{\ncamera_position 0 5 0\npoint_of_interest 0 0 0\nup 0 0 -1\nsize 0.0001\n}}\n{more}"
    );
    Scene::parse_dialect(Path::new("square.obj"), &text).expect("square light parses")
}

/// The least-squares slope of log `values` against log `counts`: the power of N an error
/// falls as (values floored at 1e-300 so an exact zero stays finite).
pub fn log_log_slope(counts: &[u32], values: &[f64]) -> f64 {
    let xs: Vec<f64> = counts.iter().map(|&n| (n as f64).ln()).collect();
    let ys: Vec<f64> = values.iter().map(|v| v.max(1e-300).ln()).collect();
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    xs.iter()
        .zip(&ys)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum::<f64>()
        / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>()
}

/// The Fresnel reflectance of unpolarised light at a smooth dielectric boundary, in f64 and
/// written apart from `engines::scattering`: the mean of the s and p amplitudes squared, 1
/// under total internal reflection.
pub fn fresnel(cos_i: f64, eta_i: f64, eta_t: f64) -> f64 {
    let sin_t = eta_i / eta_t * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let s = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    let p = (eta_i * cos_t - eta_t * cos_i) / (eta_i * cos_t + eta_t * cos_i);
    0.5 * (s * s + p * p)
}

/// Runs `render` with `args` in `dir`, sends SIGINT at each of `signals` (milliseconds after
/// the start), and returns how it ended, its stderr, and the seconds it ran on after the
/// last signal.
pub fn interrupted(
    dir: &Path,
    args: &[&str],
    signals: &[u64],
) -> (std::process::ExitStatus, String, f64) {
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_render"))
        .args(args)
        .current_dir(dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("starts");
    let start = std::time::Instant::now();
    for &ms in signals {
        std::thread::sleep(std::time::Duration::from_millis(ms).saturating_sub(start.elapsed()));
        let killed = std::process::Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .expect("kill runs");
        assert!(
            killed.success(),
            "{args:?}: the process ended before the signal at {ms} ms"
        );
    }
    let last = start.elapsed();
    let out = child.wait_with_output().expect("ends");
    let after = (start.elapsed() - last).as_secs_f64();
    (
        out.status,
        String::from_utf8_lossy(&out.stderr).into_owned(),
        after,
    )
}
