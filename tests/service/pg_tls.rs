//! TLS to PostgreSQL (docs/cluster.md). Needs the server `tests/pg/tls.sh` starts: `ssl = on` with a
//! certificate for DNS name `localhost` signed by a CA the script made, and a pg_hba.conf that
//! accepts TCP clients over TLS only (`hostssl`). The script sets `ASHLAR_TEST_TLS_PORT` and
//! `ASHLAR_TEST_TLS_CERTS` (holding `ca.pem` and an unrelated `wrong-ca.pem`). Without them
//! every test prints a loud SKIPPED line and passes (a plain `cargo test`); `tests/pg/tls.sh`,
//! run by `.ci/run`, fails if they skip.
//!
//! - `verify-full` with the right CA: an API process and a worker process run a job end to end,
//!   and every connection they hold is encrypted (`pg_stat_ssl`);
//! - `require` and the default (`prefer`) connect encrypted without a CA; `verify-ca` accepts
//!   the certificate at 127.0.0.1 (issued for `localhost`), `verify-full` refuses it there;
//! - a wrong CA is refused with the host and the reason, also by `ashlar worker` at start-up;
//! - `PGSSLMODE`/`PGSSLROOTCERT` apply when the URL has no TLS parameters (libpq's variables);
//! - `sslmode=disable` is refused by the server (hostssl only), with a hint;
//! - `sslcrl`: a CRL revoking the server's certificate is refused naming the file, one that
//!   revokes nothing is accepted, a file without a CRL is refused;
//! - `prefer` retries in plain text, as libpq, when the certificate check fails or the server
//!   refuses the encrypted session, and says both reasons when the retry fails too; `require`
//!   never does;
//! - a database whose pg_hba line says `cert` admits a client presenting `sslcert`/`sslkey`
//!   (signed by the CA) and refuses one without.
use crate::service_support;

use ashlar::service::store::tls as pg_tls;
use serde_json::{json, Value};
use service_support::*;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;
use uuid::Uuid;

struct Env {
    port: String,
    certs: PathBuf,
}

fn env(test: &str) -> Option<Env> {
    match (
        std::env::var("ASHLAR_TEST_TLS_PORT"),
        std::env::var("ASHLAR_TEST_TLS_CERTS"),
    ) {
        (Ok(port), Ok(certs)) if !port.is_empty() && !certs.is_empty() => Some(Env {
            port,
            certs: PathBuf::from(certs),
        }),
        _ => {
            // Straight to the process's stderr, not through `eprintln!`, which the test harness
            // captures: a plain `cargo test` shows the skip beside the test's "ok".
            let _ = writeln!(
                std::io::stderr(),
                "SKIPPED {test}: ASHLAR_TEST_TLS_PORT/ASHLAR_TEST_TLS_CERTS are not set (run tests/pg/tls.sh)"
            );
            None
        }
    }
}

impl Env {
    fn url(&self, host: &str, db: &str, params: &str) -> String {
        format!("postgresql://ashlar@{host}:{}/{db}?{params}", self.port)
    }

    fn ca(&self, name: &str) -> String {
        self.certs.join(name).display().to_string()
    }
}

/// The connection, or the error's text (parse or connect) the assertions read.
fn connect(url: &str) -> Result<postgres::Client, String> {
    let target = pg_tls::parse(url).map_err(|e| e.to_string())?;
    target.connect().map_err(|e| e.to_string())
}

/// The error of a connection that must fail.
fn refused(url: &str, why: &str) -> String {
    match connect(url) {
        Ok(_) => panic!("{why}: {url} connected"),
        Err(e) => e,
    }
}

/// Whether this session is encrypted, as the server sees it.
fn encrypted(c: &mut postgres::Client) -> bool {
    c.query_one(
        "SELECT ssl FROM pg_stat_ssl WHERE pid = pg_backend_pid()",
        &[],
    )
    .expect("pg_stat_ssl")
    .get(0)
}

