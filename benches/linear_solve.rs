//! Dense LU factor + solve per size: svi's own small solvers against faer and nalgebra.
//!
//! Newton's method in the spectral integrators refactors an (N·s)-sized Jacobian every
//! iteration and solves once with it, so the unit of work timed here is "copy A into the
//! factor buffer, factor with partial pivoting, copy b in, solve in place". Copies are in
//! every variant, so the comparison is fair; the matrix is column-major everywhere.
//!
//! # `linear_solve/lu/<implementation>/<n>`, n ∈ {2, 4, 8, 12, 16, 24, 32, 48, 64, 96, 128}
//!
//! - `svi_dense_lu`: [`svi::linalg::DenseLu`], allocated once, then `matrix_mut()`,
//!   `factor()`, `solve_in_place()` — no allocation in the loop.
//! - `faer_in_place`: faer 0.24's allocation-free low-level API with everything reused across
//!   iterations: `faer::linalg::lu::partial_pivoting::factor::lu_in_place` into a
//!   preallocated `Mat`, permutation buffers and a `MemBuffer`/`MemStack` sized by
//!   `lu_in_place_scratch` ∨ `solve_in_place_scratch`, then
//!   `partial_pivoting::solve::solve_in_place`; sequential (`Par::Seq`).
//! - `faer_api`: the convenient API, `a.partial_piv_lu()` then `.solve(&b)`; it allocates the
//!   factors, permutations, scratch and the result on every call (what a naive user writes).
//!
//! # `linear_solve/small/<implementation>/<N>`, fixed N ∈ {2, 3, 6}
//!
//! - `solve_small`: [`svi::linalg::solve_small`] on `SMatrix<f64, N, N>` (by value, no
//!   allocation; generic over dual numbers too);
//! - `nalgebra_lu`: nalgebra's `SMatrix::lu().solve()` for reference;
//! - `svi_dense_lu`: the runtime-sized [`svi::linalg::DenseLu`] at the same N.
//!
//! The matrices are well conditioned and reproducible: entries uniform in [−½, ½) from a
//! fixed-seed 64-bit LCG, plus n on the diagonal (strictly diagonally dominant, so partial
//! pivoting searches but never swaps — the same work for every implementation). Every
//! implementation's solution is checked against a known x before timing.
//!
//! # `linear_solve/pattern/<implementation>/<case>`
//!
//! The seam of the term-sum Newton iterations ([`svi::linalg::sparse`]) on the patterns their
//! stage Jacobians have: n coordinates, s stages, coordinates i and j coupled when
//! |i − j| ≤ w (every stage with every stage), so the matrix has size n·s and blocks of s × s.
//! Case `n<n>s<s>w<w>`: `w1` is a chain of nearest neighbours, w ≥ n − 1 all pairs (an N-body
//! system). The unit of work is one numeric factorisation and one solve after the symbolic
//! analysis (what a Newton iteration pays), for `dense` ([`svi::linalg::sparse::DenseSolver`])
//! and `sparse` ([`svi::linalg::sparse::SparseLu`]). It sets
//! [`svi::linalg::sparse::LinearSolverKind::Auto`]'s rule.
//!
//! Run with `cargo bench --bench linear_solve` (add `-- linear_solve/lu`,
//! `-- linear_solve/small` or `-- linear_solve/pattern` for a subset). Timings are short on purpose (2 s measurement,
//! 0.5 s warm-up, 20 samples); medians are in
//! `target/criterion/linear_solve_lu/<implementation>/<n>/new/estimates.json`.

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, BenchmarkId, Criterion, criterion_group, criterion_main};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::linalg::solvers::Solve;
use faer::{Mat, Par};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};
use std::hint::black_box;
use std::time::Duration;
use svi::linalg::sparse::{DenseSolver, LinearSolver, Pattern, SparseLu};
use svi::linalg::{DenseLu, solve_small};

/// Sizes of the runtime-sized comparison.
const SIZES: [usize; 11] = [2, 4, 8, 12, 16, 24, 32, 48, 64, 96, 128];

/// A fixed-seed linear congruential generator, uniform in [−½, ½).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// A diagonally dominant n×n matrix A, a solution x and b = A x.
fn system(n: usize) -> (DMatrix<f64>, DVector<f64>, DVector<f64>) {
    let mut random = Lcg(0x5eed ^ n as u64);
    let mut a = DMatrix::from_fn(n, n, |_, _| random.next());
    for i in 0..n {
        a[(i, i)] += n as f64;
    }
    let x = DVector::from_fn(n, |_, _| random.next());
    let b = &a * &x;
    (a, x, b)
}

