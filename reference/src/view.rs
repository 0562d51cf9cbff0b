//! A [`DenseProblem`] borrowed: its members as slices ([`ProblemView`]), so a
//! caller holding the data elsewhere (numpy buffers read in place by the
//! Python package) writes the stacked rows straight into the solver's types
//! ([`ProblemView::write_qp`], no copy in between) and maps the stacked
//! multipliers back ([`ProblemView::split_multipliers`]). The order of the
//! stacked rows is defined here once, by [`ProblemView::origins`].

use ldcbf_controller::QpAllocator;
use ldcbf_controller::nalgebra::{DefaultAllocator, Dim, OMatrix, OVector, U1};

use crate::problem::{DenseProblem, ProblemError, SizedQp};
use crate::stacked::{Multipliers, RowOrigin};

/// The members of a [`DenseProblem`] as slices (same meaning, same row-major
/// layout, same conventions for absent members: empty slices).
#[derive(Clone, Copy, Debug)]
pub struct ProblemView<'a> {
    /// Number of variables.
    pub n: usize,
    /// Number of inequality rows (rows of `G`).
    pub m: usize,
    /// Number of equality rows (rows of `A`).
    pub me: usize,
    /// `P`, `n x n`, row-major.
    pub P: &'a [f64],
    /// `q`, length `n`.
    pub q: &'a [f64],
    /// `G`, `m x n`, row-major.
    pub G: &'a [f64],
    /// `h`, length `m`.
    pub h: &'a [f64],
    /// `A`, `me x n`, row-major.
    pub A: &'a [f64],
    /// `b`, length `me`.
    pub b: &'a [f64],
    /// Lower bounds: empty or length `n`; `-inf` is no bound.
    pub lb: &'a [f64],
    /// Upper bounds: empty or length `n`; `+inf` is no bound.
    pub ub: &'a [f64],
}

impl DenseProblem {
    /// The problem borrowed ([`ProblemView`]).
    pub fn view(&self) -> ProblemView<'_> {
        ProblemView {
            n: self.n,
            m: self.m,
            me: self.me,
            P: &self.P,
            q: &self.q,
            G: &self.G,
            h: &self.h,
            A: &self.A,
            b: &self.b,
            lb: &self.lb,
            ub: &self.ub,
        }
    }
}

