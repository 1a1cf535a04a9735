//! The triangular-solve pair `x ← (L Lᵀ)⁻¹ x` of a reused supernodal factor, on a copy of faer's
//! factor laid out for repeated single-vector solves ([`super::TriangularSolve::Repacked`],
//! docs/contact-solve.md §35).
//!
//! faer stores a supernode of width w with r rows below it as one column-major (w + r) × w
//! block and solves it by a dense triangular solve and a general matrix product: on the walls'
//! supernodes (w of a few columns, r of a few tens of rows) the product's dispatch and its
//! temporary cost about seven instructions a multiply–add. Here each supernode's diagonal
//! block is kept with the reciprocals of its diagonal, and the rows below it row-major (the w
//! entries of one row of L contiguous), so the forward sweep is one dot product of w terms a
//! row and the backward sweep w updates from one loaded entry of `x`, with w a compile-time
//! constant for w ≤ [`MAX_UNROLLED`] (the loops unroll and keep the supernode's unknowns in
//! registers). The copy costs about one move per entry of L, once per numeric factorization;
//! it is made lazily, at the factor's first solve.
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

/// Widest supernode solved by a kernel with a compile-time width; wider ones (the separators at
/// the top of the elimination tree) take the general loop.
pub(super) const MAX_UNROLLED: usize = 8;

/// One supernode: its first column (in the permuted order), its width, and where its rows
/// below, its diagonal block and its row-major rows start in the copy's arrays.
#[derive(Debug, Clone, Copy)]
struct Node {
    start: usize,
    width: usize,
    rows: usize,
    rows_end: usize,
    diag: usize,
    below: usize,
}

/// faer's supernodal factor, repacked. Empty (`is_built` false) until `build`.
#[derive(Debug, Default)]
pub(super) struct Repacked {
    n: usize,
    /// Permuted unknown k is the system's unknown `fwd[k]` (empty: no permutation).
    fwd: Vec<usize>,
    nodes: Vec<Node>,
    /// Row indices (permuted order) of the rows below each supernode; `u32` (half the memory
    /// traffic of `usize`; `build` declines a factor of more than `u32::MAX` unknowns).
    row_idx: Vec<u32>,
    /// Each supernode's w × w diagonal block, row-major, strictly lower part used.
    diag: Vec<f64>,
    /// Reciprocal of each column's diagonal entry, in column order.
    inv_diag: Vec<f64>,
    /// Each supernode's rows below, row-major (w entries a row).
    below: Vec<f64>,
    /// The permuted vector.
    work: Vec<f64>,
    built: bool,
}

impl Repacked {
    /// Whether the copy holds the current factor.
    pub(super) fn is_built(&self) -> bool {
        self.built
    }

    /// Forget the copy (the factor's values changed).
    pub(super) fn invalidate(&mut self) {
        self.built = false;
    }