#[test]
fn verify_full_runs_a_job_end_to_end_encrypted() {
    let Some(env) = env("verify_full_runs_a_job_end_to_end_encrypted") else {
        return;
    };
    let ca = format!("sslmode=verify-full&sslrootcert={}", env.ca("ca.pem"));
    let mut admin = connect(&env.url("localhost", "postgres", &ca)).expect("verify-full connects");
    assert!(
        encrypted(&mut admin),
        "verify-full session is not encrypted"
    );
    let db = format!("ashlar_tls_{}", &Uuid::new_v4().simple().to_string()[..8]);
    admin
        .batch_execute(&format!("CREATE DATABASE {db}"))
        .expect("create database");
    let url = env.url("localhost", &db, &ca);

    let root = temp_dir("pg-tls");
    let shared = format!("file://{}", root.join("shared").display());
    let api = Server::start(
        &root.join("api"),
        &["--database", &url, "--workers", "0", "--artifacts", &shared],
    );
    let _worker = Worker::start(
        &url,
        &root.join("worker"),
        &["--workers", "1", "--artifacts", &shared],
    );
    let body = json!({"scene": column_scene(2.0), "motion": pulse(3.0)});
    let (status, text) =
        http(&api.addr, "POST", "/v1/jobs", Some(&body.to_string())).expect("POST");
    assert_eq!(status, 202, "{text}");
    let id = serde_json::from_str::<Value>(&text).expect("JSON")["id"]
        .as_str()
        .expect("id")
        .to_string();
    let mut last = Value::Null;
    wait_until(
        "the worker finishes the job",
        Duration::from_secs(120),
        || {
            let (_, t) = http(&api.addr, "GET", &format!("/v1/jobs/{id}"), None).expect("GET");
            last = serde_json::from_str(&t).unwrap_or(Value::Null);
            is_terminal(&last)
        },
    );
    assert_eq!(last["status"], "succeeded", "{last}");
    assert!(last["summary"].is_object(), "no summary: {last}");
    // The API ran nothing (0 worker threads): it serves what the worker recorded.
    let (status, csv) = http(
        &api.addr,
        "GET",
        &format!("/v1/jobs/{id}/histories?format=csv"),
        None,
    )
    .expect("GET histories");
    assert_eq!(status, 200, "{csv:.300}");
    assert!(csv.starts_with("time_s,column.x_m"), "{csv:.200}");

    // Every session the two processes hold on this database is encrypted, and there are some
    // (pool + LISTEN connections of both processes).
    let rows = admin
        .query(
            "SELECT s.ssl FROM pg_stat_ssl s JOIN pg_stat_activity a USING (pid) WHERE a.datname = $1",
            &[&db],
        )
        .expect("sessions");
    assert!(
        rows.len() >= 2,
        "expected the API's and the worker's sessions, found {}",
        rows.len()
    );
    assert!(
        rows.iter().all(|r| r.get::<_, bool>(0)),
        "a session on {db} is not encrypted"
    );
    drop(api);
    std::fs::remove_dir_all(root).ok();
}

#[test]
fn modes_behave_as_in_libpq() {
    let Some(env) = env("modes_behave_as_in_libpq") else {
        return;
    };
    let ca = env.ca("ca.pem");
    // require, prefer (the default): encrypted, certificate not checked.
    for params in ["sslmode=require", "", "sslmode=prefer"] {
        let mut c = connect(&env.url("127.0.0.1", "postgres", params))
            .unwrap_or_else(|e| panic!("{params:?}: {e}"));
        assert!(encrypted(&mut c), "{params:?} is not encrypted");
    }
    // verify-ca: the chain is checked, not the name (the certificate is for `localhost`).
    let mut c = connect(&env.url(
        "127.0.0.1",
        "postgres",
        &format!("sslmode=verify-ca&sslrootcert={ca}"),
    ))
    .expect("verify-ca at 127.0.0.1");
    assert!(encrypted(&mut c));
    // verify-full checks the name too.
    let e = refused(
        &env.url(
            "127.0.0.1",
            "postgres",
            &format!("sslmode=verify-full&sslrootcert={ca}"),
        ),
        "verify-full must refuse a certificate issued for another name",
    );
    eprintln!("verify-full at 127.0.0.1: {e}");
    assert!(
        e.contains("127.0.0.1") && e.contains("verify-full") && e.contains("not valid for name"),
        "{e}"
    );
}

#[test]
fn wrong_ca_is_refused_naming_host_and_reason() {
    let Some(env) = env("wrong_ca_is_refused_naming_host_and_reason") else {
        return;
    };
    let wrong = env.ca("wrong-ca.pem");
    for mode in ["verify-full", "verify-ca", "require"] {
        let url = env.url(
            "localhost",
            "postgres",
            &format!("sslmode={mode}&sslrootcert={wrong}"),
        );
        let e = refused(&url, "a wrong CA must be refused");
        eprintln!("{mode}, wrong CA: {e}");
        assert!(
            e.contains(&format!("localhost:{}", env.port))
                && e.contains("failed verification")
                && e.contains("UnknownIssuer")
                && e.contains(&wrong),
            "{mode}: {e}"
        );
    }
    // The same from the command line: the worker refuses to start and says why.
    let data = temp_dir("pg-tls-wrong");
    let url = env.url(
        "localhost",
        "postgres",
        &format!("sslmode=verify-full&sslrootcert={wrong}"),
    );
    let out = Command::new(env!("CARGO_BIN_EXE_ashlar"))
        .args(["worker", "--database", &url, "--data"])
        .arg(&data)
        .output()
        .expect("run ashlar worker");
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprintln!("ashlar worker, wrong CA: {}", stderr.trim());
    assert!(!out.status.success(), "worker started with a wrong CA");
    assert!(
        stderr.contains("localhost") && stderr.contains("UnknownIssuer"),
        "{stderr}"
    );
    std::fs::remove_dir_all(data).ok();
}

