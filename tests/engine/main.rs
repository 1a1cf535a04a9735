//! The engine against its references: the published benchmarks (incline, Newmark sliding, foundation, rocking, failure modes, single contacts), the dual solver, invariants, extremes and the solver shortcuts.
//!
//! One test binary for these modules (one per former file): a binary per file cost
//! ~35 MB of disk and a link each. Run one with `cargo test --test engine NAME::`.

mod block_model_auto;
mod collapse_floor;
#[path = "../common/mod.rs"]
mod common;
mod cycle_rule;
mod damping;
mod dual_mprgp;
mod dual_seed;
mod dual_stall;
mod dual_stiff_limit;
mod dxf_at_rest;
mod extremes;
mod failure_modes;
mod foundation;
mod incline;
mod invariants;
mod light_state_rocking;
mod micro_rocking;
mod multiblock_references;
mod records_housner;
mod restitution;
mod rocking;
mod rocking_impacts;
mod shaken_wall_settle;
mod single_contact;
mod sliding_newmark;
mod solver_reuse;
mod stacked_column;
mod start_check;
mod stone_settle;
mod templates;
