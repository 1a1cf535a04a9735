//! The HTTP service, its durability, the PostgreSQL cluster mode and TLS.
//!
//! One test binary for these modules (one per former file): a binary per file cost
//! ~35 MB of disk and a link each. Run one with `cargo test --test service NAME::`.

#[path = "../common/mod.rs"]
mod common;
mod pg_cluster;
mod pg_tls;
mod service_access;
mod service_criteria;
mod service_durability;
mod service_isolation;
mod service_openapi;
mod service_pga;
mod service_routes;
mod service_scene_import;
mod service_site;
#[path = "../service_support/mod.rs"]
mod service_support;
mod service_templates;
mod service_web;
mod store_contract;