/// libpq's environment variables: `ashlar worker` given a URL without TLS parameters takes
/// them from `PGSSLMODE` and `PGSSLROOTCERT`. With the wrong CA there it refuses to start,
/// naming the CA file (without the environment it would connect in `prefer` mode and run);
/// with the right one it starts.
#[test]
fn tls_parameters_from_the_environment() {
    use std::io::{BufRead, Read};
    let Some(env) = env("tls_parameters_from_the_environment") else {
        return;
    };
    let url = env.url("localhost", "postgres", "application_name=ashlar-env-test");
    let data = temp_dir("pg-tls-env");
    let worker = |ca: &str| {
        Command::new(env!("CARGO_BIN_EXE_ashlar"))
            .args(["worker", "--database", &url, "--data"])
            .arg(&data)
            .env("PGSSLMODE", "verify-full")
            .env("PGSSLROOTCERT", ca)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("spawn ashlar worker")
    };
    let wrong = env.ca("wrong-ca.pem");
    let mut child = worker(&wrong);
    let mut status = None;
    wait_until(
        "the worker refuses the wrong CA from PGSSLROOTCERT",
        Duration::from_secs(60),
        || {
            status = child.try_wait().expect("try_wait");
            status.is_some()
        },
    );
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut stderr)
        .expect("read stderr");
    eprintln!(
        "ashlar worker, wrong CA from the environment: {}",
        stderr.trim()
    );
    assert!(status.is_some_and(|s| !s.success()), "{stderr}");
    assert!(
        stderr.contains("verify-full")
            && stderr.contains("UnknownIssuer")
            && stderr.contains(&wrong),
        "{stderr}"
    );
    let mut child = worker(&env.ca("ca.pem"));
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut line)
        .expect("read the ready line");
    let _ = child.kill();
    let _ = child.wait();
    assert!(line.starts_with("ashlar worker: running"), "{line:?}");
    std::fs::remove_dir_all(data).ok();
}

#[test]
fn plain_text_is_refused_by_a_hostssl_server() {
    let Some(env) = env("plain_text_is_refused_by_a_hostssl_server") else {
        return;
    };
    let e = refused(
        &env.url("127.0.0.1", "postgres", "sslmode=disable"),
        "hostssl only: a plain-text client must be refused",
    );
    eprintln!("sslmode=disable: {e}");
    assert!(
        e.contains("127.0.0.1")
            && e.contains("no encryption")
            && e.contains("drop sslmode=disable"),
        "{e}"
    );
}

#[test]
fn client_certificate_authentication() {
    let Some(env) = env("client_certificate_authentication") else {
        return;
    };
    let ca = env.ca("ca.pem");
    ensure_database(&env, "certdb");
    let base = format!("sslmode=verify-full&sslrootcert={ca}");
    let e = refused(
        &env.url("localhost", "certdb", &base),
        "certdb demands a client certificate",
    );
    eprintln!("certdb without a client certificate: {e}");
    assert!(e.contains("certificate"), "{e}");
    let with_cert = format!(
        "{base}&sslcert={}&sslkey={}",
        env.ca("client.crt"),
        env.ca("client.key")
    );
    let mut c = connect(&env.url("localhost", "certdb", &with_cert))
        .expect("a client certificate signed by the CA is accepted");
    assert!(encrypted(&mut c));
    let who: String = c
        .query_one("SELECT current_user::text", &[])
        .expect("current_user")
        .get(0);
    assert_eq!(who, "ashlar");
}

/// Create `db` once (several test runs may share a server).
fn ensure_database(env: &Env, db: &str) {
    let ca = env.ca("ca.pem");
    let mut admin = connect(&env.url(
        "localhost",
        "postgres",
        &format!("sslmode=verify-full&sslrootcert={ca}"),
    ))
    .expect("admin connection");
    let exists = admin
        .query_opt("SELECT 1 FROM pg_database WHERE datname = $1", &[&db])
        .expect("pg_database")
        .is_some();
    if !exists {
        admin
            .batch_execute(&format!("CREATE DATABASE {db}"))
            .unwrap_or_else(|e| panic!("create {db}: {e}"));
    }
}

