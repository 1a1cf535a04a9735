//! Reduced models, numerics: one Dormand–Prince 5(4) step for the two-state systems of the
//! rocking and sliding models (x, ẋ), with its embedded error estimate.

/// (coordinate, rate): rad and rad/s for rocking, m and m/s for sliding.
pub type State = [f64; 2];

const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// Fifth-order weights (the last row of A: the method is FSAL).
const B5: [f64; 7] = [
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
    0.0,
];
/// Embedded fourth-order weights.
const B4: [f64; 7] = [
    5179.0 / 57600.0,
    0.0,
    7571.0 / 16695.0,
    393.0 / 640.0,
    -92097.0 / 339200.0,
    187.0 / 2100.0,
    1.0 / 40.0,
];

/// Error tolerances of the adaptive step (per component: atol + rtol·|x|).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    pub rtol: f64,
    /// Absolute tolerance on the coordinate (rad or m) and on the rate (per s).
    pub atol: f64,
}

/// One step of size `h` from (t, y): the fifth-order solution and the scaled error norm
/// (≤ 1 means the step meets the tolerance).
pub fn step(
    f: &impl Fn(f64, State) -> State,
    t: f64,
    y: State,
    h: f64,
    tol: Tolerance,
) -> (State, f64) {
    let (y5, norm, _) = step_from(f, t, y, f(t, y), h, tol);
    (y5, norm)
}

/// [`step`] given the first stage `k1` = f(t, y), which the caller may already hold: the last
/// stage of the previous step (the method is FSAL: that stage is f at the step's end and its
/// fifth-order solution), or the same start tried again with another `h` (event location).
/// Returns also the last stage, f(t + h, y5), for the next step.
pub fn step_from(
    f: &impl Fn(f64, State) -> State,
    t: f64,
    y: State,
    k1: State,
    h: f64,
    tol: Tolerance,
) -> (State, f64, State) {
    let mut k = [[0.0; 2]; 7];
    k[0] = k1;
    for s in 1..7 {
        let mut ys = y;
        for (j, kj) in k.iter().enumerate().take(s) {
            ys[0] += h * A[s][j] * kj[0];
            ys[1] += h * A[s][j] * kj[1];
        }
        k[s] = f(t + C[s] * h, ys);
    }
    let mut y5 = y;
    let mut err = [0.0; 2];
    for s in 0..7 {
        for c in 0..2 {
            y5[c] += h * B5[s] * k[s][c];
            err[c] += h * (B5[s] - B4[s]) * k[s][c];
        }
    }
    let norm = (0..2)
        .map(|c| err[c].abs() / (tol.atol + tol.rtol * y[c].abs().max(y5[c].abs())))
        .fold(0.0, f64::max);
    (y5, norm, k[6])
}

/// The next step size after an error norm `norm` (standard controller, safety 0.9, growth
/// limited to [0.2, 5] so one lucky step cannot overshoot the next feature of the record).
pub fn next_h(h: f64, norm: f64) -> f64 {
    let factor = if norm <= 1e-12 {
        5.0
    } else {
        (0.9 * norm.powf(-0.2)).clamp(0.2, 5.0)
    };
    h * factor
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_stage_is_f_at_the_step_end() {
        // FSAL: the seventh stage is evaluated at (t + h, y5), so handing it to the next step
        // as its first stage changes nothing (bit for bit: the stage's state is the same sum
        // in the same order as y5, and 1·h is exact).
        let f = |t: f64, y: State| [y[1], -y[0] + t.sin()];
        let tol = Tolerance {
            rtol: 1e-10,
            atol: 1e-12,
        };
        let (t, y, h) = (0.3, [0.2, -0.7], 0.01);
        let (y5, _, k7) = step_from(&f, t, y, f(t, y), h, tol);
        assert_eq!(k7, f(t + h, y5));
        assert_eq!(step(&f, t, y, h, tol).0, y5);
    }

    #[test]
    fn harmonic_oscillator_one_period_to_fifth_order() {
        // ẍ = −x from (1, 0): after 2π the state returns to (1, 0). The error of a fifth-order
        // method falls 32× when h halves (tolerance: the observed ratio within 25…40).
        let f = |_t: f64, y: State| [y[1], -y[0]];
        let tol = Tolerance {
            rtol: 1.0,
            atol: 1.0,
        };
        let run = |n: usize| {
            let h = 2.0 * std::f64::consts::PI / n as f64;
            let mut y = [1.0, 0.0];
            for i in 0..n {
                y = step(&f, i as f64 * h, y, h, tol).0;
            }
            ((y[0] - 1.0).powi(2) + y[1].powi(2)).sqrt()
        };
        let (e1, e2) = (run(20), run(40));
        let ratio = e1 / e2;
        assert!(
            (25.0..40.0).contains(&ratio),
            "ratio {ratio}, errors {e1} {e2}"
        );
    }
}
