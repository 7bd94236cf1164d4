//! The viewer's window: winit's event loop on the main thread, the image drawn into a CPU
//! framebuffer (softbuffer), keys and mouse turned into jobs for the render thread. Nothing
//! here renders: the event loop never waits for an image.

use std::borrow::Cow;
use std::num::NonZeroU32;
use std::rc::Rc;

use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use super::orbit;
use super::session::Session;
use super::view::{Photons, ViewState};
use super::worker::{Frame, Job, Report, Worker, World};
use crate::engines::{raytrace, EngineKind};
use crate::film::ray_tree::{self, Segment};
use crate::film::Film;
use crate::scene::Camera;
use std::sync::{Arc, RwLock};

/// The keys, as 'h' prints them.
const KEYS: &str = "\
keys:
  t      draw the ray tree of the pixel under the pointer (again on the same pixel: hide it)
  r      ray trace progressively (16x16 blocks, 8x8, 4x4, 2x2, then the full image) with the render flags given
  v      cycle the views: MATERIALS, RADIANCE, FORM_FACTORS, LIGHTS, UNDISTRIBUTED, ABSORBED
  space  one radiosity shot more, shot on from the solution kept
  a      animate the radiosity solver: shots added to the solution kept, the image updating, until it converges or a key stops it
  c      reset the radiosity solution (0 shots)
  s      subdivide the radiosity mesh once more
  i      interpolate the radiosity display (toggle)
  w      wireframe: the patches' outlines (toggle)
  b      back faces: quads seen from behind too (--two-sided; toggle)
  p      trace photons (-num_photons_to_shoot) and show them
  l      show the photons traced ('v' goes back to the views above)
  k      show the photons' kd-tree
  g      ray trace with photon gathering (the photon engine)
  o      write the image on screen to <scene stem>.view.png and print the render command line that renders it offline
  h      print these keys
  q      quit (closing the window too)
mouse:
  left drag    orbit around the point of interest
  right drag   dolly (the wheel too)
  middle drag  pan
  a camera move cancels a render in flight and shows the current view from the new camera";

/// A windowing library's error without the place in its source it names: winit's OS errors
/// read `os error at /…/cargo/registry/…/mod.rs:765: what`, a path of the machine that built
/// the program, which means nothing to its user.
fn without_source_path(e: &dyn std::fmt::Display) -> String {
    let text = e.to_string();
    match text.find(".rs:") {
        Some(at) => match text[at..].find(": ") {
            Some(end) => text[at + end + 2..].to_string(),
            None => text,
        },
        None => text,
    }
}

/// Opens the window and runs until 'q' or the window is closed.
pub fn run(
    session: Session,
    world: Arc<RwLock<World>>,
    worker_start: impl FnOnce(WakeUp) -> Worker,
) -> Result<(), String> {
    if ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"]
        .iter()
        .all(|v| std::env::var_os(v).is_none())
    {
        return Err(
            "render view: no display to open a window on (DISPLAY and WAYLAND_DISPLAY are not set); render without `view` to write the image instead"
                .into(),
        );
    }
    let event_loop = EventLoop::<Report>::with_user_event()
        .build()
        .map_err(|e| {
            format!(
                "render view: cannot open a window: {}",
                without_source_path(&e)
            )
        })?;
    let proxy = event_loop.create_proxy();
    let worker = worker_start(Box::new(move |report| {
        // The loop is gone only once the window has closed: nobody is left to show it.
        let _ = proxy.send_event(report);
    }));
    let mut app = App::new(session, world, worker);
    app.show_view();
    let result = event_loop.run_app(&mut app);
    if let Some(worker) = app.worker.take() {
        worker.stop();
    }
    result.map_err(|e| format!("render view: the window's event loop failed: {e}"))?;
    app.failure.map_or(Ok(()), Err)
}

/// How the render thread hands a report to the event loop.
pub type WakeUp = Box<dyn Fn(Report) + Send>;

/// A ray tree drawn over the image: its pixel (column, row from the bottom), the camera it
/// was traced through, and its rays.
struct RayTree {
    pixel: (u32, u32),
    camera: Camera,
    segments: Vec<Segment>,
}

struct App {
    session: Session,
    /// The scene and the Accel, read for ray trees.
    world: Arc<RwLock<World>>,
    /// The ray tree drawn over every image, whatever the camera ('t').
    ray_tree: Option<RayTree>,
    worker: Option<Worker>,
    window: Option<Rc<Window>>,
    surface: Option<softbuffer::Surface<Rc<Window>, Rc<Window>>>,
    /// The image on screen.
    shown: Option<Box<Frame>>,
    /// The camera of the newest job.
    camera: Camera,
    /// What is shown when no trace is ('v', the radiosity and photon keys).
    view: ViewState,
    /// The camera's distance to its point of interest at start (bounds the dolly).
    start_distance: f32,
    pointer: PhysicalPosition<f64>,
    dragging: Option<MouseButton>,
    /// A failure that ends the viewer with an error.
    failure: Option<String>,
}

