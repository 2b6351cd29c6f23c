//! Learning runs flush subnormal numbers to zero (FTZ and DAZ on x86, FZ on aarch64).
//!
//! Why: far from the data the SE kernel's values and the products built from them fall below
//! 2.2e-308, and x86 cores take a micro-code assist on every such operand. Measured with the
//! `train_time` example on recorded runs (BENCHMARKS.md): on VILTA seed 2's 1100 points one
//! FITC nlml + gradient took 0.04–2.6 s per output with gradual underflow and 0.04 s each when
//! flushed, and the update's fit went from 592 s to 39 s; on vil-gic-rbf10 seed 4's 1500 points
//! the fit went from 192 s to 51 s and one policy value + gradient from 10.8 s to 3.1 s. The
//! iterations, evaluations, nlml and J were the same. Flushing changes only values below
//! 2.2e-308, far beneath every tolerance; TensorFlow, whose PILCO port we compare with, runs its
//! CPU kernels the same way.
//!
//! The flags are per thread. A run sets them on its own thread and relies on the global rayon
//! pool's threads having them too, which holds when this module started that pool. When the
//! pool was started elsewhere without them, the run keeps gradual underflow on every thread
//! (and says so), so a result never depends on which thread computed it.

use std::sync::OnceLock;

/// Whether the current thread flushes subnormal results to zero.
pub fn flushing_here() -> bool {
    std::hint::black_box(f64::MIN_POSITIVE) * std::hint::black_box(0.5) == 0.0
}

/// The mode of the current thread as run records name it.
pub fn mode_here() -> &'static str {
    if flushing_here() {
        "flushed to zero"
    } else {
        "gradual underflow"
    }
}

/// Start the global rayon pool with flushing threads if nobody has started it yet, and report
/// whether every thread of the pool flushes (checked once per process).
pub fn pool_flushes() -> bool {
    static FLUSHES: OnceLock<bool> = OnceLock::new();
    *FLUSHES.get_or_init(|| {
        let started = rayon::ThreadPoolBuilder::new()
            .spawn_handler(|thread| {
                std::thread::Builder::new()
                    .spawn(move || {
                        // SAFETY: the flags only change how values below f64::MIN_POSITIVE are
                        // produced and read; no code of ours depends on gradual underflow.
                        unsafe { no_denormals::no_denormals(|| thread.run()) }
                    })
                    .map(|_| ())
            })
            .build_global();
        if let Err(e) = started {
            tracing::debug!(error = %e, "rayon's global pool was started elsewhere");
        }
        rayon::broadcast(|_| flushing_here()).into_iter().all(|f| f)
    })
}

/// Run `f` with subnormals flushed on this thread and the pool's, or with gradual underflow
/// everywhere when the pool cannot flush (see the module docs).
pub fn run_flushed<T>(f: impl FnOnce() -> T) -> T {
    if pool_flushes() {
        // SAFETY: as in `pool_flushes`; the guard restores this thread's flags afterwards.
        unsafe { no_denormals::no_denormals(f) }
    } else {
        tracing::warn!(
            "rayon's global pool was started without flushing subnormals; \
             this run keeps gradual underflow (slower, same numbers to 1e-300)"
        );
        f()
    }
}
