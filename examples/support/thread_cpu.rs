//! Shared by the profiling examples (`reduced_speed`, `reduced_profile`, `fallback_profile`):
//! the CPU time of the calling thread.

/// CPU seconds of this thread (`/proc/thread-self/schedstat`); 0 where not available. Some
/// kernels move it in 4 ms ticks, so a single short run reads 0 or 4 ms and only sums over many
/// runs are meaningful.
pub fn cpu() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-9)
}
