//! The Pareto front of error against wall time and the observed convergence order (stage 4).
use super::*;

/// Points on the Pareto front (no other point is both faster and more accurate), by wall time.
pub fn pareto(points: &[&Point]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].error.is_some_and(|e| e.is_finite()))
        .collect();
    idx.sort_by(|&a, &b| points[a].wall_time_s.total_cmp(&points[b].wall_time_s));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        let e = points[i].error.unwrap_or(f64::INFINITY);
        if e < best {
            best = e;
            front.push(i);
        }
    }
    front
}

/// Observed order of convergence: least-squares slope of log(error) against log(Δt) over the
/// points with error above `floor` (below it round-off or the reference's own error rules).
pub fn convergence_order(points: &[(f64, f64)], floor: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.1 > floor && p.1.is_finite() && p.0 > 0.0)
        .map(|p| (p.0.ln(), p.1.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then_some(sxy / sxx)
}

/// Error against time step of one integrator on one scene: (Δt, error) sorted by Δt.
pub fn dt_series(points: &[&Point], integrator: &str) -> Vec<(f64, f64)> {
    let mut s: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.sweep == "time_step" && p.setting.integrator == integrator)
        .filter_map(|p| p.error.map(|e| (p.setting.time_step, e.max(1e-16))))
        .collect();
    s.sort_by(|a, b| a.0.total_cmp(&b.0));
    s
}
