//! Sparse Cholesky (faer) of the block system; the symbolic factorization (ordering and
//! elimination tree) is reused while the block pattern of contacts is unchanged, and the last
//! numeric factor preconditions a conjugate-gradient solve of the next system (the matrix
//! changes little from one step or open–close iteration to the next), so most solves cost a
//! few triangular solves instead of a factorization. A solve that does not converge in
//! [`SparseParams::max_reuse_iterations`] falls back to a fresh factorization. On a large
//! factor, whether to try the old factor at all is decided by the factor's own cost model
//! (a factorization against the expected conjugate-gradient iterations, learned from the last
//! attempts): [`SparseCholesky::reuse_pays`].
use super::dissection::{coordinate_dissection, nested_dissection};
use super::repacked::Repacked;
use super::SolveError;
use crate::assembly::{BlockSystem, Dofs};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side};
use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// Relative change of an off-diagonal block that counts as a changed spring in
/// [`SparseCholesky::major_changes`]: a spring opening or closing changes its coupling block by
/// 1/m of its size when m springs join the two blocks (m ≤ 4 between two polygons' sides);
/// geometry drift changes it by the blocks' relative motion within one step, usually far less
/// (a misjudged count only costs time: the iteration still checks its own convergence).
const MAJOR_CHANGE: f64 = 0.2;

/// Length of the per-prediction tables (`expected`, [`ReuseTable`]): predicted counts from 0
/// to this − 1 have their own entry, larger ones share the last.
pub const REUSE_TABLE_LEN: usize = 16;

/// Per predicted iteration count (`major_changes`, the last entry for all larger), the
/// reused-factor attempts: `[attempts, CG iterations, failed attempts, skipped by the cost
/// rule]` (diagnostics for benchmarks).
pub type ReuseTable = [[u64; 4]; REUSE_TABLE_LEN];

/// Cost model of one factor, in units of one multiply–add of a triangular solve (the
/// instructions of the CG iteration's parts scale with these counts: docs/contact-solve.md §15).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FactorCost {
    /// A numeric factorization: Σ over the columns of L of c(c−1)/2 + c multiply–adds (c the
    /// column's count of entries, diagonal included), times
    /// [`SparseParams::factor_work_weight`].
    pub factor: f64,
    /// A triangular-solve pair (L, then Lᵀ): 2·nnz(L).
    pub pair: f64,
    /// A matrix–vector product on the stored upper triangle: [`FactorCost::MATVEC_PER_ENTRY`]
    /// per stored entry.
    pub matvec: f64,
    /// Unknowns (the vector operations of an iteration cost a few per unknown).
    pub n: f64,
}

impl FactorCost {
    /// Vector operations of one CG iteration per unknown: two updates, the direction, two dot
    /// products, the copy of the residual and the two largest-entry scans.
    /// Measured on the shaken walls (§14's instructions over the counted work, in units of a
    /// triangular-solve multiply–add): 9 at 410 stones.
    pub const VECTOR_OPS: f64 = 8.0;
    /// Work of the symmetric product per stored upper-triangle entry (two multiply–adds, with
    /// indexed loads and stores the triangular solves' dense supernodes avoid): measured 2.4
    /// at 410 stones and 3.2 at 1620 (§15).
    pub const MATVEC_PER_ENTRY: f64 = 3.0;

    /// Work of the factor `symbolic` of a matrix with `stored` upper-triangle entries.
    fn of(symbolic: &SymbolicCholesky<usize>, stored: usize, weight: f64) -> Self {
        let mut factor = 0.0;
        let mut nnz = 0.0;
        let mut column = |c: f64| {
            factor += c * (c - 1.0) / 2.0 + c;
            nnz += c;
        };
        match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => {
                for (k, (&begin, &end)) in s
                    .supernode_begin()
                    .iter()
                    .zip(s.supernode_end())
                    .enumerate()
                {
                    let below = s.supernode(k).pattern().len();
                    for j in 0..end - begin {
                        column((end - begin - j + below) as f64);
                    }
                }
            }
            SymbolicCholeskyRaw::Simplicial(s) => {
                for w in s.col_ptr().windows(2) {
                    column((w[1] - w[0]) as f64);
                }
            }
        }
        Self {
            factor: weight * factor,
            pair: 2.0 * nnz,
            matvec: Self::MATVEC_PER_ENTRY * stored as f64,
            n: symbolic.nrows() as f64,
        }
    }

    /// One CG iteration: a preconditioning (triangular-solve pair), a product, vector updates.
    pub fn iteration(&self) -> f64 {
        self.pair + self.matvec + Self::VECTOR_OPS * self.n
    }

    /// The start of a reused-factor attempt: two preconditionings (the first guess and the first
    /// residual) and a product.
    pub fn start(&self) -> f64 {
        2.0 * self.pair + self.matvec + Self::VECTOR_OPS * self.n
    }

    /// CG iterations at which a reused-factor attempt costs as much as a fresh factorization
    /// and its triangular-solve pair: start + b·iteration = factorization + pair.
    pub fn break_even(&self) -> f64 {
        (self.factor + self.pair - self.start()) / self.iteration()
    }
}

#[derive(Default)]
pub struct SparseCholesky {
    pattern: Vec<(usize, usize)>,
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// Per column block: sorted row blocks (≤ column) with the off-diagonal slot (None = diag).
    col_blocks: Vec<Vec<(usize, Option<usize>)>>,
    symbolic: Option<SymbolicCholesky<usize>>,
    l_values: Vec<f64>,
    /// `l_values` holds a factor of a matrix with the current pattern (usable as preconditioner).
    factored: bool,
    /// The matrix values `l_values` factors (to count how much the matrix changed since).
    factored_values: Vec<f64>,
    /// Scratch of [`SparseCholesky::major_changes`]: per off-diagonal slot, the largest
    /// change of an entry and the largest entry.
    change: Vec<[f64; 2]>,
    mem: Option<MemBuffer>,
    /// Conjugate-gradient scratch: right-hand side, residual, preconditioned residual,
    /// search direction and its image.
    b: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    /// Cost model of the current symbolic factor (`rebuild_pattern`).
    cost: FactorCost,
    /// Per predicted count (`major_changes`, the last entry for all larger): the expected cost
    /// of a reused-factor attempt in CG iterations beyond its start (a failed attempt counts
    /// its iterations plus the factorization it falls back to), a running average of the last
    /// attempts. Empty until the first decision; kept across pattern changes (it measures how
    /// the matrix changes, not its size).
    expected: Vec<f64>,
    pub symbolic_count: u64,
    pub numeric_count: u64,
    pub reuse_iterations: u64,
    /// Attempts, iterations, failures and rule skips per predicted count (diagnostics).
    pub reuse_table: ReuseTable,
    /// [`SparseParams::start_check_samples`]: the largest ratio max|z₀| / max|r₀| of the
    /// preconditioned to the plain start residual seen on the current factor, and how many
    /// starts it was taken from (both reset by `factorize`).
    start_ratio: f64,
    start_samples: usize,
    /// Reused-factor attempts accepted at the start by the estimate, without their second
    /// triangular-solve pair (diagnostics).
    pub start_skips: u64,
    /// With [`SparseParams::start_check_audit`]: starts accepted by the estimate whose exact
    /// test (max|z₀| ≤ `reuse_tolerance`·max|x₀|) fails.
    pub start_check_misses: u64,
    /// With [`SparseParams::check_reuse`]: the largest difference between a reused-factor
    /// solution and the refactored solution of the same system, relative to the largest
    /// unknown of the latter.
    pub reuse_max_error: f64,
    /// Scratch of [`SparseCholesky::low_rank_solve`].
    low_rank: LowRankScratch,
    /// [`SparseParams::triangular`] of the current call, and the repacked copy of the factor
    /// ([`TriangularSolve::Repacked`]; made at the factor's first solve).
    triangular: TriangularSolve,
    repacked: Repacked,
    /// Copies of the factor made for [`TriangularSolve::Repacked`] (diagnostics).
    pub repack_count: u64,
    /// Solves done by the low-rank correction of the last factor
    /// ([`SparseParams::low_rank_max_rank`]), and the sum of their ranks.
    pub low_rank_solves: u64,
    pub low_rank_rank: u64,
    /// Low-rank corrections declined (the change's support or rank above the bound, e.g. every
    /// block drifted since the factor was made in an earlier step).
    pub low_rank_declined: u64,
    /// Of those, the ones declined after the eigen-decomposition (rank above the bound: its
    /// cost was spent), and the sum of their supports' cubes (unknowns³, the cost's scale).
    pub low_rank_declined_rank: u64,
    pub low_rank_declined_cube: f64,
    /// Low-rank corrections whose refinement did not reach `reuse_tolerance` (then the
    /// solver went on as without the correction).
    pub low_rank_failed: u64,
}

/// Scratch of the low-rank correction: per unknown its index in the change's support (or
/// `usize::MAX`), the support, the changed entries (support-local row, column, change), the
/// right-hand sides solved with the old factor (column-major, n × (1 + rank)) and faer's
/// workspace for that many columns.
#[derive(Default)]
struct LowRankScratch {
    local: Vec<usize>,
    support: Vec<usize>,
    entries: Vec<(usize, usize, f64)>,
    cols: Vec<f64>,
    residual: Vec<f64>,
    /// The change's eigenvalues kept (indices above round-off), and the corrected solution.
    kept: Vec<usize>,
    sol: Vec<f64>,
    mem: Option<MemBuffer>,
    mem_cols: usize,
}

/// Unknowns the change of one spring touches at most: its two blocks' (≤ 6 each). The
/// low-rank correction declines a change touching more than this × its rank bound
/// before the eigen-decomposition (whose cost grows as the cube of the support).
const LOW_RANK_SUPPORT_PER_RANK: usize = 12;

/// Eigenvalues of the change below this fraction of its largest are round-off of the
/// entries' differences (≈ 1e-16 of the penalty stiffness a spring adds) and dropped from the
/// rank; the refinement corrects what they leave.
const LOW_RANK_DROP: f64 = 1e-12;

/// Refinement steps (residual with the new matrix, correction through the same low-rank
/// inverse) after the correction's solve: the first is the check that the solve reached
/// `reuse_tolerance`; a second catches a correction that lost digits to a poorly conditioned
/// capacitance matrix. If neither reaches it, the solver refactors.
const LOW_RANK_REFINEMENTS: usize = 2;