/// Assert that `solution` is `x` to a tolerance fit for a well-conditioned system.
fn check(name: &str, n: usize, solution: impl Iterator<Item = f64>, x: &DVector<f64>) {
    let error = solution
        .zip(x.iter())
        .map(|(s, x)| (s - x).abs())
        .fold(0.0, f64::max);
    assert!(error < 1e-12, "{name} at n = {n}: error {error:e}");
}

/// faer's allocation-free LU: factor buffer, permutations and scratch allocated once.
struct FaerLu {
    factors: Mat<f64>,
    rhs: Mat<f64>,
    forward: Vec<usize>,
    inverse: Vec<usize>,
    scratch: MemBuffer,
}

impl FaerLu {
    fn new(n: usize) -> Self {
        let requirement = factor::lu_in_place_scratch::<usize, f64>(n, n, Par::Seq, default())
            .or(solve::solve_in_place_scratch::<usize, f64>(n, 1, Par::Seq));
        FaerLu {
            factors: Mat::zeros(n, n),
            rhs: Mat::zeros(n, 1),
            forward: vec![0; n],
            inverse: vec![0; n],
            scratch: MemBuffer::new(requirement),
        }
    }

    /// Copy in A and b, factor, solve; the solution is left in `self.rhs`.
    fn factor_solve(&mut self, a: &Mat<f64>, b: &Mat<f64>) {
        self.factors.copy_from(a);
        let (_, permutation) = factor::lu_in_place(
            self.factors.as_mut(),
            &mut self.forward,
            &mut self.inverse,
            Par::Seq,
            MemStack::new(&mut self.scratch),
            default(),
        );
        self.rhs.copy_from(b);
        solve::solve_in_place(
            self.factors.as_ref(),
            self.factors.as_ref(),
            permutation,
            self.rhs.as_mut(),
            Par::Seq,
            MemStack::new(&mut self.scratch),
        );
    }
}

/// faer's tuning parameters at their defaults.
fn default<T: Default>() -> T {
    T::default()
}

/// `svi_dense_lu/<n>`: [`DenseLu`] allocated once, then copy A in, factor, copy b in, solve
/// in place; checked against `x` before timing (a filter that skips the timing must not skip
/// the check).
fn svi_dense_lu(
    group: &mut BenchmarkGroup<'_, WallTime>,
    a: &DMatrix<f64>,
    x: &DVector<f64>,
    b: &DVector<f64>,
) {
    let n = a.nrows();
    let mut lu = DenseLu::new(n);
    let mut rhs = DVector::zeros(n);
    let factor_solve = |lu: &mut DenseLu, rhs: &mut DVector<f64>| {
        lu.matrix_mut().copy_from(black_box(a));
        lu.factor().expect("nonsingular");
        rhs.copy_from(black_box(b));
        lu.solve_in_place(rhs);
    };
    factor_solve(&mut lu, &mut rhs);
    check("svi_dense_lu", n, rhs.iter().copied(), x);
    group.bench_function(BenchmarkId::new("svi_dense_lu", n), |bencher| {
        bencher.iter(|| {
            factor_solve(&mut lu, &mut rhs);
            black_box(&rhs);
        })
    });
}

fn dense(c: &mut Criterion) {
    let mut group = c.benchmark_group("linear_solve/lu");
    for n in SIZES {
        let (a, x, b) = system(n);

        svi_dense_lu(&mut group, &a, &x, &b);

        let a_faer = Mat::from_fn(n, n, |i, j| a[(i, j)]);
        let b_faer = Mat::from_fn(n, 1, |i, _| b[i]);
        let mut faer_lu = FaerLu::new(n);
        faer_lu.factor_solve(&a_faer, &b_faer);
        check("faer_in_place", n, (0..n).map(|i| faer_lu.rhs[(i, 0)]), &x);
        group.bench_function(BenchmarkId::new("faer_in_place", n), |bencher| {
            bencher.iter(|| {
                faer_lu.factor_solve(black_box(&a_faer), black_box(&b_faer));
                black_box(&faer_lu.rhs);
            })
        });

        let solution = a_faer.partial_piv_lu().solve(&b_faer);
        check("faer_api", n, (0..n).map(|i| solution[(i, 0)]), &x);
        group.bench_function(BenchmarkId::new("faer_api", n), |bencher| {
            bencher.iter(|| {
                black_box(&a_faer)
                    .partial_piv_lu()
                    .solve(black_box(&b_faer))
            })
        });
    }
    group.finish();
}

