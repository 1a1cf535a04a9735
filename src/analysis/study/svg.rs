//! The study's log–log plots, drawn with [`crate::plot`]'s pieces.
use super::{convergence_order, dt_series, Point};
use crate::plot::{self, attr, tenth, Anchor};

const W: f64 = 640.0;
const H: f64 = 420.0;
const L: f64 = 70.0;
const R: f64 = 170.0;
const T: f64 = 40.0;
const B: f64 = 50.0;

struct Axes {
    x: (f64, f64),
    y: (f64, f64),
}

impl Axes {
    fn fit(xs: &[f64], ys: &[f64]) -> Self {
        let range = |v: &[f64]| {
            let lo = v
                .iter()
                .cloned()
                .filter(|x| *x > 0.0)
                .fold(f64::INFINITY, f64::min);
            let hi = v.iter().cloned().filter(|x| *x > 0.0).fold(0.0, f64::max);
            if !lo.is_finite() || hi <= 0.0 {
                (0.0, 1.0)
            } else {
                (
                    lo.log10().floor(),
                    hi.log10().ceil().max(lo.log10().floor() + 1.0),
                )
            }
        };
        Self {
            x: range(xs),
            y: range(ys),
        }
    }
    fn px(&self, x: f64) -> f64 {
        L + (x.max(1e-300).log10() - self.x.0) / (self.x.1 - self.x.0) * (W - L - R)
    }
    fn py(&self, y: f64) -> f64 {
        H - B - (y.max(1e-300).log10() - self.y.0) / (self.y.1 - self.y.0) * (H - T - B)
    }
    fn draw(&self, title: &str, xl: &str, yl: &str) -> String {
        let mut s = plot::document(W, H, 11.0, false);
        s += &plot::text(
            (W - R + L) / 2.0,
            20.0,
            Anchor::Middle,
            &attr("font-size", 14),
            title,
        );
        s += &plot::frame(L, T, W - L - R, H - T - B);
        for d in (self.x.0 as i32)..=(self.x.1 as i32) {
            let x = self.px(10f64.powi(d));
            s += &plot::grid_line(x, T, x, H - B);
            s += &plot::text(
                tenth(x),
                H - B + 15.0,
                Anchor::Middle,
                "",
                &format!("1e{d}"),
            );
        }
        for d in (self.y.0 as i32)..=(self.y.1 as i32) {
            let y = self.py(10f64.powi(d));
            s += &plot::grid_line(L, y, W - R, y);
            s += &plot::text(L - 5.0, tenth(y + 4.0), Anchor::End, "", &format!("1e{d}"));
        }
        s += &plot::text((W - R + L) / 2.0, H - 12.0, Anchor::Middle, "", xl);
        s += &plot::axis_title(15.0, (H - B + T) / 2.0, -90.0, yl);
        // The 1 % line.
        if self.y.0 <= -2.0 && self.y.1 >= -2.0 {
            let y = self.py(0.01);
            s += &plot::beside(
                &plot::line(
                    L,
                    tenth(y),
                    W - R,
                    tenth(y),
                    "#c00",
                    &attr("stroke-dasharray", "4 3"),
                ),
                &plot::text(
                    W - R - 25.0,
                    tenth(y - 3.0),
                    Anchor::Start,
                    &attr("fill", "#c00"),
                    "1 %",
                ),
            );
        }
        s
    }
}

const COLORS: [(&str, &str); 8] = [
    ("time_step", "#1f77b4"),
    ("penalty", "#ff7f0e"),
    ("g2", "#2ca02c"),
    ("block_model", "#9467bd"),
    ("contact_solver", "#8c564b"),
    ("reduced", "#d62728"),
    ("defaults", "#000000"),
    ("other", "#7f7f7f"),
];

fn color(sweep: &str) -> &'static str {
    COLORS
        .iter()
        .find(|c| c.0 == sweep)
        .map(|c| c.1)
        .unwrap_or("#7f7f7f")
}

