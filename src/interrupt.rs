//! Ctrl-C. The first SIGINT asks every long loop (pixel rows, radiosity shots, photon blocks,
//! report runs) to stop where it is, so that the command can write what it has — atomically —
//! and exit non-zero; a second SIGINT ends the process at once. What a render has after a
//! solve or a photon pass was stopped is the image of that partial solution or those photons
//! (the pixel loop started after the first SIGINT runs to the end); a report has the runs
//! that finished (the one in flight is left out, and a reference cut short is not cached).

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Installs the handler (once per process; later calls do nothing).
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\ninterrupted: finishing the work in flight (Ctrl-C again to quit at once)");
    });
}

/// Whether Ctrl-C has been pressed.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}
