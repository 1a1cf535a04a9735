//! Load test of `ashlar serve` (a measurement, not a test): 500 job submissions from 50
//! concurrent clients over loopback while a prober times `GET /healthz` every 10 ms. Reports the
//! submission throughput, checks that every acknowledged job is in the store (none lost), and
//! gives the /healthz latency percentiles over the samples taken while all workers were busy.
//!
//! ```text
//! cargo run --release --example load_test                 # in-process server, real engine
//! cargo run --release --example load_test -- --fake       # fake runner (no physics)
//! cargo run --release --example load_test -- --addr 127.0.0.1:8080   # an already running server
//! options: --jobs N (500) --clients N (50) --workers N (cores) --wait (until all jobs finish)
//! ```
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

struct Opts {
    addr: Option<String>,
    jobs: usize,
    clients: usize,
    workers: Option<usize>,
    fake: bool,
    wait: bool,
}

fn parse_opts() -> Result<Opts, String> {
    let mut o = Opts {
        addr: None,
        jobs: 500,
        clients: 50,
        workers: None,
        fake: false,
        wait: false,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut num = |name: &str| -> Result<usize, String> {
            args.next()
                .and_then(|v| v.parse().ok())
                .ok_or(format!("{name} needs a positive integer"))
        };
        match a.as_str() {
            "--addr" => o.addr = Some(args.next().ok_or("--addr needs HOST:PORT")?),
            "--jobs" => o.jobs = num("--jobs")?,
            "--clients" => o.clients = num("--clients")?.max(1),
            "--workers" => o.workers = Some(num("--workers")?.max(1)),
            "--fake" => o.fake = true,
            "--wait" => o.wait = true,
            other => return Err(format!("unknown option {other:?}")),
        }
    }
    Ok(o)
}

// The service tests' raw HTTP/1.1 client (std only), one copy for both.
#[path = "../tests/service_support/http_client.rs"]
mod http_client;
use http_client::http;