    /// Copy the supernodal factor `l_values` of `symbolic`. Returns false (and stays unbuilt)
    /// for a simplicial factor, which faer keeps solving.
    pub(super) fn build(&mut self, symbolic: &SymbolicCholesky<usize>, l_values: &[f64]) -> bool {
        self.built = false;
        let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
            return false;
        };
        let n = symbolic.nrows();
        if u32::try_from(n).is_err() {
            return false;
        }
        self.n = n;
        self.fwd.clear();
        if let Some(perm) = symbolic.perm() {
            self.fwd.extend_from_slice(perm.arrays().0);
        }
        self.nodes.clear();
        self.row_idx.clear();
        self.diag.clear();
        self.inv_diag.clear();
        self.below.clear();
        let val_ptr = s.col_ptr_for_val();
        for (k, (&begin, &end)) in s
            .supernode_begin()
            .iter()
            .zip(s.supernode_end())
            .enumerate()
        {
            let w = end - begin;
            let pattern = s.supernode(k).pattern();
            let r = pattern.len();
            // Column-major (w + r) × w: entry (i, j) at j·(w + r) + i.
            let block = &l_values[val_ptr[k]..val_ptr[k + 1]];
            let ld = w + r;
            self.nodes.push(Node {
                start: begin,
                width: w,
                rows: self.row_idx.len(),
                rows_end: self.row_idx.len() + r,
                diag: self.diag.len(),
                below: self.below.len(),
            });
            self.row_idx.extend(pattern.iter().map(|&i| i as u32));
            for i in 0..w {
                self.diag.extend((0..w).map(|j| block[j * ld + i]));
                self.inv_diag.push(1.0 / block[i * ld + i]);
            }
            for i in w..ld {
                self.below.extend((0..w).map(|j| block[j * ld + i]));
            }
        }
        self.work.resize(n, 0.0);
        self.built = true;
        true
    }

    /// `x ← (L Lᵀ)⁻¹ x` (x in the system's order, length n).
    pub(super) fn solve(&mut self, x: &mut [f64]) {
        let n = self.n;
        debug_assert_eq!(x.len(), n);
        let mut work = std::mem::take(&mut self.work);
        let y: &mut [f64] = if self.fwd.is_empty() {
            x
        } else {
            for (w, &f) in work.iter_mut().zip(&self.fwd) {
                *w = x[f];
            }
            &mut work
        };
        for node in &self.nodes {
            match node.width {
                1 => self.forward::<1>(node, y),
                2 => self.forward::<2>(node, y),
                3 => self.forward::<3>(node, y),
                4 => self.forward::<4>(node, y),
                5 => self.forward::<5>(node, y),
                6 => self.forward::<6>(node, y),
                7 => self.forward::<7>(node, y),
                8 => self.forward::<8>(node, y),
                w => {
                    debug_assert!(w > MAX_UNROLLED);
                    self.forward_wide(node, y)
                }
            }
        }
        for node in self.nodes.iter().rev() {
            match node.width {
                1 => self.backward::<1>(node, y),
                2 => self.backward::<2>(node, y),
                3 => self.backward::<3>(node, y),
                4 => self.backward::<4>(node, y),
                5 => self.backward::<5>(node, y),
                6 => self.backward::<6>(node, y),
                7 => self.backward::<7>(node, y),
                8 => self.backward::<8>(node, y),
                w => {
                    debug_assert!(w > MAX_UNROLLED);
                    self.backward_wide(node, y)
                }
            }
        }
        if !self.fwd.is_empty() {
            for (w, &f) in work.iter().zip(&self.fwd) {
                x[f] = *w;
            }
        }
        self.work = work;
    }

    /// The node's slices: row indices, diagonal block, reciprocal diagonal, rows below.
    fn parts(&self, node: &Node) -> (&[u32], &[f64], &[f64], &[f64]) {
        let (w, r) = (node.width, node.rows_end - node.rows);
        (
            &self.row_idx[node.rows..node.rows_end],
            &self.diag[node.diag..node.diag + w * w],
            &self.inv_diag[node.start..node.start + w],
            &self.below[node.below..node.below + w * r],
        )
    }

    /// L's supernode, forward: its diagonal block's triangular solve, then each row below
    /// takes the dot product of its w entries with the supernode's unknowns.
    #[inline(always)]
    fn forward<const W: usize>(&self, node: &Node, y: &mut [f64]) {
        let (rows, diag, inv, below) = self.parts(node);
        let top: &mut [f64; W] = (&mut y[node.start..node.start + W])
            .try_into()
            .expect("supernode width");
        let mut t = *top;
        for i in 0..W {
            let mut s = t[i];
            for j in 0..i {
                s -= diag[i * W + j] * t[j];
            }
            t[i] = s * inv[i];
        }
        *top = t;
        // Two rows a pass (their sums are independent: each is the one-row loop's sum, in its
        // order), so the loop's own counting and the supernode's unknowns serve both.
        let (rows2, below2) = (rows.chunks_exact(2), below.chunks_exact(2 * W));
        let (row1, below1) = (rows2.remainder(), below2.remainder());
        for (i, l) in rows2.zip(below2) {
            let (la, lb) = l.split_at(W);
            let (mut sa, mut sb) = (0.0, 0.0);
            for j in 0..W {
                sa += la[j] * t[j];
                sb += lb[j] * t[j];
            }
            y[i[0] as usize] -= sa;
            y[i[1] as usize] -= sb;
        }
        for (&i, l) in row1.iter().zip(below1.chunks_exact(W)) {
            let mut s = 0.0;
            for j in 0..W {
                s += l[j] * t[j];
            }
            y[i as usize] -= s;
        }
    }

    /// Lᵀ's supernode, backward: each row below updates the supernode's w unknowns from its
    /// one solved unknown, then the diagonal block's transposed triangular solve.
    #[inline(always)]
    fn backward<const W: usize>(&self, node: &Node, y: &mut [f64]) {
        let (rows, diag, inv, below) = self.parts(node);
        let mut t: [f64; W] = y[node.start..node.start + W]
            .try_into()
            .expect("supernode width");
        // Two rows a pass: each unknown takes row a's update, then row b's, as one row a
        // pass would (the rows' unknowns are read before any is written: they lie below).
        let (rows2, below2) = (rows.chunks_exact(2), below.chunks_exact(2 * W));
        let (row1, below1) = (rows2.remainder(), below2.remainder());
        for (i, l) in rows2.zip(below2) {
            let (la, lb) = l.split_at(W);
            let (va, vb) = (y[i[0] as usize], y[i[1] as usize]);
            for j in 0..W {
                t[j] -= la[j] * va;
                t[j] -= lb[j] * vb;
            }
        }
        for (&i, l) in row1.iter().zip(below1.chunks_exact(W)) {
            let v = y[i as usize];
            for j in 0..W {
                t[j] -= l[j] * v;
            }
        }
        for i in (0..W).rev() {
            t[i] *= inv[i];
            let ti = t[i];
            for k in 0..i {
                t[k] -= diag[i * W + k] * ti;
            }
        }
        y[node.start..node.start + W].copy_from_slice(&t);
    }

    /// `forward` for a supernode wider than [`MAX_UNROLLED`].
    fn forward_wide(&self, node: &Node, y: &mut [f64]) {
        let (rows, diag, inv, below) = self.parts(node);
        let w = node.width;
        let (head, tail) = y.split_at_mut(node.start + w);
        let t = &mut head[node.start..];
        for i in 0..w {
            let s = t[i] - dot(&diag[i * w..i * w + i], &t[..i]);
            t[i] = s * inv[i];
        }
        let t = &*t;
        // The rows below come after the supernode's own columns (L is lower triangular).
        let base = node.start + w;
        let (rows2, below2) = (rows.chunks_exact(2), below.chunks_exact(2 * w));
        let (row1, below1) = (rows2.remainder(), below2.remainder());
        for (i, l) in rows2.zip(below2) {
            let (sa, sb) = dot2(l.split_at(w), t);
            tail[i[0] as usize - base] -= sa;
            tail[i[1] as usize - base] -= sb;
        }
        for (&i, l) in row1.iter().zip(below1.chunks_exact(w)) {
            tail[i as usize - base] -= dot(l, t);
        }
    }

    /// `backward` for a supernode wider than [`MAX_UNROLLED`].
    fn backward_wide(&self, node: &Node, y: &mut [f64]) {
        let (rows, diag, inv, below) = self.parts(node);
        let w = node.width;
        let (head, tail) = y.split_at_mut(node.start + w);
        let t = &mut head[node.start..];
        let base = node.start + w;
        let (rows2, below2) = (rows.chunks_exact(2), below.chunks_exact(2 * w));
        let (row1, below1) = (rows2.remainder(), below2.remainder());
        for (i, l) in rows2.zip(below2) {
            let (la, lb) = l.split_at(w);
            let (va, vb) = (tail[i[0] as usize - base], tail[i[1] as usize - base]);
            for ((tj, a), b) in t.iter_mut().zip(la).zip(lb) {
                *tj -= a * va;
                *tj -= b * vb;
            }
        }
        for (&i, l) in row1.iter().zip(below1.chunks_exact(w)) {
            let v = tail[i as usize - base];
            for (tj, lj) in t.iter_mut().zip(l) {
                *tj -= lj * v;
            }
        }
        // Lᵀ's diagonal block by rows of L (contiguous): each solved unknown updates the ones
        // before it.
        for i in (0..w).rev() {
            t[i] *= inv[i];
            let ti = t[i];
            for (tk, l) in t[..i].iter_mut().zip(&diag[i * w..i * w + i]) {
                *tk -= l * ti;
            }
        }
    }

    /// `solve` as before session 43, one row below a supernode a pass (the reference of the
    /// two-rows kernels' bit-identity test, `sparse_cholesky`'s tests).
    #[cfg(test)]
    pub(super) fn solve_by_rows(&mut self, x: &mut [f64]) {
        let mut work = std::mem::take(&mut self.work);
        let y: &mut [f64] = if self.fwd.is_empty() {
            x
        } else {
            for (w, &f) in work.iter_mut().zip(&self.fwd) {
                *w = x[f];
            }
            &mut work
        };
        for node in &self.nodes {
            let (rows, diag, inv, below) = self.parts(node);
            let w = node.width;
            let (head, tail) = y.split_at_mut(node.start + w);
            let t = &mut head[node.start..];
            for i in 0..w {
                let s = if w > MAX_UNROLLED {
                    t[i] - dot(&diag[i * w..i * w + i], &t[..i])
                } else {
                    let mut s = t[i];
                    for j in 0..i {
                        s -= diag[i * w + j] * t[j];
                    }
                    s
                };
                t[i] = s * inv[i];
            }
            let base = node.start + w;
            for (&i, l) in rows.iter().zip(below.chunks_exact(w)) {
                let s = if w > MAX_UNROLLED {
                    dot(l, t)
                } else {
                    let mut s = 0.0;
                    for j in 0..w {
                        s += l[j] * t[j];
                    }
                    s
                };
                tail[i as usize - base] -= s;
            }
        }
        for node in self.nodes.iter().rev() {
            let (rows, diag, inv, below) = self.parts(node);
            let w = node.width;
            let (head, tail) = y.split_at_mut(node.start + w);
            let t = &mut head[node.start..];
            let base = node.start + w;
            for (&i, l) in rows.iter().zip(below.chunks_exact(w)) {
                let v = tail[i as usize - base];
                for j in 0..w {
                    t[j] -= l[j] * v;
                }
            }
            for i in (0..w).rev() {
                t[i] *= inv[i];
                let ti = t[i];
                for k in 0..i {
                    t[k] -= diag[i * w + k] * ti;
                }
            }
        }
        if !self.fwd.is_empty() {
            for (w, &f) in work.iter().zip(&self.fwd) {
                x[f] = *w;
            }
        }
        self.work = work;
    }

    /// Supernode widths of the copy (for tests and diagnostics): count per width 1..=
    /// [`MAX_UNROLLED`], and the wider ones in the last entry.
    #[cfg(test)]
    pub(super) fn width_counts(&self) -> [usize; MAX_UNROLLED + 1] {
        let mut c = [0; MAX_UNROLLED + 1];
        for node in &self.nodes {
            c[node.width.min(MAX_UNROLLED + 1) - 1] += 1;
        }
        c
    }
}