/// The fixed-size solvers at one N, and DenseLu at the same size.
///
/// `nalgebra_solve` is nalgebra's `|a, b| a.lu().solve(b)`, passed in from a concrete N
/// because nalgebra's LU needs `DimMin` bounds that a const-generic N cannot state.
fn small_at<const N: usize>(
    group: &mut BenchmarkGroup<'_, WallTime>,
    nalgebra_solve: impl Fn(SMatrix<f64, N, N>, &SVector<f64, N>) -> Option<SVector<f64, N>>,
) {
    let (a, x, b) = system(N);
    let a_fixed = SMatrix::<f64, N, N>::from_fn(|i, j| a[(i, j)]);
    let b_fixed = SVector::<f64, N>::from_fn(|i, _| b[i]);

    let solution = solve_small(a_fixed, b_fixed).expect("nonsingular");
    check("solve_small", N, solution.iter().copied(), &x);
    group.bench_function(BenchmarkId::new("solve_small", N), |bencher| {
        bencher.iter(|| solve_small(black_box(a_fixed), black_box(b_fixed)))
    });

    let solution = nalgebra_solve(a_fixed, &b_fixed).expect("nonsingular");
    check("nalgebra_lu", N, solution.iter().copied(), &x);
    group.bench_function(BenchmarkId::new("nalgebra_lu", N), |bencher| {
        bencher.iter(|| nalgebra_solve(black_box(a_fixed), &black_box(b_fixed)))
    });

    svi_dense_lu(group, &a, &x, &b);
}

fn small(c: &mut Criterion) {
    let mut group = c.benchmark_group("linear_solve/small");
    small_at::<2>(&mut group, |a, b| a.lu().solve(b));
    small_at::<3>(&mut group, |a, b| a.lu().solve(b));
    small_at::<6>(&mut group, |a, b| a.lu().solve(b));
    group.finish();
}

/// The pattern of case (n, s, w) with diagonally dominant values from the LCG, and a
/// right-hand side.
fn coupled(n: usize, s: usize, w: usize) -> (Pattern, Vec<f64>, DVector<f64>) {
    let size = n * s;
    let mut entries = Vec::new();
    for i in 0..n {
        for j in i.saturating_sub(w)..(i + w + 1).min(n) {
            for a in 0..s {
                for b in 0..s {
                    entries.push((i * s + a, j * s + b));
                }
            }
        }
    }
    let pattern = Pattern::new(size, &entries).unwrap();
    let mut lcg = Lcg(7);
    let mut values = vec![0.0; pattern.len()];
    for &(row, col) in &entries {
        let slot = pattern.slot(row, col).unwrap();
        values[slot] = lcg.next() + if row == col { size as f64 } else { 0.0 };
    }
    let b = DVector::from_fn(size, |i, _| (i as f64 * 0.37).sin());
    (pattern, values, b)
}

fn pattern(c: &mut Criterion) {
    let mut group = c.benchmark_group("linear_solve/pattern");
    for (n, s, w) in [
        (6, 3, 5),
        (18, 3, 17),
        (18, 6, 17),
        (18, 12, 17),
        (40, 5, 39),
        (10, 5, 1),
        (40, 5, 1),
        (200, 5, 1),
        (40, 5, 4),
        (100, 3, 10),
        (20, 5, 1),
        (20, 5, 19),
        (12, 12, 11),
        (24, 6, 23),
        (30, 5, 29),
        (30, 5, 3),
        (4, 5, 1),
    ] {
        let (pattern, values, b) = coupled(n, s, w);
        let case = format!("n{n}s{s}w{w}");
        let mut dense = DenseSolver::default();
        let mut sparse = SparseLu::default();
        let mut reference = None;
        for (name, solver) in [
            ("dense", &mut dense as &mut dyn LinearSolver),
            ("sparse", &mut sparse),
        ] {
            solver.analyse(&pattern).unwrap();
            solver.factor(&pattern, &values).unwrap();
            let mut x = b.clone();
            solver.solve_in_place(&mut x).unwrap();
            let reference = reference.get_or_insert_with(|| x.clone());
            assert!((&x - &*reference).amax() < 1e-12, "{name} on {case}");
            let mut x = b.clone();
            group.bench_function(BenchmarkId::new(name, &case), |bencher| {
                bencher.iter(|| {
                    solver.factor(&pattern, black_box(&values)).unwrap();
                    x.copy_from(&b);
                    solver.solve_in_place(&mut x).unwrap();
                    black_box(&x);
                })
            });
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500))
        .sample_size(20);
    targets = dense, small, pattern
}
criterion_main!(benches);
