//! The viewer's window: winit's event loop on the main thread, the image drawn into a CPU
//! framebuffer (softbuffer), keys and mouse turned into jobs for the render thread. Nothing
//! here renders: the event loop never waits for an image.

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
use super::worker::{Frame, Job, Report, Worker};
use crate::engines::EngineKind;
use crate::scene::Camera;

/// The keys, as 'h' prints them.
const KEYS: &str = "\
keys:
  r  ray trace progressively (16x16 blocks, 8x8, 4x4, 2x2, then the full image) with the render flags given
  o  write the image on screen to <scene stem>.view.png and print the render command line that renders it offline
  h  print these keys
  q  quit (closing the window too)
mouse:
  left drag    orbit around the point of interest
  right drag   dolly (the wheel too)
  middle drag  pan
  a camera move cancels a trace and shows the MATERIALS preview again";

/// The course viewer's keys this viewer does not have yet, and what they do there.
const NOT_YET: [(&str, &str); 13] = [
    ("t", "the ray tree of the pixel under the pointer"),
    ("v", "cycling the radiosity visualization"),
    ("w", "the wireframe"),
    ("s", "subdividing the radiosity mesh"),
    ("i", "interpolating the radiosity display"),
    (" ", "one radiosity iteration"),
    ("a", "animating the radiosity solver"),
    ("c", "resetting the radiosity solution"),
    ("p", "tracing photons"),
    ("l", "showing the photons"),
    ("k", "showing the kd-tree"),
    ("g", "ray tracing with photon gathering"),
    ("b", "toggling back-face culling"),
];

/// Opens the window and runs until 'q' or the window is closed.
pub fn run(session: Session, worker_start: impl FnOnce(WakeUp) -> Worker) -> Result<(), String> {
    let event_loop = EventLoop::<Report>::with_user_event()
        .build()
        .map_err(|e| format!("render view: cannot open a window: {e}"))?;
    let proxy = event_loop.create_proxy();
    let worker = worker_start(Box::new(move |report| {
        // The loop is gone only once the window has closed: nobody is left to show it.
        let _ = proxy.send_event(report);
    }));
    let mut app = App::new(session, worker);
    app.submit(Job::Preview(app.camera));
    let result = event_loop.run_app(&mut app);
    if let Some(worker) = app.worker.take() {
        worker.stop();
    }
    result.map_err(|e| format!("render view: the window's event loop failed: {e}"))?;
    app.failure.map_or(Ok(()), Err)
}

/// How the render thread hands a report to the event loop.
pub type WakeUp = Box<dyn Fn(Report) + Send>;

struct App {
    session: Session,
    worker: Option<Worker>,
    window: Option<Rc<Window>>,
    surface: Option<softbuffer::Surface<Rc<Window>, Rc<Window>>>,
    /// The image on screen.
    shown: Option<Box<Frame>>,
    /// The camera of the newest job.
    camera: Camera,
    /// The camera's distance to its point of interest at start (bounds the dolly).
    start_distance: f32,
    pointer: PhysicalPosition<f64>,
    dragging: Option<MouseButton>,
    /// A failure that ends the viewer with an error.
    failure: Option<String>,
}

impl App {
    fn new(session: Session, worker: Worker) -> App {
        let camera = session.camera;
        App {
            start_distance: camera.focus_distance(),
            camera,
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

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), String> {
        let (w, h) = (self.session.settings.width, self.session.settings.height);
        let attributes = Window::default_attributes()
            .with_title(self.title())
            .with_inner_size(PhysicalSize::new(w, h))
            .with_resizable(false);
        let window = Rc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| format!("render view: cannot open a window: {e}"))?,
        );
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
            Some(f) if f.engine == EngineKind::Raycast => "MATERIALS (raycast)".to_string(),
            Some(f) if f.finished => {
                format!("{}: done, {} in {:.2} s", f.engine, f.stage, f.seconds)
            }
            Some(f) => format!(
                "{}: {} ({}/{}), {:.1} s",
                f.engine, f.stage, f.step.0, f.step.1, f.seconds
            ),
        };
        format!("trilux: {name}: {what}")
    }

    /// Draws the image on screen, centred on black if the window is larger.
    fn draw(&mut self) -> Result<(), String> {
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
        if let Some(frame) = &self.shown {
            let film = &frame.film;
            let rgb = film.to_srgb8();
            let (fw, fh) = (film.width as usize, film.height as usize);
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

    fn key(&mut self, key: &str, event_loop: &ActiveEventLoop) {
        match key {
            "q" => event_loop.exit(),
            "r" => self.submit(Job::Trace(self.camera)),
            "o" => self.write_shown(),
            "h" => println!("{KEYS}"),
            other => {
                if let Some((_, what)) = NOT_YET.iter().find(|(k, _)| *k == other) {
                    eprintln!(
                        "render view: '{other}' ({what}) is not in the viewer yet; 'h' lists the keys it has"
                    );
                }
            }
        }
    }

    /// 'o': the image on screen to `<stem>.view.png`, and the command line that renders it.
    fn write_shown(&mut self) {
        let Some(frame) = &self.shown else {
            eprintln!("render view: 'o': no image yet");
            return;
        };
        let path = self.session.beside_stem("view.png");
        if let Err(e) = frame.film.write(&path) {
            eprintln!("render view: 'o': {e}");
            return;
        }
        let offline = self.session.beside_stem("png");
        let command = self
            .session
            .offline_command(frame.engine, &frame.camera, &offline);
        if !frame.finished {
            eprintln!(
                "render view: wrote {} while the trace is at {}; this command renders the finished image:",
                path.display(),
                frame.stage
            );
        } else {
            eprintln!(
                "render view: wrote {}; this command renders it offline:",
                path.display()
            );
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
            self.submit(Job::Preview(camera));
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
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed && !event.repeat =>
            {
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
