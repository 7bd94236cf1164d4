//! `render view SCENE [render flags]`: the course's interactive viewer. The scene appears at
//! once in the MATERIALS view (`--engine raycast`); 'r' renders it progressively with the
//! flags given; the mouse moves the camera (cancelling a render in flight); 'o' writes the
//! image on screen and prints the offline command line that renders the same image; 'h'
//! lists the keys. Errors in the scene or the flags are reported before a window opens.
//!
//! The window (`window`) only shows images and turns input into jobs; the render thread
//! (`worker`) renders them with the library's engines, exactly as `render` does. Behind the
//! cargo feature `viewer` (on by default).

#[cfg(feature = "viewer")]
mod orbit;
#[cfg(feature = "viewer")]
mod session;
#[cfg(feature = "viewer")]
mod view;
#[cfg(feature = "viewer")]
mod window;
#[cfg(feature = "viewer")]
mod worker;

/// Runs the viewer on `SCENE [render flags]` until 'q' or the window is closed.
#[cfg(feature = "viewer")]
pub fn run(words: &[String]) -> Result<(), String> {
    let (session, scene) = session::Session::start(words)?;
    let args = &session.args;
    let pool = crate::parallel::thread_pool(args.common.threads).map_err(|e| e.to_string())?;
    let kind = args.accel_kind(&scene);
    crate::parallel::worker_start();
    let accel = pool
        .install(|| crate::accel::build(&scene, kind, &args.accel_options()))
        .map_err(|e| e.to_string())?;
    let world = std::sync::Arc::new(std::sync::RwLock::new(worker::World { scene, accel }));
    let renderer = worker::Renderer {
        world: world.clone(),
        pool,
        accel_kind: kind,
        accel_options: args.accel_options(),
        radiosity: None,
        photons: None,
    };
    window::run(session, world, |wake_up| {
        worker::Worker::start(renderer, wake_up)
    })
}

/// Without the `viewer` feature: says so.
#[cfg(not(feature = "viewer"))]
pub fn run(_words: &[String]) -> Result<(), String> {
    Err(
        "render view: this build has no viewer (it was built without the cargo feature `viewer`)"
            .into(),
    )
}
