//! The dense QP [`DenseProblem`]: built from the controller's assembly or
//! storage types and shaped back into them (the npz layout is in `npz.rs`).

use ldcbf_controller::nalgebra::{Const, DMatrix, DefaultAllocator, Dim, Dyn, OMatrix, SMatrix};
use ldcbf_controller::{
    Assembly, DenseQp, DenseQpDyn, DenseQpOf, DualActiveSet, HessianError, QpAllocator,
};

/// A dense QP in the layout of the qpbenchmark npz files,
///
/// ```text
/// minimise 1/2 x'Px + q'x  s.t.  Gx <= h,  Ax = b,  lb <= x <= ub,
/// ```
///
/// with `n` variables, `m` inequality rows and `me` equality rows; matrices are
/// row-major. `G, h` and `A, b` may be absent (`m = 0`, `me = 0`: empty
/// vectors); `lb` and `ub` are each either absent (empty) or of length `n`, with
/// `-inf` (in `lb`) and `+inf` (in `ub`) meaning no bound. The solvers take the
/// problem as one list of rows, [`DenseProblem::stacked`]. [`DenseProblem::validate`]
/// checks that the members fit together.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseProblem {
    /// Number of variables.
    pub n: usize,
    /// Number of inequality rows (rows of `G`).
    pub m: usize,
    /// Number of equality rows (rows of `A`).
    pub me: usize,
    /// `P`, `n x n`, row-major, symmetric positive definite.
    pub P: Vec<f64>,
    /// `q`, length `n`.
    pub q: Vec<f64>,
    /// `G`, `m x n`, row-major (empty when `m = 0`).
    pub G: Vec<f64>,
    /// `h`, length `m`.
    pub h: Vec<f64>,
    /// `A`, `me x n`, row-major (empty when `me = 0`).
    pub A: Vec<f64>,
    /// `b`, length `me`.
    pub b: Vec<f64>,
    /// Lower bounds on `x`: empty (absent) or length `n`; `-inf` is no bound.
    pub lb: Vec<f64>,
    /// Upper bounds on `x`: empty (absent) or length `n`; `+inf` is no bound.
    pub ub: Vec<f64>,
}

/// Error reading or shaping a problem. Each names the member (`P`, `q`, `G`,
/// `h`, `A`, `b`, `lb`, `ub`), the file or the sizes concerned. No variant has
/// a `source`: the message already holds the inner one.
#[derive(Debug, thiserror::Error)]
pub enum ProblemError {
    /// A member has the wrong number of entries for `n`, `m`, `me`.
    #[error("{naming} `{key}` has {len} entries, expected {shape} (n = {n}, m = {m}, me = {me})")]
    MemberLength {
        /// How members are named: `field` (of the problem) or `key` (of an npz file).
        naming: &'static str,
        /// The member.
        key: &'static str,
        /// Its number of entries.
        len: usize,
        /// The expected shape (`rows x columns` or `rows`).
        shape: String,
        /// Variables.
        n: usize,
        /// Inequality rows.
        m: usize,
        /// Equality rows.
        me: usize,
    },
    /// An entry of a member is NaN, or an infinity where none may be.
    #[error("{naming} `{key}`: entry {at} is {bad}")]
    MemberValue {
        /// `field` or `key`, as for [`ProblemError::MemberLength`].
        naming: &'static str,
        /// The member.
        key: &'static str,
        /// The entry, `[i]` or `[i, j]`.
        at: String,
        /// What is wrong with it.
        bad: &'static str,
    },
    /// A lower bound above its upper bound.
    #[error("{naming} `lb`: lb[{index}] = {lower} is above ub[{index}] = {upper}")]
    Bounds {
        /// `field` or `key`, as for [`ProblemError::MemberLength`].
        naming: &'static str,
        /// The variable.
        index: usize,
        /// `lb[index]`.
        lower: f64,
        /// `ub[index]`.
        upper: f64,
    },
    /// The problem does not fit the solver's sizes.
    #[error(
        "problem has n = {n}, m = {rows} (equality, inequality and bound rows); the \
         solver size is NV = {nv}, NC = {nc}"
    )]
    SolverSize {
        /// The problem's variables.
        n: usize,
        /// Its stacked rows.
        rows: usize,
        /// The solver's variables.
        nv: usize,
        /// The solver's row capacity.
        nc: usize,
    },
    /// `P` or `q` does not have `n` (a problem not validated).
    #[error("field `P` or `q` does not have n = {n} (run `validate`)")]
    NotValidated {
        /// Variables.
        n: usize,
    },
    /// The solver's row storage is full.
    #[error("row capacity exceeded")]
    RowCapacity,
    /// The solver refused the Hessian `P`.
    #[error("Hessian rejected: {0}")]
    Hessian(HessianError),
    /// Multipliers of the wrong length.
    #[error("{given} multipliers for {rows} stacked rows")]
    Multipliers {
        /// Multipliers given.
        given: usize,
        /// Stacked rows.
        rows: usize,
    },
    /// A point `(x, y)` of the wrong lengths for the KKT residuals.
    #[error("x has {x} entries and y {y}; the problem has n = {n} and {rows} stacked rows")]
    KktLengths {
        /// Entries of `x`.
        x: usize,
        /// Entries of `y`.
        y: usize,
        /// Variables.
        n: usize,
        /// Stacked rows.
        rows: usize,
    },
    /// An npz file that cannot be read or written: `reason` says why (and
    /// which key).
    #[error("{file}: {reason}")]
    File {
        /// The file, as given.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// An npz file whose members are wrong.
    #[error("{file}: {error}")]
    InFile {
        /// The file, as given.
        file: String,
        /// What is wrong with its members.
        error: Box<ProblemError>,
    },
}

