//! The `--stats` report: per-stage time shares, items and rates.

use crate::integrator::wavefront;

/// Each stage's share of the time, `name 12.3%`, largest first.
pub fn stage_shares(st: &wavefront::Stats) -> String {
    let total: f64 = st.time.iter().map(|t| t.as_secs_f64()).sum();
    let mut shares: Vec<(f64, &str)> = wavefront::Stage::ALL
        .iter()
        .filter(|s| st.calls[s.index()] > 0)
        .map(|s| (st.time[s.index()].as_secs_f64() / total.max(1e-12), s.name()))
        .collect();
    shares.sort_by(|a, b| b.0.total_cmp(&a.0));
    let list: Vec<String> = shares.iter().map(|(f, n)| format!("{n} {:.1}%", 100.0 * f)).collect();
    list.join(", ")
}

/// The `--stats` table on stderr.
pub fn print_stats(st: &wavefront::Stats, wall: f64, non_finite: u64) {
    let total: f64 = st.time.iter().map(|t| t.as_secs_f64()).sum();
    eprintln!("{:<22} {:>7} {:>12} {:>10} {:>9}", "stage", "time %", "items", "M items/s", "calls");
    for stage in wavefront::Stage::ALL {
        let k = stage.index();
        if st.calls[k] == 0 {
            continue;
        }
        let t = st.time[k].as_secs_f64();
        eprintln!(
            "{:<22} {:>6.1}% {:>12} {:>10.2} {:>9}",
            stage.name(),
            100.0 * t / total,
            st.items[k],
            st.items[k] as f64 / t / 1e6,
            st.calls[k]
        );
    }
    let ix = wavefront::Stage::IntersectClosest.index();
    let sh = wavefront::Stage::TraceShadowRays.index();
    let rays = st.items[ix] + st.items[sh];
    eprintln!(
        "{} iterations, mean queue occupancy {:.1}%; {} rays ({} closest, {} shadow): {:.2} Mrays/s; {:.3} M samples/s; {} NaN/Inf discarded; lanes {}",
        st.iterations,
        100.0 * st.occupancy_sum / st.iterations.max(1) as f64,
        rays,
        st.items[ix],
        st.items[sh],
        rays as f64 / wall / 1e6,
        st.paths as f64 / wall / 1e6,
        non_finite,
        crate::engine::simd::isa_name()
    );
}
