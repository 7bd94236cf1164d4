//! The worker threads: one rayon pool, with Embree's recommended floating-point mode set on
//! every worker.

/// Builds a pool of `threads` workers (0: one per core) with flush-to-zero and
/// denormals-are-zero set on each when Embree is linked.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .start_handler(|_| worker_start())
        .build()
}

/// What every worker thread runs first (also call it on the main thread before tracing).
pub fn worker_start() {
    #[cfg(feature = "embree")]
    crate::accel::embree::set_flush_denormals();
}
