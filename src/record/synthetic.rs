//! Synthetic runs with closed-form motion, for testing and measuring the recording writers
//! without the engine: a rigid square rocking on a fixed base with growing amplitude (until it
//! counts as toppled) and a block sliding beside it. Sits in `record`; nothing in the physics
//! core uses it.
//!
//! Everything is computed with IEEE-754 arithmetic only (its own sine and cosine), so the frames,
//! and hence the golden digest of their recording, are bit-identical on every platform.
use super::{BlockFrame, BlockMotionState, Frame, FrameBlockKind, GroundFrame, RecordHeader};
use std::collections::BTreeMap;

/// |rotation| beyond which a block counts as toppled (docs/format.md: 30°), rad.
pub const TOPPLE_ROTATION: f64 = std::f64::consts::FRAC_PI_6;

/// A rocking square (side `side`, m) on a fixed base, with a sliding block beside it, repeated
/// `copies` times along x (2 m apart) to make bigger scenes.
///
/// Column rotation θ(t) = θmax · (t / T) · sin(2π f t), CCW positive, about the bottom-left
/// corner when θ ≥ 0 and the bottom-right corner when θ < 0 (so it never sinks into the base).
/// Slider x(t) = −d · (1 − cos(π t / T)) / 2. Ground displacement g · sin(2π f t), horizontal.
#[derive(Debug, Clone, PartialEq)]
pub struct RockingSquare {
    /// T, s.
    pub duration: f64,
    /// s between frames.
    pub output_interval: f64,
    /// m.
    pub side: f64,
    /// θmax, rad: the envelope reached at t = T.
    pub max_rotation: f64,
    /// f, Hz.
    pub frequency: f64,
    /// d, m.
    pub slide: f64,
    /// g, m.
    pub ground_amplitude: f64,
    pub copies: usize,
}

impl Default for RockingSquare {
    fn default() -> Self {
        RockingSquare {
            duration: 3.0,
            output_interval: 0.01,
            side: 0.4,
            max_rotation: 0.6,
            frequency: 1.0,
            slide: 0.05,
            ground_amplitude: 0.02,
            copies: 1,
        }
    }
}

const SPACING: f64 = 2.0;

impl RockingSquare {
    /// Frames at t = k · output_interval, k = 0..=round(T / interval).
    pub fn frame_count(&self) -> u64 {
        (self.duration / self.output_interval).round() as u64 + 1
    }

    fn suffix(copy: usize) -> String {
        if copy == 0 {
            String::new()
        } else {
            format!("_{}", copy + 1)
        }
    }

    pub fn header(&self) -> RecordHeader {
        let mut block_ids = vec!["base".to_string()];
        let mut block_kinds = vec![FrameBlockKind::Fixed];
        for c in 0..self.copies {
            block_ids.push(format!("column{}", Self::suffix(c)));
            block_ids.push(format!("slider{}", Self::suffix(c)));
            block_kinds.extend([FrameBlockKind::Free, FrameBlockKind::Free]);
        }
        let history_blocks = (1..block_ids.len()).collect();
        // The keys `analysis::run` writes; fixed values (no crate version) so that the golden
        // digest does not move with a release.
        let metadata = BTreeMap::from([
            ("scene".to_string(), format!("{self:?}")),
            (
                "motion_provenance".to_string(),
                "synthetic: closed-form rocking and sliding".to_string(),
            ),
            ("motion_scale".to_string(), "1".to_string()),
            ("solver".to_string(), "none (closed form)".to_string()),
            ("code_version".to_string(), "synthetic".to_string()),
        ]);
        RecordHeader {
            block_ids,
            block_kinds,
            history_blocks,
            metadata,
        }
    }

