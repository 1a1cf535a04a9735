//! Recorded outputs: histories, MCAP, golden digests.
//!
//! One test binary for these modules (one per former file): a binary per file cost
//! ~35 MB of disk and a link each. Run one with `cargo test --test record NAME::`.

mod record_golden_run;
mod record_histories;
mod record_mcap;
