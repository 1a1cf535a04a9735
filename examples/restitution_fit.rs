//! The fitted restitution of the DDA column's rocking impacts (docs/accuracy-vs-speed.md,
//! "Restitution at the rocking column's impacts"; issue #20 point 6) with an impact knob:
//! `analysis::study::fitted_restitution` (the study's 2 s pulse run and its scan of e) for the
//! dda integrator, both block models.
//! Run: `cargo run --release --example restitution_fit -- [new|hand|hslow:F]` (`hand`:
//! `ImpactParams::hand_over_weight` with `slow_factor` 0; `hslow:F`: the hand-over with its own
//! threshold, `hand_over_below` = F).
use ashlar::analysis::study::fitted_restitution;
use ashlar::simulation::SimParams;

fn main() {
    let variant = std::env::args().nth(1).unwrap_or_else(|| "new".into());
    let mut p = SimParams::default();
    if variant == "hand" {
        p.impact.hand_over_weight = true;
        p.impact.hand_over_below = None;
        p.impact.slow_factor = 0.0;
    } else if let Some(f) = variant.strip_prefix("hslow:") {
        p.impact.hand_over_weight = true;
        p.impact.hand_over_below = Some(f.parse().expect("threshold"));
    } else if variant != "new" {
        panic!("unknown variant {variant}");
    }
    for block_model in ["rigid", "deformable"] {
        let fit = fitted_restitution("dda", block_model, Some(p)).expect("fit");
        println!(
            "{variant} | {} | e = {:.4} | RMS misfit {:.2e} rad",
            fit.source, fit.coefficient, fit.rms_misfit
        );
    }
}