/// Tuning of the sparse path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SparseParams {
    /// Force faer's supernodal factorization. Block systems of 2D masonry have dense 3×3 or
    /// 6×6 blocks and nested-dissection fill, where supernodes (dense kernels) beat faer's
    /// automatic choice here, the simplicial (scalar) one, by 1.6× at 400 blocks (callgrind,
    /// `examples/engine_scaling.rs` wall); on whole shaken steps simplicial costs 12–31 % more
    /// at 410 blocks and 76–182 % more at 1620 (docs/contact-solve.md §16). `false` leaves the
    /// choice to faer, which picks simplicial at 410 blocks but supernodal at 1620.
    pub supernodal: bool,
    /// Conjugate-gradient iterations preconditioned by the previous factor before refactoring;
    /// 0 always refactors. A step that changes no contact state converges in 1–2, one that
    /// opens or closes k springs in about k + 1; 8 covers the common case and caps the cost of
    /// a failed attempt below one factorization. A change of the matrix whose rank is
    /// already this large (estimated by `major_changes`) refactors without trying.
    pub max_reuse_iterations: usize,
    /// Convergence: the preconditioned residual (≈ the remaining error of the solution, since
    /// the preconditioner is nearly the matrix) below this fraction of the largest unknown.
    /// 1e-12 leaves the solution as accurate as the direct solve's round-off at the condition
    /// numbers of penalty systems (≈ 1e4 relative to eps).
    pub reuse_tolerance: f64,
    /// Check every reused-factor solve against a fresh factorization of the same system and
    /// keep the largest relative difference (`SparseCounts::reuse_max_error`). Off: it costs a
    /// factorization a solve, the work the reuse saves; for tests of the shortcut only (the
    /// reused factor itself is kept, so the run takes the same path as without the check).
    pub check_reuse: bool,
    /// Instructions of one multiply–add of faer's supernodal numeric factorization relative to
    /// one of its triangular solves (the factorization runs dense SIMD kernels on whole
    /// supernodes, the solves mostly vector–matrix products). Calibrated on the shaken walls
    /// (docs/contact-solve.md §15): the measured factorization/solve-pair instruction ratio
    /// over the counted multiply–add ratio, at 410 and 1620 stones.
    pub factor_work_weight: f64,
    /// The cost rule ([`SparseCholesky::reuse_pays`]) decides only when a factorization costs
    /// at least this many solve multiply–adds; below, every change smaller than
    /// `max_reuse_iterations` tries the old factor (the rule before session 34). A
    /// factorization that cheap costs little either way, and small scenes (the tests' walls and
    /// the golden-digest column) keep their path bit for bit.
    pub cost_rule_min_work: f64,
    /// Weight of the newest attempt in the running average of a prediction's cost
    /// (`SparseCholesky::expected`): 0.25 averages over about the last four attempts, so the
    /// rule follows a change of regime (shaking → rest) within a few steps.
    pub reuse_learning_rate: f64,
    /// While the rule refactors without trying, a prediction's expected cost moves by this
    /// fraction back toward its prior (the predicted count itself) per skipped solve, so a
    /// prediction judged too costly is tried again after about 1/rate solves (the matrix
    /// changes may have become smaller). 0.1: a retry costs at most one failed attempt in ten.
    pub reuse_forget_rate: f64,
    /// Cheaper start of a reused-factor solve (0 = off: every start preconditions its
    /// residual, a second triangular-solve pair, to test convergence). With k > 0, once k
    /// starts on the current factor have measured the ratio ρ = max|z₀| / max|r₀| of the
    /// preconditioned to the plain residual, a start whose `start_check_margin`·ρ·max|r₀|
    /// already meets `reuse_tolerance` is accepted without computing z₀. ρ is a sample of
    /// ‖M⁻¹‖ (M the old factor's matrix) in the directions the residuals took, not a bound;
    /// an accepted start the exact test would reject is counted by `start_check_audit`.
    /// Default 2 (docs/contact-solve.md §19): one sample would trust a single direction; two
    /// were enough for every start of the 105- and 410-stone walls at rest, under the sine and
    /// the record (no accepted start the exact test rejects, state digests unchanged), and a
    /// factor at rest lives ~100 solves, so a larger k gives up little of the −10 % there.
    pub start_check_samples: usize,
    /// Safety factor on the sampled ratio of `start_check_samples` (dimensionless): 10 asks the
    /// estimated preconditioned residual to be ten times below the tolerance, an order of
    /// magnitude for the directions the samples did not see.
    pub start_check_margin: f64,
    /// Diagnostics of `start_check_samples`: a start accepted by the estimate also computes
    /// the exact test's z₀ and counts it in `SparseCounts::start_check_misses` if that test
    /// fails. The accepted solution is kept either way, so the run's path does not change;
    /// off by default (it costs the pair the check saves). For tests of the heuristic.
    pub start_check_audit: bool,
    /// The fill-reducing ordering of the factorization (docs/contact-solve.md §20). Changes
    /// the factor's round-off, not the system solved.
    pub ordering: SparseOrdering,
    /// Blocks in a part of [`SparseOrdering::BlockDissection`] or
    /// [`SparseOrdering::BlockCoordinates`] below which the part is ordered by minimum degree
    /// instead of cut again: 8, the least factorization work on the pile of examples/pile.rs
    /// among 4–512 (4 and 8 within 0.1 %, 64 costs 9 % more: docs/contact-solve.md §20).
    pub dissection_leaf: usize,
    /// faer's amalgamation of supernodes (merging adjacent supernodes into one with explicit
    /// zeros, so its dense kernels run on wider blocks).
    pub relax: SupernodeRelax,
    /// Largest rank of a change of the matrix since its last factorization that is solved by
    /// a low-rank correction of that factor (Woodbury: K' = K + U Λ Uᵀ from the exactly
    /// changed entries, `rank` + 1 triangular-solve pairs and a `rank` × `rank` dense solve,
    /// exact to round-off, checked by a refinement) instead of the conjugate gradients or a
    /// factorization. Within one step (fixed geometry and Δt) the matrix changes only by the
    /// springs that opened or closed, each a rank-1 term, so the change is low-rank; across
    /// steps every block drifts and the correction declines. 0 (the default): off, the path
    /// of every session before 36 bit for bit (docs/pile.md, "Session 36").
    pub low_rank_max_rank: usize,
    /// Who solves the triangular-solve pairs of a factor (after a factorization, and each
    /// preconditioning of the conjugate gradients); faer factors either way.
    /// Default `Repacked` (since session 42): 16 % fewer instructions in these solves on the
    /// shaken 410-stone wall, its copies included, 10–15 % less wall time a step (sine and
    /// 3 m/s² sine), every suite passing with it; it moves results by round-off only
    /// (docs/contact-solve.md §35). `Faer`: the results of every session before 42 bit for bit.
    pub triangular: TriangularSolve,
}

/// The triangular solves of the sparse factor (docs/contact-solve.md §35). Both solve with
/// the same factor; only the order of the operations, and so the round-off, differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TriangularSolve {
    /// faer's supernodal solve (a dense triangular solve and a matrix product a supernode).
    Faer,
    /// The default. A copy of faer's supernodal factor made once per factorization, each supernode's rows
    /// below its diagonal block row-major, solved by loops unrolled on the supernode's width
    /// (`solve::repacked`). A simplicial factor is still solved by faer.
    #[default]
    Repacked,
}

/// Fill-reducing orderings of the sparse factorization. The scalar and the block orderings
/// factor the same matrix; only the order of elimination, the fill and so the round-off differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SparseOrdering {
    /// faer's approximate minimum degree on the scalar unknowns' graph (the ordering of every
    /// session before 35).
    #[default]
    ScalarAmd,
    /// Approximate minimum degree on the block graph (one node per block, its unknowns kept
    /// together): an ordering graph 3–6× smaller, and supernodes aligned with blocks.
    BlockAmd,
    /// Nested dissection of the block graph by breadth-first level sets
    /// (`solve::dissection`), parts of at most [`SparseParams::dissection_leaf`] blocks and the
    /// separators by block minimum degree: the O(n^1.5) factorization work of a 2D graph.
    BlockDissection,
    /// Nested dissection of the block graph by straight cuts at the median of the blocks'
    /// initial positions (`Dofs::position`, `solve::dissection::coordinate_dissection`), parts
    /// of at most [`SparseParams::dissection_leaf`] blocks and the separators by block minimum
    /// degree. Without positions (a system not numbered from a scene) as `BlockDissection`.
    BlockCoordinates,
}

/// Supernode amalgamation of faer's symbolic factorization.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SupernodeRelax {
    /// faer's default thresholds: merge when the merged supernode has ≤ 4 columns, or ≤ 16
    /// and < 80 % zeros, ≤ 48 and < 10 %, any size and < 5 %.
    #[default]
    Faer,
    /// No amalgamation: fundamental supernodes only.
    None,
    /// Twice faer's sizes and zero fractions ([`WIDE_RELAX`]): wider dense blocks, more
    /// explicit zeros.
    Wide,
}

/// See [`SupernodeRelax::Wide`].
const WIDE_RELAX: &[(usize, f64)] = &[(8, 1.0), (32, 0.8), (96, 0.2), (usize::MAX, 0.1)];

impl SupernodeRelax {
    fn params(self) -> SymbolicSupernodalParams<'static> {
        match self {
            SupernodeRelax::Faer => SymbolicSupernodalParams::default(),
            SupernodeRelax::None => SymbolicSupernodalParams { relax: None },
            SupernodeRelax::Wide => SymbolicSupernodalParams {
                relax: Some(WIDE_RELAX),
            },
        }
    }
}

impl Default for SparseParams {
    fn default() -> Self {
        Self {
            supernodal: true,
            max_reuse_iterations: 8,
            reuse_tolerance: 1e-12,
            check_reuse: false,
            factor_work_weight: FACTOR_WORK_WEIGHT,
            cost_rule_min_work: COST_RULE_MIN_WORK,
            reuse_learning_rate: 0.25,
            reuse_forget_rate: 0.1,
            start_check_samples: 2,
            start_check_margin: 10.0,
            start_check_audit: false,
            ordering: SparseOrdering::ScalarAmd,
            dissection_leaf: 8,
            low_rank_max_rank: 0,
            relax: SupernodeRelax::Faer,
            triangular: TriangularSolve::Repacked,
        }
    }
}

