//! Analyses that drive the simulation: PGA searches, fragility, reduced models and their selection, batch sweeps.
//!
//! One test binary for these modules (one per former file): a binary per file cost
//! ~35 MB of disk and a link each. Run one with `cargo test --test analysis NAME::`.

#[path = "../common/mod.rs"]
mod common;
mod hand_back;
mod pga_cli;
mod pga_fragility;
mod pga_frequency_sweep;
mod pga_honesty;
mod pga_incline;
mod pga_range;
mod pga_scan;
mod pga_search;
mod reduced_fallback;
mod reduced_records;
mod reduced_rocking;
mod reduced_selection;
mod reduced_sliding;
mod run_end;
mod site_distribution;
mod site_observations;
mod sweep_cli;
mod templates_cli;
