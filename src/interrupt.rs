//! Ctrl-C. The first SIGINT asks every long loop (pixel rows, radiosity shots, photon blocks,
//! report runs) to stop where it is, so that the command can write what it has — atomically —
//! and exit non-zero; a second SIGINT ends the process at once. What a render has after a
//! solve or a photon pass was stopped is the image of that partial solution or those photons
//! (the pixel loop started after the first SIGINT runs to the end); a report has the runs
//! that finished (the one in flight is left out, and a reference cut short is not cached).
//!
//! The viewer stops work the same way: each render it asks for is a numbered job, and a job
//! is superseded — every long loop stops as on Ctrl-C, and the pixel loop too — as soon as a
//! newer one is submitted (a camera move, a new key).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);
/// The newest job submitted, and the job being run (both 0 outside the viewer).
static NEWEST_JOB: AtomicU64 = AtomicU64::new(0);
static RUNNING_JOB: AtomicU64 = AtomicU64::new(0);

/// Installs the handler (once per process; later calls do nothing).
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\ninterrupted: finishing the work in flight (Ctrl-C again to quit at once)");
    });
}

/// Whether Ctrl-C has been pressed or the running job is superseded.
pub fn requested() -> bool {
    ctrl_c() || superseded()
}

/// Whether Ctrl-C has been pressed.
pub fn ctrl_c() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// Whether a newer job than the running one has been submitted.
pub fn superseded() -> bool {
    RUNNING_JOB.load(Ordering::Relaxed) != NEWEST_JOB.load(Ordering::Relaxed)
}

/// Numbers a new job, superseding the running one; returns its number.
pub fn submit_job() -> u64 {
    NEWEST_JOB.fetch_add(1, Ordering::SeqCst) + 1
}

/// Marks job `number` as the one running (superseded at once if a newer one was submitted).
pub fn start_job(number: u64) {
    RUNNING_JOB.store(number, Ordering::SeqCst);
}