/// See [`SparseParams::factor_work_weight`].
/// The measured fit is 0.57 at 410 stones (5.65 M instructions a factorization over 1.295e6
/// multiply–adds, 0.78 M a solve pair over 1.011e5) and 0.44 at 1620 (35.3 M over 1.386e7,
/// 3.43 M over 5.966e5: the solves' wider supernodes run faster there); 0.55 fits the 410-stone
/// wall, where the rule changes decisions, and at 1620 overestimates the break-even (more
/// reuse, the rule before).
const FACTOR_WORK_WEIGHT: f64 = 0.55;
/// See [`SparseParams::cost_rule_min_work`]: between the 105-stone wall (7.4e4 with the
/// weight above) and the 410-stone wall (7.1e5); the engine and regression tests' walls of
/// ≤ 100 blocks are below it (the 1000-block extremes are above).
const COST_RULE_MIN_WORK: f64 = 2e5;

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("n", &self.n)
            .field("symbolic_count", &self.symbolic_count)
            .finish()
    }
}

/// The block graph of the pattern: per block, its coupled blocks (from the upper-triangle
/// column lists, both directions).
fn block_graph(col_blocks: &[Vec<(usize, Option<usize>)>]) -> Vec<Vec<usize>> {
    let mut adj = vec![Vec::new(); col_blocks.len()];
    for (b, col) in col_blocks.iter().enumerate() {
        for &(a, slot) in col {
            if slot.is_some() {
                adj[a].push(b);
                adj[b].push(a);
            }
        }
    }
    adj
}

/// faer's approximate minimum degree on the subgraph of `adj` induced by `nodes`; returns
/// `nodes` in elimination order.
fn amd_order(adj: &[Vec<usize>], nodes: &[usize]) -> Result<Vec<usize>, SolveError> {
    let m = nodes.len();
    if m <= 1 {
        return Ok(nodes.to_vec());
    }
    let mut local = vec![usize::MAX; adj.len()];
    for (k, &v) in nodes.iter().enumerate() {
        local[v] = k;
    }
    // Upper triangle (row < column), sorted, of the induced subgraph.
    let (mut col_ptr, mut row_idx) = (vec![0], Vec::new());
    for &v in nodes {
        let j = local[v];
        let start = row_idx.len();
        row_idx.extend(
            adj[v]
                .iter()
                .map(|&w| local[w])
                .filter(|&i| i != usize::MAX && i < j),
        );
        row_idx[start..].sort_unstable();
        let mut kept = start;
        for r in start..row_idx.len() {
            if kept == start || row_idx[r] != row_idx[kept - 1] {
                row_idx[kept] = row_idx[r];
                kept += 1;
            }
        }
        row_idx.truncate(kept);
        col_ptr.push(row_idx.len());
    }
    let a = SymbolicSparseColMatRef::new_checked(m, m, &col_ptr, None, &row_idx);
    let (mut perm, mut perm_inv) = (vec![0usize; m], vec![0usize; m]);
    let mut mem = MemBuffer::new(amd::order_scratch::<usize>(m, row_idx.len()));
    amd::order(
        &mut perm,
        &mut perm_inv,
        a,
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| SolveError::Backend(format!("{e:?}")))?;
    Ok(perm.iter().map(|&k| nodes[k]).collect())
}