/// A problem in the solver's types: the Hessian and the QP (stacked rows).
pub type SizedQp<V, C> = (OMatrix<f64, V, V>, DenseQpOf<V, C>);

impl DenseProblem {
    /// A problem with inequality rows only (`me = 0`, no bounds): `m` is the
    /// length of `h`. The members are taken as given ([`DenseProblem::validate`]
    /// checks them).
    pub fn inequalities(n: usize, P: Vec<f64>, q: Vec<f64>, G: Vec<f64>, h: Vec<f64>) -> Self {
        DenseProblem {
            n,
            m: h.len(),
            me: 0,
            P,
            q,
            G,
            h,
            A: Vec::new(),
            b: Vec::new(),
            lb: Vec::new(),
            ub: Vec::new(),
        }
    }

    /// The QP of one controller cycle: `P = H` of the solver, `q, G, h` of the
    /// assembly (only the `m` rows in use).
    pub fn from_assembly<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
        solver: &DualActiveSet<NV, NC>,
        asm: &Assembly<N, NV, NC, NOBS>,
    ) -> Self {
        Self::from_dense_qp(solver.hessian(), &asm.qp)
    }

    /// From the controller's storage types.
    pub fn from_dense_qp<const NV: usize, const NC: usize>(
        H: &SMatrix<f64, NV, NV>,
        qp: &DenseQp<NV, NC>,
    ) -> Self {
        let m = qp.m.min(NC);
        let mut P = Vec::with_capacity(NV * NV);
        for i in 0..NV {
            for j in 0..NV {
                P.push(H[(i, j)]);
            }
        }
        let mut G = Vec::with_capacity(m * NV);
        for i in 0..m {
            for j in 0..NV {
                G.push(qp.gt[(j, i)]);
            }
        }
        DenseProblem::inequalities(
            NV,
            P,
            qp.q.iter().copied().collect(),
            G,
            qp.h.iter().take(m).copied().collect(),
        )
    }

    /// Checks the members: their lengths against `n`, `m`, `me` (`P` `n x n`,
    /// `q` `n`, `G` `m x n`, `h` `m`, `A` `me x n`, `b` `me`, `lb` and `ub` empty
    /// or `n`); no NaN anywhere; no infinity except `-inf` in `lb` and `+inf` in
    /// `ub`; `lb_j <= ub_j`. Errors name the field and the entry.
    pub fn validate(&self) -> Result<(), ProblemError> {
        self.check("field")
    }

    /// [`DenseProblem::validate`] with `what` (`field`, `key`) naming the members.
    pub(crate) fn check(&self, what: &'static str) -> Result<(), ProblemError> {
        self.view().check(what)
    }

    /// Objective `1/2 x'Px + q'x` (NaN when `x` or the members have the wrong
    /// length).
    pub fn objective(&self, x: &[f64]) -> f64 {
        let n = self.n;
        if x.len() != n || self.q.len() != n || Some(self.P.len()) != n.checked_mul(n) {
            return f64::NAN;
        }
        let mut f = 0.0;
        for i in 0..n {
            let mut px = 0.0;
            for j in 0..n {
                px += self.P[i * n + j] * x[j];
            }
            f += 0.5 * x[i] * px + self.q[i] * x[i];
        }
        f
    }

    /// Largest violation of any member at `x`: `(G_i x - h_i)^+`, `|A_i x - b_i|`,
    /// `(lb_j - x_j)^+`, `(x_j - ub_j)^+` (NaN when the lengths do not fit).
    pub fn max_violation(&self, x: &[f64]) -> f64 {
        let st = self.stacked();
        if x.len() != self.n {
            return f64::NAN;
        }
        (0..st.m)
            .map(|i| {
                let r = st.row_dot(i, x) - st.h[i];
                if i < st.me { r.abs() } else { r }
            })
            .fold(0.0, |a: f64, r| if r.is_nan() { r } else { a.max(r) })
    }

    /// `G_i x`, row `i` of the inequalities (NaN when out of range).
    pub(crate) fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        crate::stacked::dot_row(&self.G, self.n, i, x)
    }

    /// Number of rows of [`DenseProblem::stacked`]: `me + m` plus one per finite
    /// entry of `ub` and of `lb`.
    pub fn rows(&self) -> usize {
        let finite = |v: &[f64]| v.iter().filter(|x| x.is_finite()).count();
        self.me + self.m + finite(&self.ub) + finite(&self.lb)
    }

    /// Copies the problem into the controller's fixed-size types: the
    /// stacked rows of [`DenseProblem::stacked`] (equality rows first, held
    /// as equalities; then `G`; then the finite bounds as rows).
    pub fn to_fixed<const NV: usize, const NC: usize>(
        &self,
    ) -> Result<(SMatrix<f64, NV, NV>, DenseQp<NV, NC>), ProblemError> {
        self.to_qp(Const::<NV>, Const::<NC>)
    }

    /// The same with run-time sizes (`n` variables, room for exactly the
    /// stacked rows): the solver's `Dyn` instance takes any size.
    pub fn to_dyn(&self) -> Result<(DMatrix<f64>, DenseQpDyn), ProblemError> {
        self.to_qp(Dyn(self.n), Dyn(self.rows()))
    }

    /// [`DenseProblem::to_fixed`] and [`DenseProblem::to_dyn`], written once
    /// for any dimension types (`nv` must be `n`, `nc` at least the stacked
    /// rows).
    pub fn to_qp<V: Dim, C: Dim>(&self, nv: V, nc: C) -> Result<SizedQp<V, C>, ProblemError>
    where
        DefaultAllocator: QpAllocator<V, C>,
    {
        self.view().to_qp(nv, nc)
    }
}
