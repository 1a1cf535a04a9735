//! Anderson acceleration of the open–close loop's friction fixed point (solve stage, inside
//! `open_close::iterate`): while no contact changes state, the normal forces N_in that the
//! sliding contacts' Coulomb friction μ·N_in is computed from map *linearly* to the normal
//! forces N_out the solve gives back (the states fix the matrix; friction is a load linear in
//! N_in). Plain substitution N_in ← N_out converges at the map's spectral radius and is
//! relaxed by ½ after a few iterations (`OpenCloseParams::relax_after`); Anderson's mixing over
//! the last m iterates is GMRES on that linear map, so it converges in about as many solves as
//! the map has strongly coupled directions, not as many as its contraction needs
//! (docs/contact-solve.md §6). The stopping test is unchanged (each contact's own residual
//! |N_out − N_in|), so the converged answer is the same fixed point.
use crate::contact::ContactState;

/// The history of one run of iterations with unchanged contact states.
#[derive(Debug, Default, Clone)]
pub struct FrictionAnderson {
    /// Contacts taking part (sliding, friction, in the same direction for the whole history),
    /// with their slip direction: the key of the history.
    set: Vec<(usize, f64)>,
    /// Inputs N_in (N) and residuals N_out − N_in (N) of the last iterates, oldest first.
    inputs: Vec<Vec<f64>>,
    residuals: Vec<Vec<f64>>,
    /// Scratch: the difference columns and the QR factor of the residual differences.
    dx: Vec<Vec<f64>>,
    df: Vec<Vec<f64>>,
    r: Vec<f64>,
    gamma: Vec<f64>,
    weight: Vec<f64>,
    /// Candidate set of the current iteration (reused buffer).
    next_set: Vec<(usize, f64)>,
    next_in: Vec<f64>,
    next_out: Vec<f64>,
    /// Scratch of `step`: the orthonormalised columns, which columns are kept, the weighted
    /// residual, the answer, and retired history rows for reuse.
    q: Vec<Vec<f64>>,
    keep: Vec<bool>,
    wf: Vec<f64>,
    out: Vec<(usize, f64)>,
    spare: Vec<Vec<f64>>,
}

impl FrictionAnderson {
    /// Forget the history (a contact changed state: the map changed).
    pub fn clear(&mut self) {
        self.set.clear();
        self.spare.append(&mut self.inputs);
        self.spare.append(&mut self.residuals);
    }

    fn take_row(&mut self) -> Vec<f64> {
        let mut v = self.spare.pop().unwrap_or_default();
        v.clear();
        v
    }

    /// Carry the history over to a changed set of participants (`FrictionAnderson::step` with
    /// `keep` on): a contact that left is dropped from every past point; one that joined is
    /// entered into every past point with its current value, so its difference rows are zero,
    /// it does not move γ, and its own update is plain substitution until it has a history.
    fn remap(&mut self) {
        let mut inputs: Vec<Vec<f64>> =
            vec![Vec::with_capacity(self.next_set.len()); self.inputs.len()];
        let mut residuals = inputs.clone();
        let mut old = 0;
        for (i, key) in self.next_set.iter().enumerate() {
            while old < self.set.len() && self.set[old].0 < key.0 {
                old += 1;
            }
            let kept = old < self.set.len() && self.set[old] == *key;
            for p in 0..self.inputs.len() {
                if kept {
                    inputs[p].push(self.inputs[p][old]);
                    residuals[p].push(self.residuals[p][old]);
                } else {
                    inputs[p].push(self.next_in[i]);
                    residuals[p].push(self.next_out[i] - self.next_in[i]);
                }
            }
        }
        self.inputs = inputs;
        self.residuals = residuals;
        self.set.clone_from(&self.next_set);
    }

    /// Start collecting this iteration's participants.
    pub fn begin(&mut self) {
        self.next_set.clear();
        self.next_in.clear();
        self.next_out.clear();
    }