impl SparseCholesky {
    fn rebuild_pattern(
        &mut self,
        sys: &BlockSystem,
        dofs: &Dofs,
        params: &SparseParams,
    ) -> Result<(), SolveError> {
        let supernodal = params.supernodal;
        let nf = dofs.ndof.len();
        self.col_blocks = vec![Vec::new(); nf];
        for b in 0..nf {
            self.col_blocks[b].push((b, None));
        }
        for (k, &(a, b)) in sys.pairs.iter().enumerate() {
            self.col_blocks[b].push((a, Some(k)));
        }
        for cb in &mut self.col_blocks {
            cb.sort_unstable_by_key(|e| e.0);
        }
        self.col_ptr.clear();
        self.row_idx.clear();
        self.col_ptr.push(0);
        for b in 0..nf {
            for c in 0..dofs.ndof[b] {
                for &(a, _) in &self.col_blocks[b] {
                    let rows = if a == b { c + 1 } else { dofs.ndof[a] };
                    for r in 0..rows {
                        self.row_idx.push(dofs.offset[a] + r);
                    }
                }
                self.col_ptr.push(self.row_idx.len());
            }
        }
        let n = dofs.n;
        let symb = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let block_order = match params.ordering {
            SparseOrdering::ScalarAmd => None,
            SparseOrdering::BlockAmd => {
                let adj = block_graph(&self.col_blocks);
                Some(amd_order(&adj, &(0..nf).collect::<Vec<_>>())?)
            }
            SparseOrdering::BlockDissection | SparseOrdering::BlockCoordinates => {
                let adj = block_graph(&self.col_blocks);
                let mut failed = None;
                let mut leaf_order = |part: &[usize]| {
                    amd_order(&adj, part).unwrap_or_else(|e| {
                        failed = Some(e);
                        part.to_vec()
                    })
                };
                let leaf = params.dissection_leaf;
                let order = if params.ordering == SparseOrdering::BlockCoordinates
                    && dofs.position.len() == nf
                {
                    coordinate_dissection(&adj, &dofs.position, leaf, &mut leaf_order)
                } else {
                    nested_dissection(&adj, leaf, &mut leaf_order)
                };
                if let Some(e) = failed {
                    return Err(e);
                }
                Some(order)
            }
        };
        // Each block's unknowns stay together, in the blocks' order.
        let perm = block_order.map(|order| {
            let fwd: Vec<usize> = order
                .iter()
                .flat_map(|&b| dofs.offset[b]..dofs.offset[b] + dofs.ndof[b])
                .collect();
            let mut inv = vec![0; n];
            for (k, &i) in fwd.iter().enumerate() {
                inv[i] = k;
            }
            (fwd, inv)
        });
        let ordering = match &perm {
            None => SymmetricOrdering::Amd,
            Some((fwd, inv)) => SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, n)),
        };
        let symbolic = factorize_symbolic_cholesky(
            symb,
            Side::Upper,
            ordering,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: if supernodal {
                    SupernodalThreshold::FORCE_SUPERNODAL
                } else {
                    SupernodalThreshold::AUTO
                },
                supernodal_params: params.relax.params(),
                ..Default::default()
            },
        )
        .map_err(|e| SolveError::Backend(format!("{e:?}")))?;
        self.l_values = vec![0.0; symbolic.len_val()];
        self.repacked.invalidate();
        self.cost = FactorCost::of(&symbolic, self.row_idx.len(), params.factor_work_weight);
        self.factored = false;
        let req = symbolic
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        self.mem = Some(MemBuffer::new(req));
        self.symbolic = Some(symbolic);
        self.pattern.clone_from(&sys.pairs);
        self.n = n;
        self.symbolic_count += 1;
        Ok(())
    }

    /// Copy the system's blocks into the compressed upper triangle `values` (column by
    /// column, as `rebuild_pattern` laid it out). With `track_changes` (a factor of the same
    /// pattern exists) it also notes, per off-diagonal slot, the largest change of an entry
    /// since the factored values and the largest entry, for [`SparseCholesky::major_changes`]:
    /// one pass over the values instead of two. Not inlined: inlined into `factor_solve` it
    /// compiled to 1 % more instructions (callgrind, docs/contact-solve.md §15).
    ///
    /// Block by block (session 41): each block's entries are copied where its columns put them
    /// (entry r of column c of the block at `col_ptr` of that column + the rows of the blocks
    /// above it), so a slot's change maxima are kept in registers over its whole block and a
    /// rigid pair's 3 × 3 copy unrolls; the maxima are taken over the same entries in the same
    /// order (column by column) as the column-by-column pass did, and a maximum of |·| values
    /// does not round: `change` is the same to the bit (docs/contact-solve.md §31).
    #[inline(never)]
    fn fill_values(&mut self, sys: &BlockSystem, dofs: &Dofs, track_changes: bool) {
        self.values.resize(self.row_idx.len(), 0.0);
        if track_changes {
            self.change.clear();
            self.change.resize(sys.pairs.len(), [0.0; 2]);
        }
        let values = &mut self.values[..];
        let old_values = &self.factored_values[..];
        for (b, col_blocks) in self.col_blocks.iter().enumerate() {
            let nc = dofs.ndof[b];
            let cols = &self.col_ptr[dofs.offset[b]..dofs.offset[b] + nc];
            // Rows of the blocks above this one in each of the block's columns.
            let mut above = 0;
            for &(a, slot) in col_blocks {
                match slot {
                    None => {
                        // The diagonal block, last in its columns: rows 0..=c of column c.
                        let src = sys.diag[b].as_slice();
                        for (c, &start) in cols.iter().enumerate() {
                            let at = start + above;
                            values[at..at + c + 1].copy_from_slice(&src[6 * c..6 * c + c + 1]);
                        }
                    }
                    Some(k) => {
                        let nr = dofs.ndof[a];
                        let src = sys.off[k].as_slice();
                        if track_changes {
                            let [mut delta, mut size] = self.change[k];
                            let mut note = |at: usize, new: &[f64]| {
                                let dst = &mut values[at..at + new.len()];
                                let old = &old_values[at..at + new.len()];
                                for ((d, &new), &old) in dst.iter_mut().zip(new).zip(old) {
                                    *d = new;
                                    delta = delta.max((new - old).abs());
                                    size = size.max(new.abs()).max(old.abs());
                                }
                            };
                            if nr == 3 && nc == 3 {
                                // A rigid pair: constant sizes, the loops unroll.
                                for (c, &start) in cols.iter().enumerate() {
                                    note(start + above, &src[6 * c..6 * c + 3]);
                                }
                            } else {
                                for (c, &start) in cols.iter().enumerate() {
                                    note(start + above, &src[6 * c..6 * c + nr]);
                                }
                            }
                            self.change[k] = [delta, size];
                        } else {
                            for (c, &start) in cols.iter().enumerate() {
                                let at = start + above;
                                values[at..at + nr].copy_from_slice(&src[6 * c..6 * c + nr]);
                            }
                        }
                        above += nr;
                    }
                }
            }
        }
    }

    pub fn factor_solve(
        &mut self,
        sys: &BlockSystem,
        dofs: &Dofs,
        x: &mut [f64],
        params: &SparseParams,
    ) -> Result<(), SolveError> {
        if self.symbolic.is_none() || self.pattern != sys.pairs || self.n != dofs.n {
            self.rebuild_pattern(sys, dofs, params)?;
        }
        self.triangular = params.triangular;
        let try_reuse = self.factored && params.max_reuse_iterations > 0;
        self.fill_values(sys, dofs, try_reuse);
        if self.factored && params.low_rank_max_rank > 0 && self.low_rank_solve(x, params) {
            return Ok(());
        }
        let predicted = if try_reuse { self.major_changes() } else { 0 };
        if try_reuse && predicted < params.max_reuse_iterations {
            if !self.reuse_pays(predicted, params) {
                self.reuse_table[predicted.min(REUSE_TABLE_LEN - 1)][3] += 1;
            } else {
                let rhs = params.check_reuse.then(|| x.to_vec());
                let before = self.reuse_iterations;
                let converged = self.reuse_solve(x, params);
                self.learn(predicted, self.reuse_iterations - before, converged, params);
                if converged {
                    if let Some(mut fresh) = rhs {
                        self.check_against_fresh(sys, dofs, x, &mut fresh)?;
                    }
                    return Ok(());
                }
            }
        }
        self.factorize(sys, dofs)?;
        self.factor_solve_in_place(x)
    }

    /// Solve with the last factor corrected for the exact change of the matrix since it was
    /// made ([`SparseParams::low_rank_max_rank`]). The change D = K' − K (the entries that
    /// differ, on the unknowns they touch) is decomposed D = V Λ Vᵀ, keeping the eigenvalues
    /// above round-off; with U = the rows of V placed on those unknowns, Woodbury's identity
    /// gives K'⁻¹b = y − Z (Λ⁻¹ + Uᵀ Z)⁻¹ Uᵀ y with y = K⁻¹ b and Z = K⁻¹ U (one solve of
    /// 1 + rank right-hand sides with the old factor). The residual with K' is then corrected
    /// through the same inverse ([`LOW_RANK_REFINEMENTS`] at most) until the correction is
    /// within `reuse_tolerance` of the largest unknown (the reused-factor solve's criterion).
    /// Returns false with `x` unchanged when the change is too large or the check fails.
    fn low_rank_solve(&mut self, x: &mut [f64], params: &SparseParams) -> bool {
        let n = self.n;
        let max_rank = params.low_rank_max_rank;
        let max_support = LOW_RANK_SUPPORT_PER_RANK * max_rank;
        let lr = &mut self.low_rank;
        lr.local.resize(n, usize::MAX);
        lr.support.clear();
        lr.entries.clear();
        // The changed entries and the unknowns they touch; stop as soon as the support
        // exceeds the bound (a step's drift changes every entry: this ends in a few columns).
        let mut fits = true;
        'columns: for j in 0..n {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let d = self.values[p] - self.factored_values[p];
                if d == 0.0 {
                    continue;
                }
                let i = self.row_idx[p];
                if !d.is_finite() {
                    fits = false;
                    break 'columns;
                }
                for v in [i, j] {
                    if lr.local[v] == usize::MAX {
                        if lr.support.len() == max_support {
                            fits = false;
                            break 'columns;
                        }
                        lr.local[v] = lr.support.len();
                        lr.support.push(v);
                    }
                }
                lr.entries.push((lr.local[i], lr.local[j], d));
            }
        }
        for &v in &lr.support {
            lr.local[v] = usize::MAX;
        }
        if !fits {
            self.low_rank_declined += 1;
            return false;
        }
        let m = lr.support.len();
        if m == 0 {
            // The very matrix factored: its factor's solve is the fresh factorization's.
            self.low_rank_solves += 1;
            return self.factor_solve_in_place(x).is_ok();
        }
        let mut d = DMatrix::<f64>::zeros(m, m);
        for &(i, j, v) in &lr.entries {
            d[(i, j)] = v;
            d[(j, i)] = v;
        }
        // Eigen-decomposition of the change (symmetric); None only without convergence.
        let Some(eig) = SymmetricEigen::try_new(d, f64::EPSILON, 10_000) else {
            self.low_rank_declined += 1;
            return false;
        };
        let largest = eig.eigenvalues.amax();
        lr.kept.clear();
        lr.kept
            .extend((0..m).filter(|&k| eig.eigenvalues[k].abs() > LOW_RANK_DROP * largest));
        let kept = &lr.kept;
        let r = kept.len();
        if r > max_rank {
            self.low_rank_declined += 1;
            self.low_rank_declined_rank += 1;
            self.low_rank_declined_cube += (m as f64).powi(3);
            return false;
        }
        let (Some(symbolic), Some(mem1)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return false;
        };
        if lr.mem_cols < max_rank + 1 {
            lr.mem = Some(MemBuffer::new(
                symbolic.solve_in_place_scratch::<f64>(max_rank + 1, Par::Seq),
            ));
            lr.mem_cols = max_rank + 1;
        }
        let Some(mem) = lr.mem.as_mut() else {
            return false;
        };
        let llt = LltRef::new(symbolic, &self.l_values);
        // Column 0: b; column 1 + k: U_k = eigenvector k on the support's unknowns.
        lr.cols.clear();
        lr.cols.resize(n * (r + 1), 0.0);
        lr.cols[..n].copy_from_slice(x);
        for (c, &k) in kept.iter().enumerate() {
            let col = &mut lr.cols[n * (c + 1)..n * (c + 2)];
            for (s, &v) in lr.support.iter().enumerate() {
                col[v] = eig.eigenvectors[(s, k)];
            }
        }
        let rhs = faer::MatMut::from_column_major_slice_mut(&mut lr.cols, n, r + 1);
        llt.solve_in_place_with_conj(faer::Conj::No, rhs, Par::Seq, MemStack::new(mem));
        // Capacitance C = Λ⁻¹ + Uᵀ Z (r × r; indefinite when springs opened: LU).
        let z = |c: usize, row: usize| lr.cols[n * (c + 1) + row];
        let mut cap = DMatrix::<f64>::zeros(r, r);
        for (a, &ka) in kept.iter().enumerate() {
            cap[(a, a)] = 1.0 / eig.eigenvalues[ka];
            for c in 0..r {
                cap[(a, c)] += lr
                    .support
                    .iter()
                    .enumerate()
                    .map(|(s, &v)| eig.eigenvectors[(s, ka)] * z(c, v))
                    .sum::<f64>();
            }
        }
        let lu = cap.lu();
        // y ← y − Z C⁻¹ Uᵀ y for a y solved with the old factor; None if C is singular.
        let correct = |y: &mut [f64], cols: &[f64]| -> Option<()> {
            let t = DVector::<f64>::from_iterator(
                r,
                kept.iter().map(|&k| {
                    lr.support
                        .iter()
                        .enumerate()
                        .map(|(s, &v)| eig.eigenvectors[(s, k)] * y[v])
                        .sum::<f64>()
                }),
            );
            let w = lu.solve(&t)?;
            for (c, wc) in w.iter().enumerate() {
                let zc = &cols[n * (c + 1)..n * (c + 2)];
                for (yi, zi) in y.iter_mut().zip(zc) {
                    *yi -= wc * zi;
                }
            }
            Some(())
        };
        self.b.clear();
        self.b.extend_from_slice(x);
        let sol = &mut lr.sol;
        sol.clear();
        sol.extend_from_slice(&lr.cols[..n]);
        if correct(sol, &lr.cols).is_none() {
            self.low_rank_failed += 1;
            return false;
        }
        for _ in 0..LOW_RANK_REFINEMENTS {
            symmetric_upper_matvec(
                &self.col_ptr,
                &self.row_idx,
                &self.values,
                sol,
                &mut self.ap,
            );
            lr.residual.clear();
            lr.residual
                .extend(self.b.iter().zip(&self.ap).map(|(b, ax)| b - ax));
            let res = faer::MatMut::from_column_major_slice_mut(&mut lr.residual, n, 1);
            llt.solve_in_place_with_conj(faer::Conj::No, res, Par::Seq, MemStack::new(mem1));
            if correct(&mut lr.residual, &lr.cols).is_none() {
                break;
            }
            for (s, dx) in sol.iter_mut().zip(&lr.residual) {
                *s += dx;
            }
            let (err, scale) = (max_abs(&lr.residual), max_abs(sol));
            if !(err.is_finite() && scale.is_finite()) {
                break;
            }
            if err <= params.reuse_tolerance * scale {
                x.copy_from_slice(sol);
                self.low_rank_solves += 1;
                self.low_rank_rank += r as u64;
                return true;
            }
        }
        self.low_rank_failed += 1;
        false
    }

    /// Cost model of the current factor.
    pub fn cost(&self) -> FactorCost {
        self.cost
    }

    /// `x ← (L Lᵀ)⁻¹ x` with the current factor.
    fn factor_solve_in_place(&mut self, x: &mut [f64]) -> Result<(), SolveError> {
        let repacked = self.ensure_repacked();
        let (Some(symbolic), Some(mem)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return Err(SolveError::NoSymbolic);
        };
        if repacked {
            self.repacked.solve(x);
            return Ok(());
        }
        let llt = LltRef::new(symbolic, &self.l_values);
        let rhs = faer::MatMut::from_column_major_slice_mut(x, self.n, 1);
        llt.solve_in_place_with_conj(faer::Conj::No, rhs, Par::Seq, MemStack::new(mem));
        Ok(())
    }

    /// With [`TriangularSolve::Repacked`], make the repacked copy of the current factor if it
    /// is not made yet; returns whether the solves go through it (false for faer's solve, and
    /// for a simplicial factor, which faer solves).
    fn ensure_repacked(&mut self) -> bool {
        if self.triangular != TriangularSolve::Repacked || !self.factored {
            return false;
        }
        if !self.repacked.is_built() {
            let Some(symbolic) = self.symbolic.as_ref() else {
                return false;
            };
            if !self.repacked.build(symbolic, &self.l_values) {
                return false;
            }
            self.repack_count += 1;
        }
        true
    }

    /// About the rank of the change of the matrix since its last factorization (from the
    /// changes `fill_values` noted), which is
    /// about the number of conjugate-gradient iterations the reused factor needs: the number
    /// of off-diagonal blocks that changed by more than [`MAJOR_CHANGE`] of their size (each is
    /// at least one spring opened, closed or switched between stick and slip). Small changes
    /// of every block (the geometry and Δt drifting from step to step) are not counted: they
    /// keep the factor a good preconditioner. When the count reaches
    /// [`SparseParams::max_reuse_iterations`] the iteration cannot converge in time, and
    /// trying costs more than a factorization (the pile of examples/pile.rs spent 55 % of its
    /// solve time in such failed attempts: docs/pile.md).
    fn major_changes(&self) -> usize {
        self.change
            .iter()
            .filter(|[delta, size]| *delta > MAJOR_CHANGE * size)
            .count()
    }

    /// Whether to try the last factor on a change of `predicted` major blocks (below the
    /// hard cap [`SparseParams::max_reuse_iterations`]): when the factorization costs less
    /// than [`SparseParams::cost_rule_min_work`], always (the rule before session 34);
    /// otherwise when the expected cost of the attempt, in CG iterations beyond its start,
    /// is below the break-even of this factor's size ([`FactorCost::break_even`]). The
    /// expectation starts at the predicted count (each changed block about one iteration) and
    /// learns from the attempts (`learn`); while the rule refactors, it drifts back to that
    /// prior at [`SparseParams::reuse_forget_rate`], so a prediction is retried now and then.
    fn reuse_pays(&mut self, predicted: usize, params: &SparseParams) -> bool {
        if self.cost.factor < params.cost_rule_min_work {
            return true;
        }
        let k = predicted.min(REUSE_TABLE_LEN - 1);
        if self.expected.is_empty() {
            self.expected = (0..REUSE_TABLE_LEN).map(|p| p as f64).collect();
        }
        if self.expected[k] < self.cost.break_even() {
            return true;
        }
        self.expected[k] += params.reuse_forget_rate * (k as f64 - self.expected[k]);
        false
    }

    /// Note an attempt on a change of `predicted` major blocks that took `iterations` CG
    /// iterations and converged or not: its cost in iterations beyond the start (a failure
    /// adds the factorization and solve pair it falls back to, and the start it wasted) joins
    /// the running average of that prediction.
    fn learn(&mut self, predicted: usize, iterations: u64, converged: bool, params: &SparseParams) {
        let k = predicted.min(REUSE_TABLE_LEN - 1);
        let row = &mut self.reuse_table[k];
        row[0] += 1;
        row[1] += iterations;
        row[2] += u64::from(!converged);
        if self.expected.is_empty() {
            return;
        }
        let c = self.cost;
        let mut spent = iterations as f64;
        if !converged {
            spent += (c.factor + c.pair) / c.iteration();
        }
        self.expected[k] += params.reuse_learning_rate * (spent - self.expected[k]);
    }

    /// Solve the system with the right-hand side `fresh` by a fresh factorization, compare
    /// with the reused-factor solution `x`, and restore the reused factor (so a checked run
    /// takes the same path as an unchecked one).
    fn check_against_fresh(
        &mut self,
        sys: &BlockSystem,
        dofs: &Dofs,
        x: &[f64],
        fresh: &mut [f64],
    ) -> Result<(), SolveError> {
        let kept = (
            self.l_values.clone(),
            self.factored_values.clone(),
            self.numeric_count,
        );
        self.factorize(sys, dofs)?;
        self.factor_solve_in_place(fresh)?;
        let scale = max_abs(fresh);
        let diff = x
            .iter()
            .zip(fresh.iter())
            .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        if scale > 0.0 {
            self.reuse_max_error = self.reuse_max_error.max(diff / scale);
        }
        (self.l_values, self.factored_values, self.numeric_count) = kept;
        self.repacked.invalidate();
        Ok(())
    }

    /// Numeric factorization of the current values into `l_values`.
    fn factorize(&mut self, sys: &BlockSystem, dofs: &Dofs) -> Result<(), SolveError> {
        let (Some(symbolic), Some(mem)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return Err(SolveError::NoSymbolic);
        };
        let n = self.n;
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx),
            &self.values,
        );
        self.factored = false;
        self.repacked.invalidate();
        symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                a,
                Side::Upper,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(mem),
                Default::default(),
            )
            .map_err(|_| SolveError::NotPositiveDefinite {
                dof: first_bad_pivot(sys, dofs),
            })?;
        self.factored = true;
        self.start_ratio = 0.0;
        self.start_samples = 0;
        self.factored_values.clone_from(&self.values);
        self.numeric_count += 1;
        Ok(())
    }

    /// Conjugate gradients on the current values, preconditioned by the last factor. On
    /// success `x` (the right-hand side on entry) holds the solution; on failure (no
    /// convergence, or a breakdown that signals an indefinite matrix) `x` is restored and the
    /// caller refactors.
    fn reuse_solve(&mut self, x: &mut [f64], params: &SparseParams) -> bool {
        let n = self.n;
        let use_repacked = self.ensure_repacked();
        let (Some(symbolic), Some(mem)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return false;
        };
        let llt = LltRef::new(symbolic, &self.l_values);
        let repacked = &mut self.repacked;
        let mut precondition = |v: &mut [f64]| {
            if use_repacked {
                repacked.solve(v);
            } else {
                let m = faer::MatMut::from_column_major_slice_mut(v, n, 1);
                llt.solve_in_place_with_conj(faer::Conj::No, m, Par::Seq, MemStack::new(mem));
            }
        };
        self.b.clear();
        self.b.extend_from_slice(x);
        precondition(x);
        symmetric_upper_matvec(&self.col_ptr, &self.row_idx, &self.values, x, &mut self.ap);
        self.r.clear();
        self.r
            .extend(self.b.iter().zip(&self.ap).map(|(b, ax)| b - ax));
        let sampling = params.start_check_samples > 0;
        if sampling && self.start_samples >= params.start_check_samples {
            let (scale, res) = (max_abs(x), max_abs(&self.r));
            if scale.is_finite()
                && res.is_finite()
                && params.start_check_margin * self.start_ratio * res
                    <= params.reuse_tolerance * scale
            {
                self.start_skips += 1;
                if params.start_check_audit {
                    self.z.clone_from(&self.r);
                    precondition(&mut self.z);
                    let err = max_abs(&self.z);
                    if !(err <= params.reuse_tolerance * scale || err == 0.0) {
                        self.start_check_misses += 1;
                    }
                }
                return true;
            }
        }
        self.z.clone_from(&self.r);
        precondition(&mut self.z);
        if sampling {
            let res = max_abs(&self.r);
            let ratio = max_abs(&self.z) / res;
            if res > 0.0 && ratio.is_finite() {
                self.start_ratio = self.start_ratio.max(ratio);
                self.start_samples += 1;
            }
        }
        self.p.clone_from(&self.z);
        let mut rz = dot(&self.r, &self.z);
        for _ in 0..params.max_reuse_iterations {
            let scale = max_abs(x);
            let err = max_abs(&self.z);
            if !(err.is_finite() && scale.is_finite()) {
                break;
            }
            if err <= params.reuse_tolerance * scale || err == 0.0 {
                return true;
            }
            self.reuse_iterations += 1;
            symmetric_upper_matvec(
                &self.col_ptr,
                &self.row_idx,
                &self.values,
                &self.p,
                &mut self.ap,
            );
            let pap = dot(&self.p, &self.ap);
            if !(pap > 0.0 && pap.is_finite()) {
                break;
            }
            let alpha = rz / pap;
            for i in 0..n {
                x[i] += alpha * self.p[i];
                self.r[i] -= alpha * self.ap[i];
            }
            self.z.clone_from(&self.r);
            precondition(&mut self.z);
            let rz_new = dot(&self.r, &self.z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                self.p[i] = self.z[i] + beta * self.p[i];
            }
        }
        x.copy_from_slice(&self.b);
        false
    }
}