impl App {
    fn new(session: Session, world: Arc<RwLock<World>>, worker: Worker) -> App {
        let camera = session.camera;
        App {
            world,
            ray_tree: None,
            start_distance: camera.focus_distance(),
            camera,
            view: ViewState::new(&session),
            session,
            worker: Some(worker),
            window: None,
            surface: None,
            shown: None,
            pointer: PhysicalPosition::new(0.0, 0.0),
            dragging: None,
            failure: None,
        }
    }

    fn submit(&self, job: Job) {
        if let Some(worker) = &self.worker {
            worker.submit(job);
        }
    }

    /// The current view from the current camera.
    fn show_view(&self) {
        self.submit(self.view.job(&self.session, self.camera));
    }

    /// A render with `engine` and the flags given, in stages where the engine has no
    /// pre-pass ('r', 'g').
    fn trace(&self, engine: EngineKind) {
        let mut settings = self.session.settings.clone();
        self.session.engine_defaults(engine, &mut settings);
        self.submit(Job {
            camera: self.camera,
            engine,
            settings,
            progressive: true,
            time_limit: self.session.args.common.time_limit,
            two_sided: self.view.two_sided,
            label: engine.to_string(),
            controls: &[],
            flags: Vec::new(),
        });
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), String> {
        let (w, h) = (self.session.settings.width, self.session.settings.height);
        let attributes = Window::default_attributes()
            .with_title(self.title())
            .with_inner_size(PhysicalSize::new(w, h))
            .with_resizable(false);
        let window = Rc::new(event_loop.create_window(attributes).map_err(|e| {
            format!(
                "render view: cannot open a window: {}",
                without_source_path(&e)
            )
        })?);
        let context = softbuffer::Context::new(window.clone())
            .map_err(|e| format!("render view: no framebuffer for the window: {e}"))?;
        let surface = softbuffer::Surface::new(&context, window.clone())
            .map_err(|e| format!("render view: no framebuffer for the window: {e}"))?;
        self.window = Some(window);
        self.surface = Some(surface);
        Ok(())
    }

    /// The window's title: the scene, then what is on screen and how far it is.
    fn title(&self) -> String {
        let name = self.session.input.file_name().map_or_else(
            || self.session.input.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        let what = match &self.shown {
            None => "loading".to_string(),
            Some(f) if !f.finished => format!(
                "{}: {} ({}/{}), {:.1} s",
                f.job.label, f.stage, f.step.0, f.step.1, f.seconds
            ),
            Some(f) if f.job.progressive => {
                format!("{}: done, {} in {:.2} s", f.job.label, f.stage, f.seconds)
            }
            // Milliseconds: a view drawn from what the render thread keeps (a shot more, a
            // camera move) takes a few.
            Some(f) => format!("{} in {:.3} s", f.job.label, f.seconds),
        };
        let residual = self
            .shown
            .as_ref()
            .and_then(|f| super::view::residual(&f.summary))
            .map_or(String::new(), |r| format!(", residual {r:.1e}"));
        let animating = if self.view.animating {
            ", animating"
        } else {
            ""
        };
        let sides = match &self.shown {
            Some(f) if f.job.two_sided => ", two-sided",
            _ => "",
        };
        format!("trilux: {name}: {what}{sides}{residual}{animating}")
    }

    /// Draws the image on screen, centred on black if the window is larger.
    fn draw(&mut self) -> Result<(), String> {
        // The pixels as 8-bit sRGB, with the image's size, before the surface is borrowed.
        let image = self
            .on_screen()
            .map(|f| (f.to_srgb8(), f.width as usize, f.height as usize));
        let (Some(window), Some(surface)) = (&self.window, &mut self.surface) else {
            return Ok(());
        };
        let size = window.inner_size();
        let (Some(w), Some(h)) = (NonZeroU32::new(size.width), NonZeroU32::new(size.height)) else {
            return Ok(());
        };
        let fail = |e: softbuffer::SoftBufferError| format!("render view: drawing failed: {e}");
        surface.resize(w, h).map_err(fail)?;
        let mut buffer = surface.buffer_mut().map_err(fail)?;
        buffer.fill(0);
        if let Some((rgb, fw, fh)) = image {
            let (ww, wh) = (size.width as usize, size.height as usize);
            let (x0, y0) = (ww.saturating_sub(fw) / 2, wh.saturating_sub(fh) / 2);
            for row in 0..fh.min(wh) {
                for x in 0..fw.min(ww) {
                    let p = &rgb[3 * (row * fw + x)..];
                    buffer[(y0 + row) * ww + x0 + x] =
                        (p[0] as u32) << 16 | (p[1] as u32) << 8 | p[2] as u32;
                }
            }
        }
        buffer.present().map_err(fail)
    }

    /// The image on screen: the shown frame, with the ray tree drawn over it (a copy only
    /// then).
    fn on_screen(&self) -> Option<Cow<'_, Film>> {
        let frame = self.shown.as_ref()?;
        Some(match &self.ray_tree {
            Some(tree) => Cow::Owned(ray_tree::overlay(
                &frame.film,
                &frame.job.camera,
                &tree.segments,
            )),
            None => Cow::Borrowed(&frame.film),
        })
    }