    /// The frame at t = k · output_interval.
    pub fn frame(&self, k: u64) -> Frame {
        let t = k as f64 * self.output_interval;
        let w = 2.0 * PI * self.frequency;
        let (s, c) = sin_cos(w * t);
        let ground = GroundFrame {
            acceleration: [-self.ground_amplitude * w * w * s, 0.0],
            velocity: [self.ground_amplitude * w * c, 0.0],
            displacement: [self.ground_amplitude * s, 0.0],
        };
        let half_base = SPACING * self.copies as f64 / 2.0 + 0.5;
        let mut blocks = vec![BlockFrame {
            x: 0.0,
            y: 0.0,
            rotation: 0.0,
            vx: 0.0,
            vy: 0.0,
            angular_velocity: 0.0,
            state: BlockMotionState::AtRest,
            outline: vec![
                [-half_base, -0.5],
                [half_base, -0.5],
                [half_base, 0.0],
                [-half_base, 0.0],
            ],
        }];
        for copy in 0..self.copies {
            let x0 = SPACING * copy as f64 - SPACING * (self.copies as f64 - 1.0) / 2.0;
            blocks.push(self.column(t, x0));
            blocks.push(self.slider(t, x0 - 0.75));
        }
        Frame {
            time: t,
            blocks,
            ground,
        }
    }

    pub fn frames(&self) -> impl Iterator<Item = Frame> + '_ {
        (0..self.frame_count()).map(move |k| self.frame(k))
    }

    fn column(&self, t: f64, x0: f64) -> BlockFrame {
        let b = self.side;
        let w = 2.0 * PI * self.frequency;
        let (s, c) = sin_cos(w * t);
        let env = self.max_rotation / self.duration;
        let theta = env * t * s;
        let omega = env * s + env * t * w * c;
        let pivot = if theta >= 0.0 {
            [x0 - b / 2.0, 0.0]
        } else {
            [x0 + b / 2.0, 0.0]
        };
        let (sn, cs) = sin_cos(theta);
        let place = |p: [f64; 2]| {
            let (dx, dy) = (p[0] - pivot[0], p[1] - pivot[1]);
            [pivot[0] + cs * dx - sn * dy, pivot[1] + sn * dx + cs * dy]
        };
        let c0 = [x0, b / 2.0];
        let cen = place(c0);
        let corners = [
            [x0 - b / 2.0, 0.0],
            [x0 + b / 2.0, 0.0],
            [x0 + b / 2.0, b],
            [x0 - b / 2.0, b],
        ];
        let state = if theta == 0.0 && omega == 0.0 {
            BlockMotionState::AtRest
        } else if theta.abs() > TOPPLE_ROTATION {
            BlockMotionState::Toppled
        } else {
            BlockMotionState::Rocking
        };
        BlockFrame {
            x: cen[0] - c0[0],
            y: cen[1] - c0[1],
            rotation: theta,
            // d(centroid)/dt = ω × (centroid − pivot).
            vx: -omega * (cen[1] - pivot[1]),
            vy: omega * (cen[0] - pivot[0]),
            angular_velocity: omega,
            state,
            outline: corners.iter().map(|&p| place(p)).collect(),
        }
    }

    fn slider(&self, t: f64, x0: f64) -> BlockFrame {
        let (s, c) = sin_cos(PI * t / self.duration);
        let x = -self.slide * (1.0 - c) / 2.0;
        let vx = -self.slide * PI / (2.0 * self.duration) * s;
        // A slide speed below 1 µm/s is a block at rest.
        let state = if vx.abs() > 1e-6 {
            BlockMotionState::Sliding
        } else {
            BlockMotionState::AtRest
        };
        let (w, h) = (0.3, 0.15);
        BlockFrame {
            x,
            y: 0.0,
            rotation: 0.0,
            vx,
            vy: 0.0,
            angular_velocity: 0.0,
            state,
            outline: vec![
                [x0 + x, 0.0],
                [x0 + x + w, 0.0],
                [x0 + x + w, h],
                [x0 + x, h],
            ],
        }
    }
}

const PI: f64 = std::f64::consts::PI;