/// y = A·x for a symmetric matrix stored as its upper triangle in compressed columns, each
/// column's diagonal entry last (as `rebuild_pattern` lays them out: row blocks in increasing
/// order, the diagonal block last with rows 0..=c). Same operations in the same order as a
/// loop that tests `i != j` on every entry, without the test.
fn symmetric_upper_matvec(
    col_ptr: &[usize],
    row_idx: &[usize],
    values: &[f64],
    x: &[f64],
    y: &mut Vec<f64>,
) {
    y.clear();
    y.resize(x.len(), 0.0);
    for (j, (&xj, ends)) in x.iter().zip(col_ptr.windows(2)).enumerate() {
        let (rows, vals) = (&row_idx[ends[0]..ends[1]], &values[ends[0]..ends[1]]);
        let Some((&diag, below)) = vals.split_last() else {
            continue;
        };
        let mut acc = 0.0;
        for (&i, &v) in rows.iter().zip(below) {
            y[i] += v * xj;
            acc += v * x[i];
        }
        y[j] += diag * xj;
        y[j] += acc;
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
}

/// Best effort at naming the unknown behind a failed factorization: the first non-positive
/// diagonal entry, else 0.
fn first_bad_pivot(sys: &BlockSystem, dofs: &Dofs) -> usize {
    for (f, d) in sys.diag.iter().enumerate() {
        for k in 0..dofs.ndof[f] {
            if d[(k, k)].is_nan() || d[(k, k)] <= 0.0 {
                return dofs.offset[f] + k;
            }
        }
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Mat6, Vec6};

    /// A block system of `nb` rigid blocks on a grid `cols` wide, each coupled to its right and
    /// upper neighbours (the pattern of a wall): diagonally dominant, so positive definite.
    fn grid_system(nb: usize, cols: usize) -> (BlockSystem, Dofs) {
        let mut dofs = Dofs::default();
        for b in 0..nb {
            dofs.free_index.push(Some(b));
            dofs.block_of.push(b);
            dofs.ndof.push(3);
            dofs.offset.push(3 * b);
        }
        dofs.n = 3 * nb;
        // Deterministic pseudo-random entries in [-1, 1).
        let mut seed = 12345_u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut sys = BlockSystem::default();
        for b in 0..nb {
            for n in [b + 1, b + cols] {
                if n < nb && (n != b + 1 || n % cols != 0) {
                    sys.pairs.push((b, n));
                }
            }
        }
        sys.pairs.sort_unstable();
        for _ in &sys.pairs {
            let mut m = Mat6::zeros();
            for c in 0..3 {
                for r in 0..3 {
                    m[(r, c)] = next();
                }
            }
            sys.off.push(m);
        }
        for _ in 0..nb {
            let mut m = Mat6::zeros();
            for c in 0..3 {
                for r in 0..c {
                    let v = 0.5 * next();
                    m[(r, c)] = v;
                    m[(c, r)] = v;
                }
                m[(c, c)] = 20.0 + next();
            }
            sys.diag.push(m);
            let mut r = Vec6::zeros();
            for k in 0..3 {
                r[k] = next();
            }
            sys.rhs.push(r);
        }
        (sys, dofs)
    }

    /// `fill_values` as it was before session 41 (column by column, every block of a column in
    /// turn): the reference of its bit-identity test. Returns the values and the changes.
    fn fill_values_by_column(
        chol: &SparseCholesky,
        sys: &BlockSystem,
        dofs: &Dofs,
    ) -> (Vec<f64>, Vec<[f64; 2]>) {
        let mut values = vec![0.0; chol.row_idx.len()];
        let mut change = vec![[0.0_f64; 2]; sys.pairs.len()];
        let mut at = 0;
        for b in 0..dofs.ndof.len() {
            for c in 0..dofs.ndof[b] {
                for &(a, slot) in &chol.col_blocks[b] {
                    let (src, rows) = match slot {
                        None => (&sys.diag[b].as_slice()[6 * c..], c + 1),
                        Some(k) => (&sys.off[k].as_slice()[6 * c..], dofs.ndof[a]),
                    };
                    for r in 0..rows {
                        let (new, old) = (src[r], chol.factored_values[at + r]);
                        values[at + r] = new;
                        if let Some(k) = slot {
                            let [delta, size] = change[k];
                            change[k] = [
                                delta.max((new - old).abs()),
                                size.max(new.abs()).max(old.abs()),
                            ];
                        }
                    }
                    at += rows;
                }
            }
        }
        (values, change)
    }

    /// The block-by-block `fill_values` (session 41) gives the column-by-column copy's values
    /// and change maxima to the bit (tolerance 0: it is meant to do the same operations), on a
    /// rigid grid and on one with every third block deformable (6 unknowns: the general path).
    #[test]
    fn block_fill_equals_the_column_by_column_fill_to_the_bit() {
        for mixed in [false, true] {
            let (mut sys, mut dofs) = grid_system(60, 7);
            if mixed {
                let mut offset = 0;
                for f in 0..dofs.ndof.len() {
                    dofs.ndof[f] = if f % 3 == 1 { 6 } else { 3 };
                    dofs.offset[f] = offset;
                    offset += dofs.ndof[f];
                }
                dofs.n = offset;
                // Fill the 6-dof parts too (the grid filled only the leading 3 × 3).
                let mut v = 0.37;
                for m in sys.diag.iter_mut().chain(sys.off.iter_mut()) {
                    for e in m.iter_mut() {
                        if *e == 0.0 {
                            v = (v * 7.31 + 0.11) % 1.0;
                            *e = v - 0.5;
                        }
                    }
                }
            }
            let mut chol = SparseCholesky::default();
            chol.rebuild_pattern(&sys, &dofs, &SparseParams::default())
                .expect("pattern");
            chol.fill_values(&sys, &dofs, false);
            chol.factored_values.clone_from(&chol.values);
            for (k, m) in sys.off.iter_mut().enumerate() {
                if k % 4 == 0 {
                    *m *= 1.5;
                } else {
                    *m *= 1.0 + 1e-9 * k as f64;
                }
            }
            chol.fill_values(&sys, &dofs, true);
            let (values, change) = fill_values_by_column(&chol, &sys, &dofs);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&chol.values), bits(&values), "values, mixed {mixed}");
            assert_eq!(
                bits(&chol.change.concat()),
                bits(&change.concat()),
                "changes, mixed {mixed}"
            );
            assert!(chol.major_changes() > 0, "the test changes some blocks");
        }
    }

    fn rhs_of(sys: &BlockSystem, dofs: &Dofs) -> Vec<f64> {
        let mut b = vec![0.0; dofs.n];
        for (f, r) in sys.rhs.iter().enumerate() {
            for k in 0..3 {
                b[dofs.offset[f] + k] = r[k];
            }
        }
        b
    }

    fn max_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
    }

    /// The supernodal factorization solves the system (residual 1e-12 of the right-hand side,
    /// by the matrix-vector product of the conjugate gradients, whose operand layout this also
    /// checks); after a small change of every block (geometry drift: no major change) the next
    /// solve reuses the factor and gives the fresh factorization's answer within the reuse
    /// tolerance's order (1e-11 of the solution, as tests/engine/solver_reuse.rs).
    #[test]
    fn supernodal_solve_and_reuse_after_a_small_change() {
        let (mut sys, dofs) = grid_system(150, 10);
        let mut chol = SparseCholesky::default();
        let params = SparseParams::default();
        let b = rhs_of(&sys, &dofs);
        let mut x = b.clone();
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        let mut ax = Vec::new();
        symmetric_upper_matvec(&chol.col_ptr, &chol.row_idx, &chol.values, &x, &mut ax);
        assert!(max_diff(&ax, &b) <= 1e-12 * max_abs(&b), "residual");
        for m in sys.diag.iter_mut().chain(sys.off.iter_mut()) {
            *m *= 1.0 + 1e-4;
        }
        let mut reused = b.clone();
        chol.factor_solve(&sys, &dofs, &mut reused, &params)
            .expect("positive definite");
        assert_eq!(chol.numeric_count, 1, "the second solve reuses the factor");
        assert!(chol.reuse_iterations >= 1);
        let mut fresh_chol = SparseCholesky::default();
        let mut fresh = b.clone();
        fresh_chol
            .factor_solve(&sys, &dofs, &mut fresh, &params)
            .expect("positive definite");
        let d = max_diff(&reused, &fresh);
        assert!(d <= 1e-11 * max_abs(&fresh), "reuse differs by {d:e}");
    }

    /// A change of many coupling blocks by more than `MAJOR_CHANGE` (springs opening) is
    /// counted as such and refactors without trying the old factor.
    #[test]
    fn major_changes_refactor() {
        let (mut sys, dofs) = grid_system(150, 10);
        let mut chol = SparseCholesky::default();
        let params = SparseParams::default();
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        for m in sys.off.iter_mut().take(params.max_reuse_iterations) {
            *m *= 0.5;
        }
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert_eq!(chol.major_changes(), params.max_reuse_iterations);
        assert_eq!(chol.numeric_count, 2, "refactored");
        assert_eq!(chol.reuse_iterations, 0, "without trying the old factor");
    }

    /// The size-aware rule (on for any size: `cost_rule_min_work` 0). The break-even is the
    /// factor's own (start + b·iteration = factorization + pair, from its counted sizes); a
    /// change predicted to need at least b iterations refactors without trying the old factor,
    /// one predicted below it tries it, and an unchanged matrix (rest) reuses it with no
    /// iteration. The grid's break-even is checked to lie where both cases exist (1 < b < cap).
    #[test]
    fn cost_rule_refactors_above_the_break_even_and_reuses_at_rest() {
        let (mut sys, dofs) = grid_system(400, 20);
        let params = SparseParams {
            cost_rule_min_work: 0.0,
            ..Default::default()
        };
        let mut chol = SparseCholesky::default();
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        let c = chol.cost();
        let b = c.break_even();
        let by_hand = (c.factor + c.pair - c.start()) / c.iteration();
        assert_eq!(b, by_hand);
        assert!(
            b > 1.0 && b < (params.max_reuse_iterations - 1) as f64,
            "break-even {b} outside the test's range"
        );

        // Rest: the same matrix again reuses the factor with no iteration.
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert_eq!(chol.numeric_count, 1, "at rest the factor is reused");
        assert_eq!(chol.reuse_iterations, 0);
        assert_eq!(chol.reuse_table[0][0], 1, "one attempt at prediction 0");

        // A change of ⌈b⌉ coupling blocks: the prior expects ⌈b⌉ ≥ b iterations: refactor.
        let above = b.ceil() as usize;
        for m in sys.off.iter_mut().take(above) {
            *m *= 0.5;
        }
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert_eq!(chol.major_changes(), above);
        assert_eq!(chol.numeric_count, 2, "refactored above the break-even");
        assert_eq!(chol.reuse_table[above][3], 1, "by the cost rule");
        assert_eq!(chol.reuse_iterations, 0, "without trying the old factor");

        // A change of ⌈b⌉ − 1 < b blocks (since the last factorization) tries the old factor.
        let below = above - 1;
        for m in sys.off.iter_mut().skip(above).take(below) {
            *m *= 0.5;
        }
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert_eq!(chol.major_changes(), below);
        assert_eq!(chol.reuse_table[below][0], 1, "tried below the break-even");

        // The same change of ⌈b⌉ blocks with the rule off (the default's small-factor
        // path) tries the old factor: the rule, not the cap, refactored above.
        let mut old = SparseCholesky::default();
        let off = SparseParams {
            cost_rule_min_work: f64::INFINITY,
            ..Default::default()
        };
        let (mut sys, dofs) = grid_system(400, 20);
        let mut x = rhs_of(&sys, &dofs);
        old.factor_solve(&sys, &dofs, &mut x, &off)
            .expect("positive definite");
        for m in sys.off.iter_mut().take(above) {
            *m *= 0.5;
        }
        let mut x = rhs_of(&sys, &dofs);
        old.factor_solve(&sys, &dofs, &mut x, &off)
            .expect("positive definite");
        assert_eq!(old.reuse_table[above][0], 1, "the old rule tries");
    }

    /// Attempts that fail (the cap reached: the change is too large for the old factor) teach
    /// the rule to refactor that prediction: each failure costs its iterations plus the
    /// factorization and pair it falls back to (f = cap + (factorization + pair)/iteration),
    /// so from the prior 0 the running average after k failures is f·(1 − (1 − rate)^k), and
    /// the rule refactors without trying from the first k at which that reaches the
    /// break-even: exactly k failed attempts, then a skip.
    #[test]
    fn failed_attempts_teach_the_rule_to_refactor() {
        let (mut sys, dofs) = grid_system(400, 20);
        let params = SparseParams {
            cost_rule_min_work: 0.0,
            max_reuse_iterations: 2,
            ..Default::default()
        };
        let mut chol = SparseCholesky::default();
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        let c = chol.cost();
        let failure = params.max_reuse_iterations as f64 + (c.factor + c.pair) / c.iteration();
        let mut expected_failures = 0;
        let mut e = 0.0;
        while e < c.break_even() {
            e += params.reuse_learning_rate * (failure - e);
            expected_failures += 1;
        }
        assert!(
            expected_failures > 1,
            "the running average needs several failures"
        );
        // Every block changes by 10 %: no major change (prediction 0), but too much for
        // two iterations.
        let change = |sys: &mut BlockSystem| {
            for m in sys.diag.iter_mut() {
                *m *= 1.1;
            }
            for (k, m) in sys.off.iter_mut().enumerate() {
                *m *= if k % 2 == 0 { 1.1 } else { 1.0 / 1.1 };
            }
        };
        for _ in 0..expected_failures + 1 {
            change(&mut sys);
            let mut x = rhs_of(&sys, &dofs);
            chol.factor_solve(&sys, &dofs, &mut x, &params)
                .expect("positive definite");
            assert_eq!(chol.major_changes(), 0);
        }
        let [tries, _, failed, skipped] = chol.reuse_table[0];
        assert_eq!(
            tries, expected_failures,
            "attempts before the rule refactors"
        );
        assert_eq!(failed, tries, "every attempt failed");
        assert_eq!(skipped, 1, "then the rule refactors without trying");
        assert_eq!(chol.numeric_count, 1 + tries + skipped);
    }

    /// Add a spring of stiffness `k` along `g` (3 unknowns of block a, then 3 of block b)
    /// between the blocks of coupling `pair`: K += k g gᵀ on their unknowns, a rank-1 change
    /// (k < 0 removes it: a spring opening).
    fn add_spring(sys: &mut BlockSystem, pair: usize, g: [f64; 6], k: f64) {
        let (a, b) = sys.pairs[pair];
        for r in 0..3 {
            for c in 0..3 {
                sys.diag[a][(r, c)] += k * g[r] * g[c];
                sys.diag[b][(r, c)] += k * g[3 + r] * g[3 + c];
                sys.off[pair][(r, c)] += k * g[r] * g[3 + c];
            }
        }
    }

    /// The low-rank correction: after three springs changed since the factorization (two
    /// closed, one opened: a rank-3 change), the solve with the old factor and Woodbury's
    /// capacitance matrix equals a fresh factorization's solve to round-off (1e-12 of the
    /// largest unknown: a direct solve's round-off at this condition number, ≈ 10, is ~1e-15,
    /// and the refinement stops within `reuse_tolerance` 1e-12), with no new factorization, no
    /// CG iteration and rank 3 found from the changed entries. A drift of every block (a new
    /// step) is declined and takes the old path.
    #[test]
    fn low_rank_solve_equals_a_fresh_factorization() {
        let (mut sys, dofs) = grid_system(150, 10);
        let params = SparseParams {
            low_rank_max_rank: 8,
            ..Default::default()
        };
        let springs = [
            (3, [0.3, -0.8, 0.1, -0.3, 0.8, -0.2], 50.0),
            (40, [0.0, 1.0, 0.4, 0.0, -1.0, -0.4], 80.0),
            (41, [1.0, 0.0, 0.2, -1.0, 0.0, 0.5], 30.0),
        ];
        // The third spring is closed when the matrix is factored, and opens later.
        add_spring(&mut sys, springs[2].0, springs[2].1, springs[2].2);
        let mut chol = SparseCholesky::default();
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        add_spring(&mut sys, springs[0].0, springs[0].1, springs[0].2);
        add_spring(&mut sys, springs[1].0, springs[1].1, springs[1].2);
        add_spring(&mut sys, springs[2].0, springs[2].1, -springs[2].2);
        let b = rhs_of(&sys, &dofs);
        let mut low = b.clone();
        chol.factor_solve(&sys, &dofs, &mut low, &params)
            .expect("positive definite");
        assert_eq!(chol.low_rank_solves, 1, "solved by the correction");
        assert_eq!(chol.low_rank_rank, 3, "three springs changed");
        assert_eq!(chol.numeric_count, 1, "no new factorization");
        assert_eq!(chol.reuse_iterations, 0, "no CG iteration");
        let mut fresh = b.clone();
        SparseCholesky::default()
            .factor_solve(&sys, &dofs, &mut fresh, &SparseParams::default())
            .expect("positive definite");
        let d = max_diff(&low, &fresh);
        assert!(d <= 1e-12 * max_abs(&fresh), "low-rank differs by {d:e}");
        assert!(
            max_diff(&b, &fresh) > 1e-3 * max_abs(&fresh),
            "the system changed"
        );

        // Every block drifts (a new step): declined, solved the old way.
        for m in sys.diag.iter_mut().chain(sys.off.iter_mut()) {
            *m *= 1.0 + 1e-4;
        }
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert_eq!(chol.low_rank_declined, 1);
        assert_eq!(chol.low_rank_solves, 1);
        let mut fresh = rhs_of(&sys, &dofs);
        SparseCholesky::default()
            .factor_solve(&sys, &dofs, &mut fresh, &SparseParams::default())
            .expect("positive definite");
        assert!(max_diff(&x, &fresh) <= 1e-11 * max_abs(&fresh));
    }

    /// A grid as `grid_system` whose blocks have 3, 6, 1, 2, 4 and 5 unknowns in turn (a
    /// rigid, a deformable block, and other sizes so that supernodes of every width 1 to 8
    /// form), extra entries filled, diagonally dominant.
    fn mixed_grid(nb: usize, cols: usize) -> (BlockSystem, Dofs) {
        let (mut sys, mut dofs) = grid_system(nb, cols);
        let mut offset = 0;
        for f in 0..nb {
            dofs.ndof[f] = [3, 6, 1, 2, 4, 5][f % 6];
            dofs.offset[f] = offset;
            offset += dofs.ndof[f];
        }
        dofs.n = offset;
        let mut v = 0.37;
        let mut next = || {
            v = (v * 7.31 + 0.11) % 1.0;
            v - 0.5
        };
        for m in sys.off.iter_mut() {
            for c in 0..6 {
                for r in 0..6 {
                    if r >= 3 || c >= 3 {
                        m[(r, c)] = next();
                    }
                }
            }
        }
        for m in sys.diag.iter_mut() {
            for c in 3..6 {
                for r in 0..c {
                    let e = 0.5 * next();
                    m[(r, c)] = e;
                    m[(c, r)] = e;
                }
                m[(c, c)] = 20.0 + next();
            }
        }
        (sys, dofs)
    }

    /// A right-hand side with every unknown set (pseudo-random in [-1, 1)).
    fn full_rhs(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i * 7919 + 13) % 1000) as f64 / 500.0 - 1.0)
            .collect()
    }

    /// Gershgorin's bound on the condition number of the symmetric matrix stored as `chol`'s
    /// upper triangle: (max of dᵢ + Σ|offᵢ|) / (min of dᵢ − Σ|offᵢ|); None if the lower
    /// bound is not positive.
    fn gershgorin_condition(chol: &SparseCholesky) -> Option<f64> {
        let n = chol.n;
        let (mut diag, mut off) = (vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            for p in chol.col_ptr[j]..chol.col_ptr[j + 1] {
                let (i, v) = (chol.row_idx[p], chol.values[p]);
                if i == j {
                    diag[j] = v;
                } else {
                    off[i] += v.abs();
                    off[j] += v.abs();
                }
            }
        }
        let lo = (0..n)
            .map(|i| diag[i] - off[i])
            .fold(f64::INFINITY, f64::min);
        let hi = (0..n).map(|i| diag[i] + off[i]).fold(0.0, f64::max);
        (lo > 0.0).then(|| hi / lo)
    }

    /// Largest count of entries of a column of the supernodal factor (diagonal included).
    fn max_column_count(chol: &SparseCholesky) -> usize {
        let symbolic = chol.symbolic.as_ref().expect("factored");
        let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
            panic!("supernodal factor expected");
        };
        (0..s.n_supernodes())
            .map(|k| s.supernode_end()[k] - s.supernode_begin()[k] + s.supernode(k).pattern().len())
            .max()
            .unwrap_or(0)
    }

    /// Factor `sys` with faer, solve a full right-hand side by faer's triangular solves and
    /// by the repacked copy of the same factor. Returns the largest difference relative to
    /// the largest unknown, its round-off bound (see the test below) and the copy's supernode
    /// widths.
    fn repacked_against_faer(
        sys: &BlockSystem,
        dofs: &Dofs,
        params: &SparseParams,
    ) -> (f64, f64, [usize; super::super::repacked::MAX_UNROLLED + 1]) {
        let mut chol = SparseCholesky::default();
        chol.rebuild_pattern(sys, dofs, params).expect("pattern");
        chol.fill_values(sys, dofs, false);
        chol.factorize(sys, dofs).expect("positive definite");
        let b = full_rhs(dofs.n);
        let mut by_faer = b.clone();
        chol.triangular = TriangularSolve::Faer;
        chol.factor_solve_in_place(&mut by_faer).expect("solve");
        assert_eq!(chol.repack_count, 0, "faer's solve makes no copy");
        let mut repacked = b.clone();
        chol.triangular = TriangularSolve::Repacked;
        chol.factor_solve_in_place(&mut repacked).expect("solve");
        assert_eq!(chol.repack_count, 1, "one copy of the factor");
        let mut ax = Vec::new();
        symmetric_upper_matvec(
            &chol.col_ptr,
            &chol.row_idx,
            &chol.values,
            &repacked,
            &mut ax,
        );
        assert!(max_diff(&ax, &b) <= 1e-12 * max_abs(&b), "residual");
        let kappa = gershgorin_condition(&chol).expect("diagonally dominant");
        let c = max_column_count(&chol) as f64;
        let bound = 4.0 * c * (f64::EPSILON / 2.0) * kappa;
        let diff = max_diff(&repacked, &by_faer) / max_abs(&by_faer);
        (diff, bound, chol.repacked.width_counts())
    }

    /// The repacked triangular solves give faer's solution of the same factor to round-off, on
    /// rigid and mixed grids under every ordering and amalgamation. Tolerance: a triangular
    /// solve with L of at most c entries a column is backward stable, (L + δL) ŷ = b with
    /// |δL| ≤ γ_c |L| (γ_c ≈ c·u, Higham, Accuracy and Stability, Thm 8.5), so a solve pair's
    /// relative error is at most about 2·c·u·κ(A) to first order (|L||Lᵀ| ≈ |A| for these
    /// diagonally dominant matrices), and two such solutions differ by at most 4·c·u·κ(A); κ(A)
    /// is bounded by Gershgorin's discs and c is the factor's largest column count, both
    /// computed from the case. Every kernel width (1 to 8 and the general loop) must occur.
    #[test]
    fn repacked_solve_equals_faers_to_round_off() {
        let mut widths = [0; super::super::repacked::MAX_UNROLLED + 1];
        let mut check = |sys: &BlockSystem, dofs: &Dofs, params: SparseParams| {
            let (diff, bound, w) = repacked_against_faer(sys, dofs, &params);
            assert!(
                diff <= bound,
                "{:?} {:?} n {}: differs by {diff:e} (bound {bound:e})",
                params.ordering,
                params.relax,
                dofs.n
            );
            for (a, b) in widths.iter_mut().zip(w) {
                *a += b;
            }
        };
        let (sys, dofs) = grid_system(150, 10);
        check(&sys, &dofs, SparseParams::default());
        let (sys, dofs) = grid_system(1200, 30);
        for ordering in [
            SparseOrdering::ScalarAmd,
            SparseOrdering::BlockAmd,
            SparseOrdering::BlockDissection,
            SparseOrdering::BlockCoordinates,
        ] {
            for relax in [
                SupernodeRelax::Faer,
                SupernodeRelax::None,
                SupernodeRelax::Wide,
            ] {
                let params = SparseParams {
                    ordering,
                    relax,
                    ..Default::default()
                };
                check(&sys, &dofs, params);
            }
        }
        let (sys, dofs) = mixed_grid(300, 12);
        for ordering in [SparseOrdering::ScalarAmd, SparseOrdering::BlockDissection] {
            let params = SparseParams {
                ordering,
                ..Default::default()
            };
            check(&sys, &dofs, params);
        }
        assert!(
            widths.iter().all(|&w| w > 0),
            "every kernel width exercised: {widths:?}"
        );
    }

    /// Inside the solver: with `TriangularSolve::Repacked` the first solve, a reused-factor
    /// solve after a small change, a refactorization after a major change and a checked reuse
    /// (whose fresh factorization is undone) all solve their system (residual 1e-12 of the
    /// right-hand side; reuse within 1e-11 of a fresh solve, as the faer-solved tests above).
    /// A copy left from an older factor would fail the residual after the refactorization, or
    /// after the checked reuse (which restores the older factor under a copy of the fresh one).
    #[test]
    fn repacked_solver_keeps_its_copy_of_the_current_factor() {
        let (mut sys, dofs) = grid_system(150, 10);
        let params = SparseParams {
            triangular: TriangularSolve::Repacked,
            ..Default::default()
        };
        let mut chol = SparseCholesky::default();
        let residual = |chol: &SparseCholesky, x: &[f64], b: &[f64]| {
            let mut ax = Vec::new();
            symmetric_upper_matvec(&chol.col_ptr, &chol.row_idx, &chol.values, x, &mut ax);
            max_diff(&ax, b) / max_abs(b)
        };
        let b = rhs_of(&sys, &dofs);
        let mut x = b.clone();
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert!(residual(&chol, &x, &b) <= 1e-12, "first solve");
        assert_eq!(chol.repack_count, 1);
        // Small drift: reused factor, CG preconditioned by the copy.
        for m in sys.diag.iter_mut().chain(sys.off.iter_mut()) {
            *m *= 1.0 + 1e-4;
        }
        let b = rhs_of(&sys, &dofs);
        let mut x = b.clone();
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert_eq!((chol.numeric_count, chol.repack_count), (1, 1), "reused");
        assert!(chol.reuse_iterations >= 1);
        let mut fresh = b.clone();
        SparseCholesky::default()
            .factor_solve(&sys, &dofs, &mut fresh, &SparseParams::default())
            .expect("positive definite");
        assert!(max_diff(&x, &fresh) <= 1e-11 * max_abs(&fresh), "reuse");
        // Major change: refactored, a new copy.
        for m in sys.off.iter_mut().take(params.max_reuse_iterations) {
            *m *= 0.5;
        }
        let b = rhs_of(&sys, &dofs);
        let mut x = b.clone();
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert_eq!(
            (chol.numeric_count, chol.repack_count),
            (2, 2),
            "refactored"
        );
        assert!(residual(&chol, &x, &b) <= 1e-12, "solve after refactoring");
        // A checked reuse makes, copies and undoes a fresh factorization; the run must take
        // the unchecked run's path to the bit (`check_reuse`), so the copy of the fresh factor
        // must not outlive it.
        let checked = SparseParams {
            check_reuse: true,
            ..params
        };
        let (mut sys2, dofs2) = grid_system(150, 10);
        let (mut plain, mut with_check) = (SparseCholesky::default(), SparseCholesky::default());
        for step in 0..4 {
            let b = rhs_of(&sys2, &dofs2);
            let (mut x1, mut x2) = (b.clone(), b.clone());
            plain
                .factor_solve(&sys2, &dofs2, &mut x1, &params)
                .expect("positive definite");
            with_check
                .factor_solve(&sys2, &dofs2, &mut x2, &checked)
                .expect("positive definite");
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&x1), bits(&x2), "checked run left the path at {step}");
            for m in sys2.diag.iter_mut().chain(sys2.off.iter_mut()) {
                *m *= 1.0 + 1e-4;
            }
        }
        assert_eq!(
            with_check.numeric_count, 1,
            "the checks' factorizations undone"
        );
        assert!(with_check.reuse_max_error > 0.0 && with_check.reuse_max_error <= 1e-11);
        // The same factor by faer's solve: the copy is not used.
        let b = rhs_of(&sys, &dofs);
        let mut x = b.clone();
        let before = chol.repack_count;
        chol.factor_solve(&sys, &dofs, &mut x, &SparseParams::default())
            .expect("positive definite");
        assert!(residual(&chol, &x, &b) <= 1e-11);
        assert_eq!(chol.repack_count, before);
    }

    /// The simplicial path (faer's automatic choice) solves the same way.
    #[test]
    fn simplicial_factor_solves() {
        let (sys, dofs) = grid_system(60, 6);
        let mut chol = SparseCholesky::default();
        let params = SparseParams {
            supernodal: false,
            ..Default::default()
        };
        let b = rhs_of(&sys, &dofs);
        let mut x = b.clone();
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        let mut ax = Vec::new();
        symmetric_upper_matvec(&chol.col_ptr, &chol.row_idx, &chol.values, &x, &mut ax);
        let res = ax
            .iter()
            .zip(&b)
            .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(res <= 1e-12 * max_abs(&b), "residual {res:e}");
    }

    /// Every ordering and amalgamation solves the same system: residual within 1e-12 of the
    /// right-hand side (as the default's test above), and the solutions agree with the scalar
    /// ordering's within 1e-12 of the largest unknown (round-off of a diagonally dominant system
    /// of 1200 unknowns, condition ≈ 10). On the 30 × 40 grid the block orderings' factor
    /// (faer's amalgamation) must not cost more than 1.5× the scalar one's (a block ordering
    /// that lost the grid's structure would cost several times more; measured in §20).
    #[test]
    fn block_orderings_solve_the_same_system() {
        let (sys, dofs) = grid_system(1200, 30);
        let b = rhs_of(&sys, &dofs);
        let solve = |ordering, relax| {
            let params = SparseParams {
                ordering,
                relax,
                dissection_leaf: 16,
                ..Default::default()
            };
            let mut chol = SparseCholesky::default();
            let mut x = b.clone();
            chol.factor_solve(&sys, &dofs, &mut x, &params)
                .expect("positive definite");
            let mut ax = Vec::new();
            symmetric_upper_matvec(&chol.col_ptr, &chol.row_idx, &chol.values, &x, &mut ax);
            assert!(
                max_diff(&ax, &b) <= 1e-12 * max_abs(&b),
                "{ordering:?} {relax:?} residual"
            );
            (x, chol.cost().factor)
        };
        let (reference, scalar_work) = solve(SparseOrdering::ScalarAmd, SupernodeRelax::Faer);
        for ordering in [
            SparseOrdering::BlockAmd,
            SparseOrdering::BlockDissection,
            SparseOrdering::BlockCoordinates,
        ] {
            for relax in [
                SupernodeRelax::Faer,
                SupernodeRelax::None,
                SupernodeRelax::Wide,
            ] {
                let (x, work) = solve(ordering, relax);
                assert!(
                    max_diff(&x, &reference) <= 1e-12 * max_abs(&reference),
                    "{ordering:?} {relax:?} differs from the scalar ordering"
                );
                // The bound is on the ordering: amalgamation adds explicit zeros on purpose.
                assert!(
                    relax != SupernodeRelax::Faer || work <= 1.5 * scalar_work,
                    "{ordering:?}: factor work {work:.3e} vs {scalar_work:.3e}"
                );
            }
        }
    }

    /// The two-rows kernels of the repacked solve (session 43, docs/contact-solve.md §37) give
    /// the one-row kernels' solution (`Repacked::solve_by_rows`, the solve of session 42) to
    /// the bit: tolerance 0, since each row's sum and each unknown's updates keep their order.
    /// On the rigid grids under every ordering and amalgamation and on the mixed grid; every
    /// kernel width (1 to 8 and the general loop) must occur.
    #[test]
    fn two_rows_a_pass_equal_one_row_a_pass_to_the_bit() {
        let mut widths = [0; super::super::repacked::MAX_UNROLLED + 1];
        let mut check = |sys: &BlockSystem, dofs: &Dofs, params: SparseParams| {
            let mut chol = SparseCholesky::default();
            chol.rebuild_pattern(sys, dofs, &params).expect("pattern");
            chol.fill_values(sys, dofs, false);
            chol.factorize(sys, dofs).expect("positive definite");
            chol.triangular = TriangularSolve::Repacked;
            assert!(chol.ensure_repacked(), "a supernodal factor, repacked");
            let b = full_rhs(dofs.n);
            let (mut pairs, mut rows) = (b.clone(), b);
            chol.repacked.solve(&mut pairs);
            chol.repacked.solve_by_rows(&mut rows);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert!(
                bits(&pairs) == bits(&rows),
                "{:?} {:?} n {}: two rows a pass differ from one",
                params.ordering,
                params.relax,
                dofs.n
            );
            for (a, b) in widths.iter_mut().zip(chol.repacked.width_counts()) {
                *a += b;
            }
        };
        let (sys, dofs) = grid_system(150, 10);
        check(&sys, &dofs, SparseParams::default());
        let (sys, dofs) = grid_system(1200, 30);
        for ordering in [
            SparseOrdering::ScalarAmd,
            SparseOrdering::BlockAmd,
            SparseOrdering::BlockDissection,
            SparseOrdering::BlockCoordinates,
        ] {
            for relax in [
                SupernodeRelax::Faer,
                SupernodeRelax::None,
                SupernodeRelax::Wide,
            ] {
                let params = SparseParams {
                    ordering,
                    relax,
                    ..Default::default()
                };
                check(&sys, &dofs, params);
            }
        }
        let (sys, dofs) = mixed_grid(300, 12);
        check(&sys, &dofs, SparseParams::default());
        assert!(
            widths.iter().all(|&w| w > 0),
            "every kernel width exercised: {widths:?}"
        );
    }
}