    /// 't': the ray tree of the pixel under the pointer, as the ray tracer traces it with
    /// the flags given, through the camera of the image on screen; the same pixel again
    /// hides it.
    fn toggle_ray_tree(&mut self) {
        let (w, h) = (self.session.settings.width, self.session.settings.height);
        let Some(window) = &self.window else { return };
        let size = window.inner_size();
        let (x0, y0) = (
            size.width.saturating_sub(w) as f64 / 2.0,
            size.height.saturating_sub(h) as f64 / 2.0,
        );
        let (column, row) = (self.pointer.x - x0, self.pointer.y - y0);
        if !(0.0..w as f64).contains(&column) || !(0.0..h as f64).contains(&row) {
            return eprintln!("render view: 't': the pointer is not over the image");
        }
        let pixel = (column as u32, h - 1 - row as u32);
        if self.ray_tree.as_ref().is_some_and(|t| t.pixel == pixel) {
            self.ray_tree = None;
            return;
        }
        let Some(camera) = self.shown.as_ref().map(|f| f.job.camera) else {
            return;
        };
        let Ok(world) = self.world.read() else {
            return eprintln!("render view: 't': the scene's lock was poisoned by a failed render");
        };
        let segments = raytrace::ray_tree(
            &world.scene,
            &camera,
            world.accel.as_ref(),
            &self.session.settings,
            pixel,
        );
        println!(
            "ray tree of pixel {} {}: {} rays",
            pixel.0,
            pixel.1,
            segments.len()
        );
        self.ray_tree = Some(RayTree {
            pixel,
            camera,
            segments,
        });
    }

    fn key(&mut self, key: &str, event_loop: &ActiveEventLoop) {
        // Any key but 'a' stops an animation ('o' and 'h' only look).
        if !matches!(key, "a" | "o" | "h") {
            self.view.animating = false;
        }
        let view = &mut self.view;
        match key {
            "q" => return event_loop.exit(),
            "r" => return self.trace(self.session.engine),
            "g" => return self.trace(EngineKind::Photon),
            "o" => return self.write_shown(),
            "t" => {
                self.toggle_ray_tree();
                if let Some(window) = &self.window {
                    window.request_redraw();
                }
                return;
            }
            "h" => return println!("{KEYS}"),
            "v" => view.next_mode(),
            " " => view.shoot(),
            "a" => {
                view.animating = !view.animating;
                if view.animating {
                    view.animate_step();
                }
            }
            "c" => view.shots = Some(0),
            "s" => {
                view.subdivide += 1;
                view.shots.get_or_insert(0);
            }
            "i" => view.interpolate = !view.interpolate,
            "w" => view.wireframe = !view.wireframe,
            "p" | "l" | "k" => {
                if self.session.settings.photons() == 0 {
                    return eprintln!(
                        "render view: '{key}': no photons to shoot; start the viewer with -num_photons_to_shoot N"
                    );
                }
                if key != "p" && !view.photons_traced {
                    return eprintln!("render view: '{key}': no photons yet; 'p' traces them");
                }
                view.photons_traced = true;
                view.photons = Some(match key {
                    "k" => Photons::KdTree,
                    _ => Photons::Points,
                });
            }
            "b" => view.two_sided = !view.two_sided,
            _ => return,
        }
        self.show_view();
        if let Some(window) = &self.window {
            window.set_title(&self.title());
        }
    }