impl ProblemView<'_> {
    /// [`DenseProblem::validate`] of the borrowed members, `what` (`field`,
    /// `key`) naming them. Each member is first scanned for a non-finite
    /// entry in one pass without branches (the common case: all finite); only
    /// a member that has one is searched entry by entry for the message.
    pub fn check(&self, what: &'static str) -> Result<(), ProblemError> {
        let (n, m, me) = (self.n, self.m, self.me);
        let vector = |v: &[f64]| if v.is_empty() { 0 } else { n };
        // (key, values, rows, columns of a matrix)
        let members: [(&str, &[f64], usize, Option<usize>); 8] = [
            ("P", self.P, n, Some(n)),
            ("q", self.q, n, None),
            ("G", self.G, m, Some(n)),
            ("h", self.h, m, None),
            ("A", self.A, me, Some(n)),
            ("b", self.b, me, None),
            ("lb", self.lb, vector(self.lb), None),
            ("ub", self.ub, vector(self.ub), None),
        ];
        for (key, v, rows, cols) in members {
            let bounds = matches!(key, "lb" | "ub");
            if rows.checked_mul(cols.unwrap_or(1)) != Some(v.len()) {
                let shape = match cols {
                    Some(c) => format!("{rows} x {c}"),
                    None => format!("{rows}"),
                };
                return Err(ProblemError::MemberLength {
                    naming: what,
                    key,
                    len: v.len(),
                    shape,
                    n,
                    m,
                    me,
                });
            }
            if !bounds && all_finite(v) {
                continue;
            }
            for (k, &x) in v.iter().enumerate() {
                let bad = match (key, x) {
                    (_, x) if x.is_nan() => "NaN",
                    ("lb", f64::INFINITY) => "+inf (a lower bound no x meets)",
                    ("ub", f64::NEG_INFINITY) => "-inf (an upper bound no x meets)",
                    ("lb" | "ub", _) => continue,
                    (_, x) if x.is_infinite() => "infinite",
                    _ => continue,
                };
                let at = match cols {
                    Some(c) => format!("[{}, {}]", k / c, k % c),
                    None => format!("[{k}]"),
                };
                return Err(ProblemError::MemberValue {
                    naming: what,
                    key,
                    at,
                    bad,
                });
            }
        }
        if !self.lb.is_empty() && !self.ub.is_empty() {
            for (j, (l, u)) in self.lb.iter().zip(self.ub).enumerate() {
                if l > u {
                    return Err(ProblemError::Bounds {
                        naming: what,
                        index: j,
                        lower: *l,
                        upper: *u,
                    });
                }
            }
        }
        Ok(())
    }

    /// The origin of each stacked row, in the stacked order: the equalities
    /// `A x = b`, then `G x <= h`, then `x_j <= ub_j` for each finite `ub_j`
    /// (ascending `j`), then `-x_j <= -lb_j` for each finite `lb_j`.
    pub fn origins(&self) -> impl Iterator<Item = RowOrigin> + '_ {
        (0..self.me)
            .map(RowOrigin::Eq)
            .chain((0..self.m).map(RowOrigin::Ineq))
            .chain(finite(self.ub).map(RowOrigin::Upper))
            .chain(finite(self.lb).map(RowOrigin::Lower))
    }

    /// Number of stacked rows: `me + m` plus one per finite bound.
    pub fn rows(&self) -> usize {
        self.me + self.m + finite(self.ub).count() + finite(self.lb).count()
    }

    /// Stacked row `o` as `(g, h)`, written into `g` (length `n`); NaN where
    /// a member is too short.
    pub fn row_into(&self, o: RowOrigin, g: &mut [f64]) -> f64 {
        let n = self.n;
        let at = |v: &[f64], k: usize| v.get(k).copied().unwrap_or(f64::NAN);
        let copy = |g: &mut [f64], src: &[f64], i: usize| {
            for (j, x) in g.iter_mut().enumerate() {
                *x = at(src, i * n + j);
            }
        };
        let unit = |g: &mut [f64], j: usize, s: f64| {
            for (k, x) in g.iter_mut().enumerate() {
                *x = if k == j { s } else { 0.0 };
            }
        };
        match o {
            RowOrigin::Eq(i) => {
                copy(g, self.A, i);
                at(self.b, i)
            }
            RowOrigin::Ineq(i) => {
                copy(g, self.G, i);
                at(self.h, i)
            }
            RowOrigin::Upper(j) => {
                unit(g, j, 1.0);
                at(self.ub, j)
            }
            RowOrigin::Lower(j) => {
                unit(g, j, -1.0);
                -at(self.lb, j)
            }
        }
    }

    /// `P` as the solver's Hessian, copied as one slice (`nv` must be `n`,
    /// `P` of length `n^2`, else `None`). The row-major `P` lands in
    /// column-major storage, so the matrix is `P'`: the same for the
    /// symmetric `P` the solver takes, and the solver's symmetry check
    /// refuses both alike otherwise.
    pub fn hessian<V: Dim>(&self, nv: V) -> Option<OMatrix<f64, V, V>>
    where
        DefaultAllocator: ldcbf_controller::nalgebra::allocator::Allocator<V, V>,
    {
        if nv.value() != self.n || Some(self.P.len()) != self.n.checked_mul(self.n) {
            return None;
        }
        let mut H = OMatrix::<f64, V, V>::zeros_generic(nv, nv);
        H.as_mut_slice().copy_from_slice(self.P);
        Some(H)
    }

    /// Writes `q` and the stacked rows into `qp` (its previous rows are
    /// overwritten; its capacity must hold [`ProblemView::rows`], its `nv` be
    /// `n`). Rows of `A` and `G` are copied as contiguous slices (one column
    /// of `qp.gt` each).
    pub fn write_qp<V: Dim, C: Dim>(
        &self,
        qp: &mut ldcbf_controller::DenseQpOf<V, C>,
    ) -> Result<(), ProblemError>
    where
        DefaultAllocator: QpAllocator<V, C>,
    {
        let n = qp.gt.nrows();
        let rows = self.rows();
        if self.n != n || rows > qp.gt.ncols() {
            return Err(ProblemError::SolverSize {
                n: self.n,
                rows,
                nv: n,
                nc: qp.gt.ncols(),
            });
        }
        if self.q.len() != n
            || self.h.len() != self.m
            || self.b.len() != self.me
            || Some(self.P.len()) != n.checked_mul(n)
            || Some(self.G.len()) != self.m.checked_mul(n)
            || Some(self.A.len()) != self.me.checked_mul(n)
        {
            return Err(ProblemError::NotValidated { n });
        }
        qp.q.as_mut_slice().copy_from_slice(self.q);
        let gt = qp.gt.as_mut_slice();
        let h = qp.h.as_mut_slice();
        let (me, m) = (self.me, self.m);
        // `A` then `G`, row-major, are the first `me + m` columns of `gt`.
        gt[..me * n].copy_from_slice(self.A);
        gt[me * n..(me + m) * n].copy_from_slice(self.G);
        h[..me].copy_from_slice(self.b);
        h[me..me + m].copy_from_slice(self.h);
        for (i, o) in self.origins().enumerate().skip(me + m) {
            h[i] = self.row_into(o, &mut gt[i * n..(i + 1) * n]);
        }
        qp.m = rows;
        qp.me = me;
        Ok(())
    }

    /// [`DenseProblem::to_qp`] of the borrowed members.
    pub fn to_qp<V: Dim, C: Dim>(&self, nv: V, nc: C) -> Result<SizedQp<V, C>, ProblemError>
    where
        DefaultAllocator: QpAllocator<V, C>,
    {
        let n = nv.value();
        let rows = self.rows();
        if self.n != n || rows > nc.value() {
            return Err(ProblemError::SolverSize {
                n: self.n,
                rows,
                nv: n,
                nc: nc.value(),
            });
        }
        let mut qp = ldcbf_controller::DenseQpOf::<V, C>::with_q_generic(
            OVector::<f64, V>::zeros_generic(nv, U1),
            nc,
        );
        self.write_qp(&mut qp)?;
        let H = self.hessian(nv).ok_or(ProblemError::NotValidated { n })?;
        Ok((H, qp))
    }

    /// The multipliers `y` of the stacked rows member by member (see
    /// [`Stacked::split_multipliers`](crate::Stacked::split_multipliers),
    /// which is this map on a stacked copy).
    pub fn split_multipliers(&self, y: &[f64]) -> Result<Multipliers, ProblemError> {
        split(self.origins(), self.n, self.me, self.m, y)
    }
}

