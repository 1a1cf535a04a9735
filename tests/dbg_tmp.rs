mod common;
use ashlar::motion::GroundMotion;
use common::*;
use serde_json::json;
#[test]
fn dbg() {
    let (mut v, d) = incline(45.0, 30.0, json!({ "time_step": 1e-3, "block_model": "rigid", "duration": 1.0 }));
    let v0 = 0.1;
    v["initial"] = json!([{ "block": "block", "velocity": [v0 * d[0], v0 * d[1]] }]);
    let scene = parse(&v);
    let mut s = sim(&scene, &GroundMotion::none());
    let (a, f) = (45f64.to_radians(), 30f64.to_radians());
    let acc = G * (a.sin() - a.cos() * f.tan());
    let mut k = 0;
    run(&mut s, 0.3, |s| {
        k += 1;
        if k % 20 == 0 || k < 5 {
            let u = displacement(s, 1);
            let num = u[0] * d[0] + u[1] * d[1];
            let exact = 0.5 * acc * s.time * s.time + v0 * s.time;
            let st: Vec<String> = s.contacts.contacts.iter().map(|c| format!("{:?} N={:.0} g={:.2e}", c.state, c.normal_force, c.gap)).collect();
            eprintln!("t={:.3} num={num:.5} exact={exact:.5} v={:?} {:?}", s.time, s.states[0].vel.as_slice()[..3].to_vec(), st);
        }
    });
}
