//! Analysis: drives the simulation for a user question (a run, failure modes, PGA searches).
//! Sits on top of `simulation`, `motion` and `record`; the service and CLI call in here.
pub mod criteria;
pub mod fragility;
pub mod observations;
pub mod pga;
pub mod reduced;
pub mod reference;
pub mod run;
pub mod run_end;
pub mod run_fallback;
pub mod run_summary;
pub mod study;
pub mod study_records;