/// Σ aᵢ bᵢ over four interleaved partial sums (the compiler pairs them into vector
/// operations; a single running sum would chain every addition on the previous one).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (a4.remainder(), b4.remainder());
    let mut acc = [0.0; 4];
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut s = (acc[0] + acc[2]) + (acc[1] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

/// [`dot`] of two rows `a` and `b` with the same `t`, each sum in `dot`'s order (so each is
/// `dot`'s to the bit), `t` loaded once for both.
fn dot2((a, b): (&[f64], &[f64]), t: &[f64]) -> (f64, f64) {
    let (a4, b4, t4) = (a.chunks_exact(4), b.chunks_exact(4), t.chunks_exact(4));
    let (ra, rb, rt) = (a4.remainder(), b4.remainder(), t4.remainder());
    let (mut acc_a, mut acc_b) = ([0.0; 4], [0.0; 4]);
    for ((x, y), z) in a4.zip(b4).zip(t4) {
        for k in 0..4 {
            acc_a[k] += x[k] * z[k];
            acc_b[k] += y[k] * z[k];
        }
    }
    let mut sa = (acc_a[0] + acc_a[2]) + (acc_a[1] + acc_a[3]);
    let mut sb = (acc_b[0] + acc_b[2]) + (acc_b[1] + acc_b[3]);
    for ((x, y), z) in ra.iter().zip(rb).zip(rt) {
        sa += x * z;
        sb += y * z;
    }
    (sa, sb)
}