fn job_body(k: usize) -> String {
    // A column on a plinth under a pulse, 20 s simulated: about 0.1 s of CPU with the engine.
    serde_json::json!({
        "scene": ashlar::presets::plinth_column_json(20.0),
        "motion": ashlar::presets::half_sine_json(2.0 + 0.01 * (k % 100) as f64, 0.4),
    })
    .to_string()
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((p / 100.0) * (sorted.len() - 1) as f64).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

fn main() -> Result<(), String> {
    let o = parse_opts()?;
    // In-process server unless --addr: the same service `ashlar serve` runs, on a loopback port.
    let mut local = None;
    let addr = match &o.addr {
        Some(a) => a.clone(),
        None => {
            let data = std::env::temp_dir().join(format!("ashlar-load-{}", uuid::Uuid::new_v4()));
            let mut cfg = ashlar::service::ServiceConfig::new(&data);
            if let Some(w) = o.workers {
                cfg.workers.workers = w;
            }
            let runner = if o.fake {
                ashlar::service::fake::fake_runner(Duration::from_millis(500))
            } else {
                ashlar::service::analysis_runner()
            };
            let svc = ashlar::service::Service::start(cfg, runner).map_err(|e| e.to_string())?;
            let state = svc.state();
            let rt = tokio::runtime::Builder::new_multi_thread()
                .enable_all()
                .build()
                .map_err(|e| e.to_string())?;
            let listener = rt
                .block_on(tokio::net::TcpListener::bind("127.0.0.1:0"))
                .map_err(|e| e.to_string())?;
            let a = listener
                .local_addr()
                .map_err(|e| e.to_string())?
                .to_string();
            rt.spawn(async move {
                let _ = axum::serve(listener, ashlar::service::app(state)).await;
            });
            local = Some((svc, rt, data));
            a
        }
    };
    println!(
        "server: http://{addr} ({})",
        if o.addr.is_some() {
            "external"
        } else if o.fake {
            "in-process, fake runner"
        } else {
            "in-process, engine"
        }
    );

    // Prober: /healthz every 10 ms; keeps (latency ms, workers busy) pairs.
    let stop = Arc::new(AtomicBool::new(false));
    let samples: Arc<Mutex<Vec<(f64, bool)>>> = Arc::default();
    let prober = {
        let (stop, samples, addr) = (stop.clone(), samples.clone(), addr.clone());
        std::thread::spawn(move || {
            while !stop.load(Ordering::SeqCst) {
                let t = Instant::now();
                let r = http(&addr, "GET", "/healthz", None);
                let ms = t.elapsed().as_secs_f64() * 1e3;
                if let Ok((200, body)) = r {
                    let v: serde_json::Value = serde_json::from_str(&body).unwrap_or_default();
                    let busy = v["running"].as_u64().unwrap_or(0)
                        >= v["workers"].as_u64().unwrap_or(u64::MAX);
                    if let Ok(mut s) = samples.lock() {
                        s.push((ms, busy));
                    }
                } else if let Ok(mut s) = samples.lock() {
                    s.push((f64::INFINITY, true)); // a failed probe counts as infinitely slow
                }
                std::thread::sleep(Duration::from_millis(10));
            }
        })
    };

    // Clients: each submits its share as fast as it can.
    let next = Arc::new(AtomicUsize::new(0));
    let ids: Arc<Mutex<Vec<String>>> = Arc::default();
    let errors: Arc<Mutex<Vec<String>>> = Arc::default();
    let submit_lat: Arc<Mutex<Vec<f64>>> = Arc::default();
    let t0 = Instant::now();
    let clients: Vec<_> = (0..o.clients)
        .map(|_| {
            let (next, ids, errors, lat, addr, jobs) = (
                next.clone(),
                ids.clone(),
                errors.clone(),
                submit_lat.clone(),
                addr.clone(),
                o.jobs,
            );
            std::thread::spawn(move || loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                if k >= jobs {
                    break;
                }
                let t = Instant::now();
                match http(&addr, "POST", "/v1/jobs", Some(&job_body(k))) {
                    Ok((202, body)) => {
                        let v: serde_json::Value = serde_json::from_str(&body).unwrap_or_default();
                        if let (Some(id), Ok(mut ids)) = (v["id"].as_str(), ids.lock()) {
                            ids.push(id.to_string());
                        }
                    }
                    Ok((s, body)) => errors
                        .lock()
                        .map(|mut e| e.push(format!("{s}: {body}")))
                        .unwrap_or(()),
                    Err(e) => errors
                        .lock()
                        .map(|mut v| v.push(e.to_string()))
                        .unwrap_or(()),
                }
                if let Ok(mut l) = lat.lock() {
                    l.push(t.elapsed().as_secs_f64() * 1e3);
                }
            })
        })
        .collect();
    for c in clients {
        c.join().map_err(|_| "a client thread panicked")?;
    }
    let submit_s = t0.elapsed().as_secs_f64();
    // Keep probing a little while the workers chew through the queue.
    std::thread::sleep(Duration::from_secs(5));

    // None lost: every acknowledged id is known to the server, in a valid state.
    let ids = ids.lock().map(|v| v.clone()).unwrap_or_default();
    let mut lost = Vec::new();
    let mut by_status = std::collections::BTreeMap::<String, usize>::new();
    for id in &ids {
        match http(&addr, "GET", &format!("/v1/jobs/{id}"), None) {
            Ok((200, body)) => {
                let v: serde_json::Value = serde_json::from_str(&body).unwrap_or_default();
                *by_status
                    .entry(v["status"].as_str().unwrap_or("?").to_string())
                    .or_default() += 1;
            }
            _ => lost.push(id.clone()),
        }
    }
    if o.wait {
        println!("waiting for all jobs to finish…");
        loop {
            let unfinished = ids
                .iter()
                .filter(|id| {
                    http(&addr, "GET", &format!("/v1/jobs/{id}"), None)
                        .map(|(_, b)| {
                            b.contains("\"status\":\"queued\"")
                                || b.contains("\"status\":\"running\"")
                        })
                        .unwrap_or(true)
                })
                .count();
            if unfinished == 0 {
                break;
            }
            std::thread::sleep(Duration::from_secs(2));
        }
    }
    stop.store(true, Ordering::SeqCst);
    prober.join().map_err(|_| "the prober panicked")?;

    let errors = errors.lock().map(|v| v.clone()).unwrap_or_default();
    let mut lat = submit_lat.lock().map(|v| v.clone()).unwrap_or_default();
    lat.sort_by(f64::total_cmp);
    let samples = samples.lock().map(|v| v.clone()).unwrap_or_default();
    let mut busy: Vec<f64> = samples
        .iter()
        .filter(|(_, b)| *b)
        .map(|(ms, _)| *ms)
        .collect();
    busy.sort_by(f64::total_cmp);
    println!(
        "submissions: {} sent by {} clients in {submit_s:.2} s ({:.0}/s)",
        o.jobs,
        o.clients,
        o.jobs as f64 / submit_s
    );
    println!(
        "  accepted 202: {}, refused/failed: {}",
        ids.len(),
        errors.len()
    );
    println!(
        "  POST latency ms: p50 {:.1}, p99 {:.1}, max {:.1}",
        percentile(&lat, 50.0),
        percentile(&lat, 99.0),
        lat.last().copied().unwrap_or(f64::NAN)
    );
    println!(
        "  lost (acknowledged but unknown to the server): {}",
        lost.len()
    );
    println!("  status after the run: {by_status:?}");
    println!(
        "healthz while all workers busy: {} samples, p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms",
        busy.len(),
        percentile(&busy, 50.0),
        percentile(&busy, 99.0),
        busy.last().copied().unwrap_or(f64::NAN)
    );
    for e in errors.iter().take(5) {
        println!("  error: {e}");
    }
    if let Some((svc, rt, data)) = local {
        svc.shutdown(Duration::ZERO);
        rt.shutdown_timeout(Duration::from_secs(1));
        std::fs::remove_dir_all(data).ok();
    }
    let p99 = percentile(&busy, 99.0);
    if !lost.is_empty() || ids.len() != o.jobs || busy.is_empty() || p99.is_nan() || p99 >= 50.0 {
        return Err(format!(
            "FAILED: {} lost, {} of {} accepted, healthz p99 {p99:.2} ms over {} busy samples (target < 50 ms)",
            lost.len(),
            ids.len(),
            o.jobs,
            busy.len()
        ));
    }
    println!("OK: none lost, healthz p99 {p99:.2} ms < 50 ms");
    Ok(())
}
