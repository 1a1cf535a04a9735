//! One module per fixed bug, each opening with what broke.
//!
//! One test binary for these modules (one per former file): a binary per file cost
//! ~35 MB of disk and a link each. Run one with `cargo test --test regression NAME::`.

#[path = "../common/mod.rs"]
mod common;
mod regression_auto_controls;
mod regression_contact_chatter;
mod regression_dual_floor;
mod regression_dual_phantom_corner;
mod regression_dual_tolerance_small_dt;
mod regression_dual_trapezoidal;
mod regression_floor_penetration;
mod regression_handover_verdict;
mod regression_impact_cluster_size;
mod regression_impact_energy_stack;
mod regression_pga_range;
mod regression_phantom_penetration;
mod regression_reported_controls;
mod regression_sigterm_after_listening;
mod regression_simultaneous_landings;
mod regression_soft_penalty;
mod regression_stale_progress_event;
mod regression_step_limit_diagnostic;
mod regression_trapezoidal_impact;
mod regression_trapezoidal_release;
