//! Reading what users bring: ground-motion records (formats, closed forms, golden intensity measures, bad input, fuzzing) and scenes.
//!
//! One test binary for these modules (one per former file): a binary per file cost
//! ~35 MB of disk and a link each. Run one with `cargo test --test inputs NAME::`.

#[path = "../common/mod.rs"]
mod common;

mod motion_bad_input;
mod motion_cli;
mod motion_closed_forms;
mod motion_formats;
mod motion_fuzz;
mod motion_golden;
mod scene_dxf;
mod scene_fuzz;
mod scene_restitution;