/// (sin x, cos x) with additions and multiplications only: Cody–Waite reduction by π/2 and
/// Taylor series on [−π/4, π/4]. Within a few 1e-16 of the true values for |x| < 1e3, and the
/// same bits everywhere (the platform's libm may differ in the last bit between systems).
pub fn sin_cos(x: f64) -> (f64, f64) {
    // π/2 split (fdlibm's constants): HI has 33 significant bits, so k · HI is exact for
    // |k| < 2^20 and x − k · HI loses nothing; LO = π/2 − HI to double precision.
    const HI: f64 = 1.570_796_326_734_125_6;
    const LO: f64 = 6.077_100_506_506_192e-11;
    let k = (x / HI).round();
    let r = (x - k * HI) - k * LO;
    let r2 = r * r;
    // Taylor terms up to r^17 / 17!: below 1e-17 for |r| ≤ π/4.
    let mut sin = 0.0;
    let mut cos = 0.0;
    let mut term_s = r; // r^(2n+1)/(2n+1)!
    let mut term_c = 1.0; // r^(2n)/(2n)!
    for n in 0..9 {
        sin += term_s;
        cos += term_c;
        let a = (2 * n + 2) as f64;
        let b = (2 * n + 3) as f64;
        term_s = -term_s * r2 / (a * b);
        term_c = -term_c * r2 / ((a - 1.0) * a);
    }
    match (k as i64).rem_euclid(4) {
        0 => (sin, cos),
        1 => (cos, -sin),
        2 => (-sin, -cos),
        _ => (-cos, sin),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_matches_libm() {
        // Reference: the platform's libm. 4e-16 absolute is two ulps of values near 1; the
        // reduction's error grows with |x|, so the range stays within what the synthetic runs use.
        let mut x = -60.0;
        while x < 60.0 {
            let (s, c) = sin_cos(x);
            assert!((s - x.sin()).abs() < 4e-16 + 1e-17 * x.abs(), "sin {x}");
            assert!((c - x.cos()).abs() < 4e-16 + 1e-17 * x.abs(), "cos {x}");
            x += 0.0137;
        }
    }

    #[test]
    fn column_rotates_rigidly_about_a_corner_on_the_base() {
        let m = RockingSquare::default();
        for f in m.frames() {
            let col = &f.blocks[1];
            // Rigid: the side stays `side` (1e-15 m: a few roundings of 0.4 m coordinates).
            let o = &col.outline;
            let side = ((o[1][0] - o[0][0]).powi(2) + (o[1][1] - o[0][1]).powi(2)).sqrt();
            assert!((side - m.side).abs() < 1e-15, "t {}", f.time);
            // The pivot corner stays on the base (y = 0) and nothing goes below it.
            let min_y = o.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
            assert!(
                min_y.abs() < 1e-15 && o.iter().any(|p| p[1] == 0.0),
                "t {}",
                f.time
            );
        }
        let states: std::collections::BTreeSet<String> = m
            .frames()
            .flat_map(|f| {
                f.blocks
                    .iter()
                    .map(|b| format!("{:?}", b.state))
                    .collect::<Vec<_>>()
            })
            .collect();
        assert_eq!(states.len(), 4, "all four states appear: {states:?}");
    }

    #[test]
    fn velocities_are_the_time_derivatives_of_positions() {
        // Second method: central differences with h = 1e-6 s; error O(h²·x''') ≈ 1e-11 plus
        // rounding 1e-16/h ≈ 1e-10, so 1e-8 m/s is a loose but failing-capable bound.
        let h = 1e-6;
        let m = RockingSquare {
            output_interval: h,
            duration: 3.0,
            ..RockingSquare::default()
        };
        for t in [0.37, 1.1, 2.63] {
            let k = (t / h).round() as u64;
            let (a, b, c) = (m.frame(k - 1), m.frame(k), m.frame(k + 1));
            for i in 1..b.blocks.len() {
                let dx = (c.blocks[i].x - a.blocks[i].x) / (2.0 * h);
                let dy = (c.blocks[i].y - a.blocks[i].y) / (2.0 * h);
                let dr = (c.blocks[i].rotation - a.blocks[i].rotation) / (2.0 * h);
                assert!((dx - b.blocks[i].vx).abs() < 1e-8, "vx block {i} t {t}");
                assert!((dy - b.blocks[i].vy).abs() < 1e-8, "vy block {i} t {t}");
                assert!(
                    (dr - b.blocks[i].angular_velocity).abs() < 1e-8,
                    "ω block {i} t {t}"
                );
            }
        }
    }
}
