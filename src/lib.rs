//! ashlar: Discontinuous Deformation Analysis of historical structures under earthquakes.
//!
//! Data flows top to bottom; a module never imports one further down:
//! `scene → geometry → contact → assembly → solve → integrate ⇒ simulation`,
//! `motion` feeds assembly, `record` and `analysis` sit on top of `simulation`,
//! `service` drives `analysis`, and `cli` (behind `main.rs`) is thin.
pub mod analysis;
pub mod assembly;
pub mod cli;
pub mod contact;
pub mod geometry;
pub mod integrate;
pub mod motion;
pub mod plot;
pub mod presets;
pub mod quantity;
pub mod record;
pub mod scene;
pub mod service;
pub mod simulation;
pub mod solve;