/// One row of a legend right of the plot, its baseline 4 px below `y`: `marker`, then `label`.
fn legend_row(marker: &str, y: f64, label: &str) -> String {
    plot::beside(
        marker,
        &plot::text(W - R + 25.0, y + 4.0, Anchor::Start, "", label),
    )
}

pub fn pareto(scene: &str, pts: &[&Point]) -> String {
    let ok: Vec<&Point> = pts
        .iter()
        .copied()
        .filter(|p| p.error.is_some_and(|e| e.is_finite()))
        .collect();
    let xs: Vec<f64> = ok.iter().map(|p| p.wall_time_s.max(1e-6)).collect();
    let ys: Vec<f64> = ok
        .iter()
        .map(|p| p.error.unwrap_or(1.0).max(1e-12))
        .collect();
    let ax = Axes::fit(&xs, &ys);
    let mut s = ax.draw(
        &format!("{scene}: error against wall time"),
        "wall time (s)",
        "relative error",
    );
    for p in &ok {
        let (x, y) = (
            ax.px(p.wall_time_s.max(1e-6)),
            ax.py(p.error.unwrap_or(1.0).max(1e-12)),
        );
        let (fill, faded, tooltip) = (
            color(&p.sweep),
            attr("opacity", 0.8),
            Some(p.label.as_str()),
        );
        s += &if p.setting.integrator == "trapezoidal" && p.sweep == "time_step" {
            plot::rect(
                tenth(x - 3.5),
                tenth(y - 3.5),
                7.0,
                7.0,
                fill,
                &faded,
                tooltip,
            )
        } else {
            plot::circle(tenth(x), tenth(y), 4.0, fill, &faded, tooltip)
        };
    }
    let front = super::pareto(&ok);
    let line: Vec<(f64, f64)> = front
        .iter()
        .map(|&i| {
            (
                ax.px(ok[i].wall_time_s.max(1e-6)),
                ax.py(ok[i].error.unwrap_or(1.0).max(1e-12)),
            )
        })
        .collect();
    s += &plot::polyline(&line, "black", 1.2, "");
    let mut y = T + 10.0;
    for (name, c) in COLORS.iter().take(7) {
        s += &legend_row(&plot::circle(W - R + 15.0, y, 4.0, c, "", None), y, name);
        y += 16.0;
    }
    let square = plot::rect(W - R + 11.5, y - 3.5, 7.0, 7.0, "#1f77b4", "", None);
    s += &legend_row(&square, y, "trapezoidal");
    y += 16.0;
    let front = plot::line(W - R + 8.0, y, W - R + 20.0, y, "black", "");
    s += &legend_row(&front, y, "Pareto front");
    s + plot::END
}

pub fn convergence(scene: &str, pts: &[&Point]) -> String {
    let series = [("dda", "#1f77b4"), ("trapezoidal", "#d62728")];
    let data: Vec<Vec<(f64, f64)>> = series.iter().map(|(i, _)| dt_series(pts, i)).collect();
    let xs: Vec<f64> = data.iter().flatten().map(|p| p.0).collect();
    let ys: Vec<f64> = data.iter().flatten().map(|p| p.1).collect();
    let ax = Axes::fit(&xs, &ys);
    let mut s = ax.draw(
        &format!("{scene}: error against time step"),
        "maximum time step Δt (s)",
        "relative error",
    );
    let mut y = T + 10.0;
    for ((name, c), d) in series.iter().zip(&data) {
        let line: Vec<(f64, f64)> = d.iter().map(|p| (ax.px(p.0), ax.py(p.1))).collect();
        s += &plot::polyline(&line, c, 1.5, "");
        for p in d {
            s += &plot::circle(tenth(ax.px(p.0)), tenth(ax.py(p.1)), 3.5, c, "", None);
        }
        let order = convergence_order(d, 1e-9)
            .map(|o| format!("order {o:.2}"))
            .unwrap_or_else(|| "order n/a".into());
        let marker = plot::line(W - R + 8.0, y, W - R + 20.0, y, c, &attr("stroke-width", 2));
        s += &legend_row(&marker, y, &format!("{name}: {order}"));
        y += 16.0;
    }
    s + plot::END
}
