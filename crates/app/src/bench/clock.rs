//! The benchmarks' clocks and statistics: the calling thread's CPU time
//! (the per-core cost, which other processes on a shared machine do not
//! inflate, from the `cpu-time` crate) and nearest-rank percentiles.

/// CPU time consumed by the calling thread (µs), 0 where the platform does
/// not report it.
pub fn thread_cpu_us() -> f64 {
    cpu_time::ThreadTime::try_now()
        .map(|t| t.as_duration().as_secs_f64() * 1e6)
        .unwrap_or(0.0)
}

/// Nearest-rank percentile `q ∈ [0, 1]` of sorted samples (0 if empty).
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Nearest rank (Hyndman & Fan's definition 1): of 1..=10, the median
    /// is the 5th value, p90 the 9th, p100 the 10th, p0 the first.
    #[test]
    fn nearest_rank_percentiles() {
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(percentile(&v, 0.5), 5.0);
        assert_eq!(percentile(&v, 0.9), 9.0);
        assert_eq!(percentile(&v, 1.0), 10.0);
        assert_eq!(percentile(&v, 0.0), 1.0);
        assert_eq!(percentile(&[], 0.5), 0.0);
    }

    /// The thread clock advances by at least the CPU work done and never
    /// runs backwards (Linux reports it; other platforms give 0).
    #[test]
    fn thread_clock_is_monotonic() {
        let a = thread_cpu_us();
        let mut x = 0u64;
        for i in 0..2_000_000u64 {
            x = x.wrapping_add(std::hint::black_box(i) * i);
        }
        std::hint::black_box(x);
        let b = thread_cpu_us();
        assert!(b >= a, "{a} -> {b}");
        if cfg!(target_os = "linux") {
            assert!(b > a, "no CPU time counted for 2e6 multiply-adds");
        }
    }
}
