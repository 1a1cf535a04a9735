//! The PostgreSQL schema: a version-1 database migrated in place, a newer one refused; bad
//! `--database` URLs named (see `mod.rs`).
use super::*;
use ashlar::service::store::postgres::MIGRATIONS;

#[test]
fn migrates_a_version_1_database() {
    let Some(base) = base_url("migrates_a_version_1_database") else {
        return;
    };
    let url = fresh_db(&base, "migrate");
    // A database as the first PostgreSQL-backed ashlar left it: schema version 1, a queued job,
    // a job running under a server that no longer exists, and a finished one.
    // Migration 1 is that schema (a released migration never changes), then the fixture's rows.
    let mut v1 = sql(&url);
    v1.batch_execute(MIGRATIONS[0].1).expect("schema version 1");
    v1.batch_execute(include_str!("../../fixtures/pg_schema_v1.sql"))
        .expect("load the v1 fixture");
    let s = PgStore::open(&url, LeaseParams::default()).expect("open upgrades");
    assert_eq!(s.schema_version().expect("version"), SCHEMA_VERSION);
    let mut c = sql(&url);
    let versions: Vec<i32> = c
        .query(
            "SELECT version FROM ashlar_schema_version ORDER BY version",
            &[],
        )
        .expect("versions")
        .iter()
        .map(|r| r.get(0))
        .collect();
    assert_eq!(versions, (1..=SCHEMA_VERSION).collect::<Vec<_>>());
    let done = Uuid::parse_str("00000000-0000-4000-8000-000000000003").expect("uuid");
    let r = s.get(done).expect("get").expect("kept");
    assert_eq!(r.status, JobStatus::Succeeded);
    assert_eq!(r.result.as_deref(), Some(r#"{"completed":true,"pga":2.5}"#));
    // The v1 running job has no lease: the reaper requeues it, and it keeps its place.
    assert_eq!(s.recover(3).expect("reap"), (1, 0));
    let first = s.claim().expect("claim").expect("job");
    assert_eq!(first.id.to_string(), "00000000-0000-4000-8000-000000000001");
    let second = s.claim().expect("claim").expect("job");
    assert_eq!(
        second.id.to_string(),
        "00000000-0000-4000-8000-000000000002"
    );
    assert_eq!(second.attempts, 2, "the old attempt still counts");
    // Opening again is a no-op; a newer schema is refused with a clear message.
    drop(s);
    PgStore::open(&url, LeaseParams::default()).expect("reopen");
    c.execute(
        "INSERT INTO ashlar_schema_version (version) VALUES (99)",
        &[],
    )
    .expect("bump");
    let e = PgStore::open(&url, LeaseParams::default())
        .err()
        .expect("refused");
    assert!(
        matches!(&e, StoreError::SchemaNewer { found: 99, .. })
            && e.to_string().contains("upgrade ashlar"),
        "{e}"
    );
}

#[test]
fn bad_database_urls_are_named() {
    // No server needed.
    let e = PgStore::open("mysql://x", LeaseParams::default())
        .err()
        .expect("refused");
    assert!(
        matches!(&e, StoreError::Config(_)) && e.to_string().contains("--database"),
        "{e}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_ashlar"))
        .args(["worker", "--database", "sqlite:/tmp/x.sqlite"])
        .output()
        .expect("run");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("PostgreSQL"), "{err}");
    let out = Command::new(env!("CARGO_BIN_EXE_ashlar"))
        .args(["worker", "--database", "postgres://nobody@127.0.0.1:1/none"])
        .output()
        .expect("run");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("connecting to PostgreSQL"), "{err}");
}