    /// 'o': the image on screen to `<stem>.view.png` (and its ray tree to
    /// `<stem>.view.raytree.obj`), and the command line that renders them offline.
    fn write_shown(&mut self) {
        let (Some(frame), Some(film)) = (&self.shown, self.on_screen()) else {
            eprintln!("render view: 'o': no image yet");
            return;
        };
        let path = self.session.beside_stem("view.png");
        if let Err(e) = film.write(&path) {
            eprintln!("render view: 'o': {e}");
            return;
        }
        let offline = self.session.beside_stem("png");
        let mut command = self.session.offline_command(&frame.job, &offline);
        let mut written = path.display().to_string();
        if let Some(tree) = &self.ray_tree {
            let obj = self.session.beside_stem("view.raytree.obj");
            if let Err(e) = ray_tree::write_obj(&tree.segments, &obj) {
                eprintln!("render view: 'o': {e}");
                return;
            }
            written += &format!(" and {}", obj.display());
            if tree.camera == frame.job.camera {
                command += &format!(" --ray-tree {} {}", tree.pixel.0, tree.pixel.1);
            } else {
                eprintln!(
                    "render view: the ray tree drawn is pixel {} {} of an earlier camera: the command below leaves it out; {} holds its rays",
                    tree.pixel.0,
                    tree.pixel.1,
                    obj.display()
                );
            }
        }
        if !frame.finished {
            eprintln!(
                "render view: wrote {written} while the render is at {}; this command renders the finished image:",
                frame.stage
            );
        } else if command.contains(" --ray-tree ") {
            eprintln!(
                "render view: wrote {written}; this command renders them offline (the image with the tree as {}):",
                self.session.beside_stem("raytree.png").display()
            );
        } else {
            eprintln!("render view: wrote {written}; this command renders it offline:");
        }
        println!("{command}");
    }

    /// A drag from the last pointer position to `to` with the button held.
    fn drag(&mut self, to: PhysicalPosition<f64>) {
        let (dx, dy) = (
            (to.x - self.pointer.x) as f32,
            (to.y - self.pointer.y) as f32,
        );
        self.pointer = to;
        let size = (self.session.settings.width, self.session.settings.height);
        let camera = match self.dragging {
            Some(MouseButton::Left) => orbit::orbit(&self.camera, (dx, dy)),
            Some(MouseButton::Right) => orbit::dolly(
                &self.camera,
                orbit::dolly_steps_of_drag(dy),
                self.start_distance,
            ),
            Some(MouseButton::Middle) => orbit::pan(&self.camera, (dx, dy), size),
            _ => return,
        };
        self.move_camera(camera);
    }

    fn move_camera(&mut self, camera: Camera) {
        if camera != self.camera {
            self.camera = camera;
            self.view.animating = false;
            self.show_view();
        }
    }

    /// An animation's next step once its last image is in: more shots, unless the solver
    /// stopped before the shots asked for (converged, or nothing emits).
    fn animate(&mut self, frame: &Frame) {
        if !self.view.animating || frame.job.engine != EngineKind::Radiosity {
            return;
        }
        let tolerance = self.session.settings.radiosity.tolerance;
        let converged = super::view::residual(&frame.summary).is_none_or(|r| r <= tolerance);
        if !converged {
            self.view.animate_step();
            self.show_view();
        } else {
            self.view.animating = false;
        }
    }
}

impl ApplicationHandler<Report> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            if let Err(e) = self.open(event_loop) {
                self.failure = Some(e);
                event_loop.exit();
            }
        }
    }

    fn user_event(&mut self, _: &ActiveEventLoop, report: Report) {
        match report {
            Report::Frame(frame) => {
                if frame.finished {
                    self.animate(&frame);
                }
                self.shown = Some(frame);
                if let Some(window) = &self.window {
                    window.set_title(&self.title());
                    window.request_redraw();
                }
            }
            Report::Failed(message) => eprintln!("render view: {message}"),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.draw() {
                    self.failure = Some(e);
                    event_loop.exit();
                }
            }
            // Synthetic presses are winit's replay, on focus in, of the keys the server holds
            // down at the time it reads the focus event: a key pressed just after the focus
            // change would arrive twice, as the replay and as its own event.
            WindowEvent::KeyboardInput {
                event,
                is_synthetic: false,
                ..
            } if event.state == ElementState::Pressed && !event.repeat => {
                match &event.logical_key {
                    Key::Character(c) => self.key(&c.to_lowercase(), event_loop),
                    Key::Named(NamedKey::Space) => self.key(" ", event_loop),
                    _ => {}
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.dragging = (state == ElementState::Pressed).then_some(button);
            }
            WindowEvent::CursorMoved { position, .. } => {
                if self.dragging.is_some() {
                    self.drag(position);
                } else {
                    self.pointer = position;
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                let camera = orbit::dolly(&self.camera, steps, self.start_distance);
                self.move_camera(camera);
            }
            _ => {}
        }
    }
}