#[test]
fn prefer_falls_back_to_plain_text_as_libpq() {
    let Some(env) = env("prefer_falls_back_to_plain_text_as_libpq") else {
        return;
    };
    // pg_hba.conf (tests/pg/tls.sh): `plaindb` takes TLS or plain text, `nossldb` plain text
    // only, every other database TLS only.
    ensure_database(&env, "plaindb");
    ensure_database(&env, "nossldb");
    let wrong = env.ca("wrong-ca.pem");

    // TLS works: `prefer` stays encrypted.
    let mut c = connect(&env.url("127.0.0.1", "plaindb", "sslmode=prefer")).expect("prefer");
    assert!(encrypted(&mut c), "prefer fell back although TLS works");

    // The certificate check fails (a root certificate that did not sign the server's):
    // `prefer` retries in plain text; `require` refuses.
    let mut c = connect(&env.url(
        "localhost",
        "plaindb",
        &format!("sslmode=prefer&sslrootcert={wrong}"),
    ))
    .expect("prefer retries in plain text after a failed certificate check");
    assert!(!encrypted(&mut c));
    let e = refused(
        &env.url(
            "localhost",
            "plaindb",
            &format!("sslmode=require&sslrootcert={wrong}"),
        ),
        "require must not fall back to plain text",
    );
    assert!(e.contains("UnknownIssuer"), "{e}");

    // The server refuses the encrypted session (`hostssl nossldb … reject`): `prefer`
    // retries in plain text; `require` refuses.
    let mut c = connect(&env.url("127.0.0.1", "nossldb", "sslmode=prefer"))
        .expect("prefer retries in plain text when the server refuses TLS");
    assert!(!encrypted(&mut c));
    let e = refused(
        &env.url("127.0.0.1", "nossldb", "sslmode=require"),
        "require must not fall back to plain text",
    );
    eprintln!("require, nossldb: {e}");
    assert!(e.contains("pg_hba.conf"), "{e}");

    // Both attempts fail (a TLS-only database, a wrong root certificate): both reasons.
    let e = refused(
        &env.url(
            "localhost",
            "postgres",
            &format!("sslmode=prefer&sslrootcert={wrong}"),
        ),
        "a TLS-only server refuses the plain-text retry",
    );
    eprintln!("prefer, wrong CA, hostssl only: {e}");
    assert!(
        e.contains("UnknownIssuer")
            && e.contains("plain-text retry of sslmode=prefer failed too")
            && e.contains("no encryption"),
        "{e}"
    );
}

#[test]
fn revoked_server_certificate_is_refused() {
    let Some(env) = env("revoked_server_certificate_is_refused") else {
        return;
    };
    let ca = env.ca("ca.pem");
    let with_crl = |crl: &str| {
        format!(
            "sslmode=verify-full&sslrootcert={ca}&sslcrl={}",
            env.ca(crl)
        )
    };
    let mut c = connect(&env.url("localhost", "postgres", &with_crl("empty.crl")))
        .expect("a CRL revoking nothing is accepted");
    assert!(encrypted(&mut c));
    let e = refused(
        &env.url("localhost", "postgres", &with_crl("revoked.crl")),
        "a revoked server certificate must be refused",
    );
    eprintln!("verify-full, revoked: {e}");
    assert!(
        e.contains("Revoked") && e.contains("revoked") && e.contains(&env.ca("revoked.crl")),
        "{e}"
    );
    // `require` with a root certificate checks the chain, revocation included (as libpq).
    let e = refused(
        &env.url(
            "localhost",
            "postgres",
            &format!(
                "sslmode=require&sslrootcert={ca}&sslcrl={}",
                env.ca("revoked.crl")
            ),
        ),
        "require with a CA and a CRL checks revocation",
    );
    assert!(e.contains("Revoked"), "{e}");
    // A file that holds no CRL (here: a certificate) is refused before connecting.
    let e = match pg_tls::parse(&env.url("localhost", "postgres", &with_crl("ca.pem"))) {
        Ok(_) => panic!("a certificate taken for a CRL"),
        Err(e) => e.to_string(),
    };
    assert!(
        e.contains("no PEM block -----BEGIN X509 CRL-----") && e.contains("sslcrl="),
        "{e}"
    );
}
