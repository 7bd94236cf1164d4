//! The instructions the batched kernels run in (`pulp`'s run-time dispatch: the BVH's batched
//! queries, the path tracer's vertex kernel, the Sobol lanes): the processor's widest, or
//! narrower where the environment's `TRILUX_SIMD` asks, so that one host measures what a
//! narrower one gets, as Mitsuba 3's kernels are built narrower with its vector width
//! (`scripts/path-time-vs-mitsuba.sh`).

use std::sync::OnceLock;

/// The instruction set the kernels dispatch to. `TRILUX_SIMD`: `avx512` (the default: the
/// widest the processor has), `avx2` (x86-64-v3, 8 lanes of f32) or `scalar`; a level the
/// processor lacks, or any other value (with a warning), gives the widest it has.
pub fn arch() -> pulp::Arch {
    static ARCH: OnceLock<pulp::Arch> = OnceLock::new();
    *ARCH.get_or_init(|| {
        let widest = pulp::Arch::new();
        let asked = std::env::var("TRILUX_SIMD");
        match asked.as_deref() {
            Err(_) | Ok("avx512") => widest,
            #[cfg(target_arch = "x86_64")]
            Ok("avx2") => pulp::x86::V3::try_new().map_or(widest, pulp::Arch::V3),
            #[cfg(target_arch = "x86_64")]
            Ok("scalar") => pulp::Arch::Scalar,
            Ok(other) => {
                eprintln!(
                    "warning: TRILUX_SIMD={other}: expected avx512, avx2 or scalar; the kernels \
                     run in the processor's widest instructions"
                );
                widest
            }
        }
    })
}