    /// A sliding contact `k` whose friction used `n_in` and whose solve gave `n_out` (N).
    pub fn note(&mut self, k: usize, state: ContactState, n_in: f64, n_out: f64) {
        if let ContactState::Sliding { dir } = state {
            self.next_set.push((k, dir));
            self.next_in.push(n_in);
            self.next_out.push(n_out);
        }
    }

    /// Add this iteration's point and return, for each participant in the order noted, the next
    /// input, or `None` when there is no history to mix with (the caller keeps its plain or
    /// relaxed update). `depth` is the number of differences mixed, `floor` (N) is added to a
    /// contact's force in its weight, as in the loop's stopping test.
    pub fn step(&mut self, depth: usize, floor: f64) -> Option<&[(usize, f64)]> {
        if self.next_set != self.set {
            if self.inputs.is_empty() {
                self.clear();
                std::mem::swap(&mut self.set, &mut self.next_set);
            } else {
                self.remap();
            }
        }
        let n = self.set.len();
        if n == 0 || depth == 0 {
            return None;
        }
        let mut res = self.take_row();
        res.extend(self.next_in.iter().zip(&self.next_out).map(|(a, b)| b - a));
        let mut input = self.take_row();
        input.extend_from_slice(&self.next_in);
        self.inputs.push(input);
        self.residuals.push(res);
        while self.inputs.len() > depth + 1 {
            let a = self.inputs.remove(0);
            let b = self.residuals.remove(0);
            self.spare.push(a);
            self.spare.push(b);
        }
        let points = self.inputs.len();
        if points < 2 {
            return None;
        }
        let last_x = &self.inputs[points - 1];
        let last_f = &self.residuals[points - 1];
        // Each contact's residual relative to its own force, as the stopping test measures it.
        self.weight.clear();
        self.weight.extend(
            last_x
                .iter()
                .zip(last_f)
                .map(|(x, f)| 1.0 / (x.abs().max((x + f).abs()) + floor)),
        );
        // A mix gone wrong (the map changed under a kept history): restart from this point.
        let norm = |f: &[f64]| -> f64 {
            f.iter()
                .zip(&self.weight)
                .map(|(f, w)| (f * w) * (f * w))
                .sum::<f64>()
        };
        if norm(last_f) > 100.0 * norm(&self.residuals[points - 2]) {
            let old: Vec<Vec<f64>> = self
                .inputs
                .drain(..points - 1)
                .chain(self.residuals.drain(..points - 1))
                .collect();
            self.spare.extend(old);
            return None;
        }
        let m = points - 1;
        self.dx.resize(m, Vec::new());
        self.df.resize(m, Vec::new());
        for j in 0..m {
            let (dx, df) = (&mut self.dx[j], &mut self.df[j]);
            dx.clear();
            df.clear();
            for i in 0..n {
                dx.push(self.inputs[j + 1][i] - self.inputs[j][i]);
                df.push((self.residuals[j + 1][i] - self.residuals[j][i]) * self.weight[i]);
            }
        }
        // Modified Gram–Schmidt on the weighted residual differences; a column nearly in the
        // span of the earlier ones is dropped (its γ = 0), which keeps the mix well posed.
        let keep = &mut self.keep;
        keep.clear();
        keep.resize(m, true);
        self.r.clear();
        self.r.resize(m * m, 0.0);
        let q = &mut self.q;
        q.resize(m, Vec::new());
        for (qj, dfj) in q.iter_mut().zip(&self.df) {
            qj.clone_from(dfj);
        }
        for j in 0..m {
            let norm0 = dot(&q[j], &q[j]).sqrt();
            for i in 0..j {
                if !keep[i] {
                    continue;
                }
                let rij = dot(&q[i], &q[j]);
                self.r[i * m + j] = rij;
                // i < j: the earlier column is in the first half.
                let (a, b) = q.split_at_mut(j);
                let (qi, qj) = (&a[i], &mut b[0]);
                for (b, a) in qj.iter_mut().zip(qi) {
                    *b -= rij * a;
                }
            }
            let norm = dot(&q[j], &q[j]).sqrt();
            if norm.is_nan() || norm <= 1e-10 * norm0 || norm == 0.0 {
                keep[j] = false;
                continue;
            }
            self.r[j * m + j] = norm;
            for v in q[j].iter_mut() {
                *v /= norm;
            }
        }
        // γ = R⁻¹ Qᵀ f (weighted).
        let wf = &mut self.wf;
        wf.clear();
        wf.extend(last_f.iter().zip(&self.weight).map(|(f, w)| f * w));
        self.gamma.clear();
        self.gamma.resize(m, 0.0);
        for j in (0..m).rev() {
            if !keep[j] {
                continue;
            }
            let mut s = dot(&q[j], wf);
            for i in j + 1..m {
                if keep[i] {
                    s -= self.r[j * m + i] * self.gamma[i];
                }
            }
            self.gamma[j] = s / self.r[j * m + j];
        }
        if self.gamma.iter().any(|g| !g.is_finite()) {
            self.clear();
            return None;
        }
        // x⁺ = x + f − Σ γ_j (Δx_j + Δf_j), in unweighted forces.
        let out = &mut self.out;
        out.clear();
        for i in 0..n {
            let mut v = last_x[i] + last_f[i];
            for j in 0..m {
                v -= self.gamma[j] * (self.dx[j][i] + self.df[j][i] / self.weight[i]);
            }
            out.push((self.set[i].0, v.max(0.0)));
        }
        Some(&self.out)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On an affine map N ↦ A·N + b (what the loop's solve is for fixed contact states) the
    /// mix converges like GMRES: within n + 2 maps for n contacts, where plain substitution at
    /// spectral radius 0.95 needs about 450 for the same 1e-10.
    #[test]
    fn converges_on_an_affine_map_in_about_n_iterations() {
        let a = [[0.9, 0.04, 0.0], [0.04, -0.7, 0.1], [0.0, 0.1, 0.5]];
        let b = [10.0, 200.0, 3.0];
        let map = |x: &[f64; 3]| -> [f64; 3] {
            let mut y = b;
            for i in 0..3 {
                for j in 0..3 {
                    y[i] += a[i][j] * x[j];
                }
            }
            y
        };
        let mut acc = FrictionAnderson::default();
        let mut x = [1.0, 1.0, 1.0];
        let mut iterations = 0;
        for it in 1..=20 {
            let y = map(&x);
            let err = (0..3)
                .map(|i| (y[i] - x[i]).abs() / y[i].abs())
                .fold(0.0, f64::max);
            if err < 1e-10 {
                iterations = it;
                break;
            }
            acc.begin();
            for i in 0..3 {
                acc.note(i, ContactState::Sliding { dir: 1.0 }, x[i], y[i]);
            }
            match acc.step(5, 1e-9) {
                Some(next) => {
                    for &(k, v) in next {
                        x[k] = v;
                    }
                }
                None => x = y,
            }
        }
        assert!(
            (1..=5).contains(&iterations),
            "took {iterations} maps (0 = not converged in 20)"
        );
    }

    /// A contact that changes its slip direction leaves the history; the others keep theirs.
    #[test]
    fn a_contact_that_changes_direction_restarts_alone() {
        let mut acc = FrictionAnderson::default();
        for (n_in, n_out) in [(1.0, 2.0), (2.0, 2.5)] {
            acc.begin();
            acc.note(0, ContactState::Sliding { dir: 1.0 }, n_in, n_out);
            acc.note(1, ContactState::Sliding { dir: 1.0 }, n_in, n_out);
            acc.step(5, 1e-9);
        }
        acc.begin();
        acc.note(0, ContactState::Sliding { dir: 1.0 }, 2.5, 2.75);
        acc.note(1, ContactState::Sliding { dir: -1.0 }, 2.5, 7.0);
        let next = acc.step(5, 1e-9).expect("contact 0 has a history").to_vec();
        // Contact 1 entered with zero differences: plain substitution.
        assert_eq!(next[1], (1, 7.0));
        // Contact 0's map N ↦ 1.5 + N/2 has its fixed point at 3.
        assert!((next[0].1 - 3.0).abs() < 1e-9, "{next:?}");
    }
}
