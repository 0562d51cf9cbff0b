//! The stacked form of a [`DenseProblem`]: every member as rows of one list,
//! equalities first, the form the solvers take, and the map from the stacked
//! multipliers back to the members.

use crate::problem::{DenseProblem, ProblemError};

/// Where a row of [`Stacked`] comes from (the index is into the member).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowOrigin {
    /// Row `i` of `A x = b` (an equality row `A_i x = b_i`).
    Eq(usize),
    /// Row `i` of `G x <= h`.
    Ineq(usize),
    /// The upper bound `x_j <= ub_j`, as the row `e_j' x <= ub_j`.
    Upper(usize),
    /// The lower bound `lb_j <= x_j`, as the row `-e_j' x <= -lb_j`.
    Lower(usize),
}

impl RowOrigin {
    /// True for [`RowOrigin::Eq`]: the row holds with equality and its
    /// multiplier has free sign.
    pub fn is_equality(self) -> bool {
        matches!(self, RowOrigin::Eq(_))
    }
}

/// A [`DenseProblem`] as one list of `m` rows `g_i x (= or <=) h_i`: rows
/// `0..me` are the equalities `A x = b`, rows `me..m` inequalities, in the order
/// `G x <= h`, then `x_j <= ub_j` for each finite `ub_j` (ascending `j`), then
/// `-x_j <= -lb_j` for each finite `lb_j`. Multipliers `y` of this list (the
/// solvers' output) satisfy `Px + q + G'y = 0` at the optimum, with `y_i >= 0`
/// on the inequality rows; [`Stacked::split_multipliers`] maps them back.
#[derive(Clone, Debug, PartialEq)]
pub struct Stacked {
    /// Number of variables.
    pub n: usize,
    /// Number of equality rows (the first `me` rows).
    pub me: usize,
    /// Total number of rows.
    pub m: usize,
    /// The rows, `m x n`, row-major.
    pub G: Vec<f64>,
    /// The right-hand sides, length `m`.
    pub h: Vec<f64>,
    /// The member each row comes from, length `m`.
    pub origin: Vec<RowOrigin>,
}

/// Multipliers of a [`DenseProblem`] member by member (see
/// [`Stacked::split_multipliers`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Multipliers {
    /// Of `A x = b`, length `me` (free sign).
    pub eq: Vec<f64>,
    /// Of `G x <= h`, length `m` (`>= 0` at an optimum).
    pub ineq: Vec<f64>,
    /// Of `lb <= x`, length `n`; `0` where `lb_j` is absent or `-inf`.
    pub lower: Vec<f64>,
    /// Of `x <= ub`, length `n`; `0` where `ub_j` is absent or `+inf`.
    pub upper: Vec<f64>,
}

impl Multipliers {
    /// The box multipliers in one vector, `upper - lower` (the `z_box` of
    /// qpsolvers: positive where the upper bound is active, negative where the
    /// lower one is).
    pub fn z_box(&self) -> Vec<f64> {
        self.upper
            .iter()
            .zip(&self.lower)
            .map(|(u, l)| u - l)
            .collect()
    }
}

/// `g_i x` for row `i` of the `n`-column row-major matrix `g` (NaN when the row
/// or `x` is out of range).
pub(crate) fn dot_row(g: &[f64], n: usize, i: usize, x: &[f64]) -> f64 {
    match i.checked_mul(n).and_then(|s| g.get(s..s + n)) {
        Some(row) if x.len() == n => row.iter().zip(x).map(|(a, b)| a * b).sum(),
        _ => f64::NAN,
    }
}

impl DenseProblem {
    /// The stacked form (see [`Stacked`]). Entries missing from members of the
    /// wrong length read as NaN ([`DenseProblem::validate`] reports them).
    pub fn stacked(&self) -> Stacked {
        let n = self.n;
        let mut st = Stacked {
            n,
            me: self.me,
            m: 0,
            G: Vec::with_capacity(self.rows().saturating_mul(n)),
            h: Vec::with_capacity(self.rows()),
            origin: Vec::with_capacity(self.rows()),
        };
        let view = self.view();
        let mut g = vec![0.0; n];
        for o in view.origins() {
            st.h.push(view.row_into(o, &mut g));
            st.G.extend_from_slice(&g);
            st.origin.push(o);
            st.m += 1;
        }
        st
    }
}

impl Stacked {
    /// `g_i x` for stacked row `i` (NaN when `i` or `x` is out of range).
    pub fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        dot_row(&self.G, self.n, i, x)
    }

    /// The multipliers `y` of the stacked rows (length `m`) member by member; a
    /// bound's multiplier is `>= 0` for both `lower` and `upper` (the sign of its
    /// row). Errors when `y` does not have length `m`.
    pub fn split_multipliers(&self, y: &[f64]) -> Result<Multipliers, ProblemError> {
        if y.len() != self.m || self.origin.len() != self.m {
            return Err(ProblemError::Multipliers {
                given: y.len(),
                rows: self.m,
            });
        }
        let ineq = self
            .origin
            .iter()
            .filter(|o| matches!(o, RowOrigin::Ineq(_)))
            .count();
        crate::view::split(self.origin.iter().copied(), self.n, self.me, ineq, y)
    }
}