/// The multipliers `y` of rows of origins `origins` member by member; `y`
/// must have one entry per origin.
pub(crate) fn split(
    origins: impl Iterator<Item = RowOrigin>,
    n: usize,
    me: usize,
    m: usize,
    y: &[f64],
) -> Result<Multipliers, ProblemError> {
    let mut out = Multipliers {
        eq: vec![0.0; me],
        ineq: vec![0.0; m],
        lower: vec![0.0; n],
        upper: vec![0.0; n],
    };
    let mut rows = 0;
    for (k, o) in origins.enumerate() {
        rows = k + 1;
        let Some(&v) = y.get(k) else { continue };
        let slot = match o {
            RowOrigin::Eq(i) => out.eq.get_mut(i),
            RowOrigin::Ineq(i) => out.ineq.get_mut(i),
            RowOrigin::Upper(j) => out.upper.get_mut(j),
            RowOrigin::Lower(j) => out.lower.get_mut(j),
        };
        if let Some(s) = slot {
            *s = v;
        }
    }
    if rows != y.len() {
        return Err(ProblemError::Multipliers {
            given: y.len(),
            rows,
        });
    }
    Ok(out)
}

/// True when every entry of `v` is finite: one pass over the exponent bits
/// without an early exit, so that it vectorises.
pub fn all_finite(v: &[f64]) -> bool {
    const EXP: u64 = 0x7ff0_0000_0000_0000;
    !v.iter()
        .fold(false, |bad, x| bad | (x.to_bits() & EXP == EXP))
}

/// The indices of the finite entries of `v`, ascending.
fn finite(v: &[f64]) -> impl Iterator<Item = usize> + '_ {
    v.iter()
        .enumerate()
        .filter(|(_, x)| x.is_finite())
        .map(|(j, _)| j)
}
