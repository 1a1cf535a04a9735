//! The grid of settings swept on each scene (stage 2): time step, penalty, g2, integrator,
//! block model, contact solver, model.
use super::*;

/// The settings swept for one scene: one-at-a-time sweeps around the defaults.
pub(super) fn settings(bench: &Bench, quick: bool) -> Vec<(String, Setting)> {
    let base = Setting::baseline();
    let mut out = Vec::new();
    let mut defaults = base.clone();
    defaults.defaults = true;
    out.push(("defaults".to_string(), defaults));
    let overturning = matches!(bench.metric, Metric::Overturning { .. });
    let wall = matches!(bench.metric, Metric::Finest { .. });
    let dts: Vec<f64> = if quick {
        vec![1e-2, 1e-3]
    } else if overturning {
        vec![1e-2, 3e-3, 1e-3, 3e-4, 1e-4]
    } else if wall {
        vec![1e-2, 3e-3, 1e-3, 3e-4]
    } else {
        vec![1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5]
    };
    for integ in ["dda", "trapezoidal"] {
        for &dt in &dts {
            out.push((
                "time_step".into(),
                Setting {
                    integrator: integ.into(),
                    time_step: dt,
                    ..base.clone()
                },
            ));
        }
    }
    let penalties: Vec<f64> = if quick {
        vec![1e9]
    } else {
        vec![1e7, 1e8, 1e9, 1e10, 1e11, 1e12]
    };
    for k in penalties {
        out.push((
            "penalty".into(),
            Setting {
                penalty_stiffness: Some(k),
                ..base.clone()
            },
        ));
    }
    if !quick {
        for g2 in [1e-2, 1e-4] {
            out.push((
                "g2".into(),
                Setting {
                    max_displacement_ratio: g2,
                    ..base.clone()
                },
            ));
        }
    }
    out.push((
        "block_model".into(),
        Setting {
            block_model: "rigid".into(),
            ..base.clone()
        },
    ));
    out.push((
        "contact_solver".into(),
        Setting {
            contact_solver: "dual".into(),
            ..base.clone()
        },
    ));
    if bench.reducible {
        let tols: Vec<f64> = if quick {
            vec![1e-10]
        } else {
            vec![1e-3, 1e-4, 1e-6, 1e-8, 1e-10]
        };
        for rtol in tols {
            out.push((
                "reduced".into(),
                Setting {
                    model: "reduced".into(),
                    reduced_rtol: Some(rtol),
                    ..base.clone()
                },
            ));
        }
    }
    out
}
