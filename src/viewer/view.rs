//! What the window shows when it is not showing a trace: the course viewer's 'v' modes of the
//! radiosity solver stepped shot by shot, and the photons. The state changes with keys; each
//! state is one job for the render thread — an engine, its settings and the flags that make
//! the offline command render the same image.
//!
//! The radiosity views are the library's solve with `--radiosity-iterations` shots; the
//! render thread keeps the solve, so that a camera move or another mode only draws it, and
//! more shots (space, 'a') shoot on from it. Fewer shots ('c'), or a change to what the
//! solve reads (the mesh's subdivision, the quads' sides), solve again from the start.

use super::session::Session;
use super::worker::Job;
use crate::engines::photon::settings::Display as PhotonDisplay;
use crate::engines::radiosity::settings::Display as RadiosityDisplay;
use crate::engines::EngineKind;
use crate::scene::Camera;

/// The course viewer's 'v' modes, in its order.
const MODES: [(RadiosityDisplay, &str, &str); 6] = [
    (RadiosityDisplay::Materials, "MATERIALS", "materials"),
    (RadiosityDisplay::Radiance, "RADIANCE", "radiance"),
    (
        RadiosityDisplay::FormFactors,
        "FORM_FACTORS",
        "form-factors",
    ),
    (RadiosityDisplay::Lights, "LIGHTS", "lights"),
    (
        RadiosityDisplay::Undistributed,
        "UNDISTRIBUTED",
        "undistributed",
    ),
    (RadiosityDisplay::Absorbed, "ABSORBED", "absorbed"),
];

/// The flags a radiosity view sets, replacing the session's.
const RADIOSITY_CONTROLS: &[&str] = &[
    "--radiosity-iterations",
    "--visualize",
    "--subdivide",
    "--interpolate",
    "--wireframe",
];

/// Shown instead of the radiosity modes: the photon map's photons, or its kd-tree too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Photons {
    Points,
    KdTree,
}

/// The views' state.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewState {
    /// Index into MODES ('v').
    mode: usize,
    /// Radiosity shots taken (space, 'a'; 'c' sets 0); None until the solver is asked for:
    /// MATERIALS is then the ray-cast preview, no mesh built.
    pub shots: Option<u64>,
    /// Times the mesh is split in four ('s').
    pub subdivide: u32,
    /// Smooth radiosity display ('i').
    pub interpolate: bool,
    /// Patch outlines ('w').
    pub wireframe: bool,
    /// Whether photons were traced ('p'), and whether they are shown ('l', 'k').
    pub photons_traced: bool,
    pub photons: Option<Photons>,
    /// Shots added until the solver converges ('a').
    pub animating: bool,
    /// Quads seen from behind too ('b'; `--two-sided`): back faces not culled.
    pub two_sided: bool,
}

impl ViewState {
    /// The state at start: the MATERIALS preview, the mesh as the flags give it.
    pub fn new(session: &Session) -> ViewState {
        let r = &session.settings.radiosity;
        ViewState {
            mode: 0,
            shots: None,
            subdivide: r.subdivide,
            interpolate: r.interpolate,
            wireframe: r.wireframe,
            photons_traced: false,
            photons: None,
            animating: false,
            two_sided: session.args.common.two_sided,
        }
    }

    /// 'v': the next mode (and the radiosity modes again if photons were shown).
    pub fn next_mode(&mut self) {
        self.photons = None;
        self.mode = (self.mode + 1) % MODES.len();
    }

    /// Space: one more shot; from MATERIALS, the view turns to RADIANCE to show it.
    pub fn shoot(&mut self) {
        self.shots = Some(self.shots.map_or(1, |s| s + 1));
        self.photons = None;
        if self.mode == 0 {
            self.mode = 1;
        }
    }

    /// 'a': the shots of the next animation step: a quarter more (at least one), so that
    /// a solve of n shots costs about 5n shots of animation, each an image.
    pub fn animate_step(&mut self) {
        let shots = self.shots.unwrap_or(0);
        self.shots = Some(shots + (shots / 4).max(1));
        self.photons = None;
        if self.mode == 0 {
            self.mode = 1;
        }
    }

    /// The job that draws this state from `camera`.
    pub fn job(&self, session: &Session, camera: Camera) -> Job {
        let mut settings = session.settings.clone();
        let job = |engine, mut settings, label: String, controls, flags| {
            session.engine_defaults(engine, &mut settings);
            Job {
                camera,
                engine,
                settings,
                progressive: false,
                time_limit: None,
                two_sided: self.two_sided,
                label,
                controls,
                flags,
            }
        };
        if let Some(photons) = self.photons {
            let (display, name, flag) = match photons {
                Photons::Points => (PhotonDisplay::Photons, "PHOTONS", "photons"),
                Photons::KdTree => (PhotonDisplay::Kdtree, "KD-TREE", "kdtree"),
            };
            settings.photon.display = display;
            let label = format!("{name} (photon, {} photons)", settings.photons());
            return job(
                EngineKind::Photon,
                settings,
                label,
                &["--visualize"],
                vec!["--visualize".into(), flag.into()],
            );
        }
        let (display, name, flag) = MODES[self.mode];
        let mesh_as_given = self.subdivide == session.settings.radiosity.subdivide
            && !self.wireframe
            && !self.interpolate;
        match self.shots {
            None if display == RadiosityDisplay::Materials && mesh_as_given => job(
                EngineKind::Raycast,
                settings,
                "MATERIALS (raycast)".into(),
                &[],
                Vec::new(),
            ),
            shots => {
                let shots = shots.unwrap_or(0);
                let r = &mut settings.radiosity;
                r.iterations = Some(shots);
                r.display = display;
                r.subdivide = self.subdivide;
                r.interpolate = self.interpolate;
                r.wireframe = self.wireframe;
                let mut flags = vec![
                    "--radiosity-iterations".to_string(),
                    shots.to_string(),
                    "--visualize".into(),
                    flag.into(),
                    "--subdivide".into(),
                    self.subdivide.to_string(),
                ];
                if self.interpolate {
                    flags.push("--interpolate".into());
                }
                if self.wireframe {
                    flags.push("--wireframe".into());
                }
                job(
                    EngineKind::Radiosity,
                    settings,
                    format!("{name} (radiosity, {shots} shots)"),
                    RADIOSITY_CONTROLS,
                    flags,
                )
            }
        }
    }
}

/// The residual (undistributed over emitted power) a radiosity render's summary reports
/// ("…, 501 shots, residual 9.836e-4, …"): with `--radiosity-iterations` the solver takes
/// exactly that many shots, so the animation reads here whether it has converged.
pub fn residual(summary: &[String]) -> Option<f32> {
    summary.iter().find_map(|line| {
        let after = line.split("residual ").nth(1)?;
        after.split([',', ' ']).next()?.parse().ok()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_residual_is_read_from_the_solvers_summary() {
        let line = "radiosity: 96 patches, progressive solver, 501 shots, residual 9.836e-4, converged to tolerance 1.0e-3".to_string();
        assert_eq!(residual(&[line]), Some(9.836e-4));
        assert_eq!(residual(&["photons: 20000".to_string()]), None);
    }
}
