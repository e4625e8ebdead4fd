//! Linear stability on the harmonic oscillator (Li, Wu, Leok 2018, §4 and Figs. 3–6).
//!
//! The stability matrices from the methods' tangent maps are checked against the closed forms
//! S₁ (eq. 34) and S₂ (eq. 37), derived again in `svi::stability`; S₂ also against the stability
//! function of the equivalent collocation Runge–Kutta method, built here from its Butcher
//! tableau. Region boundaries are checked against independent computations: hand derivations,
//! bisection on the closed forms, and 40-digit mpmath evaluations of the same closed forms with
//! exact quadrature (reference values quoted below, each with its source).
//!
//! Run with `cargo test --release --test integration stability:: -- --nocapture` to see the regions of every
//! configuration of Figs. 3–6.

use nalgebra::{Complex, DMatrix, DVector, Matrix2};
use svi::basis::{LagrangeBasis, chebyshev_gauss_lobatto};
use svi::quadrature::GaussLegendre;
use svi::stability::{
    Interval, StabilityReport, analyse, collocation_closed_form, stability_matrix, svi_closed_form,
};
use svi::{Error, SpectralCollocation, Svi};

/// The z grid of the comparisons: both sides of the linear SVI's bound 12, and up to 900.
const GRID: [f64; 10] = [0.01, 0.1, 1.0, 4.0, 11.9, 12.1, 50.0, 100.0, 400.0, 900.0];

/// (CGL points, Gauss points) of the SVI configurations compared.
const SVI_CONFIGURATIONS: [(usize, usize); 7] =
    [(2, 2), (5, 4), (5, 10), (9, 8), (9, 18), (4, 3), (6, 12)];

/// CGL points of the SC configurations compared.
const SC_POINTS: [usize; 3] = [3, 5, 9];

/// The range of Figs. 3–6, from just above 0, sampled about once per unit of z.
const Z_MIN: f64 = 1e-6;
const Z_MAX: f64 = 900.0;
const SAMPLES: usize = 900;

fn svi(points: usize, quadrature: usize) -> Svi {
    Svi::new(points).with_quadrature(quadrature)
}

/// max |a − b| relative to the size of a (at least 1).
fn relative_difference(a: &Matrix2<f64>, b: &Matrix2<f64>) -> f64 {
    (a - b).amax() / a.amax().max(1.0)
}

fn ends(intervals: &[Interval]) -> Vec<(f64, f64)> {
    intervals.iter().map(|i| (i.lower, i.upper)).collect()
}

/// Assert that `intervals` has the ends `expected`, each to `tolerance`.
fn assert_intervals(name: &str, intervals: &[Interval], expected: &[(f64, f64)], tolerance: f64) {
    assert_eq!(
        intervals.len(),
        expected.len(),
        "{name}: {:?} vs {expected:?}",
        ends(intervals)
    );
    for (interval, &(lower, upper)) in intervals.iter().zip(expected) {
        assert!(
            (interval.lower - lower).abs() <= tolerance
                && (interval.upper - upper).abs() <= tolerance,
            "{name}: {interval:?} vs ({lower}, {upper})"
        );
    }
}

fn print_report(name: &str, report: &StabilityReport) {
    println!(
        "{name}: A-stable {}, P-stable {}",
        report.a_stable, report.p_stable
    );
    println!("  R_s = {:?}", ends(&report.stable));
    println!("  R_p = {:?}", ends(&report.periodic));
    println!("  R_q = {:?}", ends(&report.strongly_stable));
}

#[test]
fn svi_closed_form_matches_tangent_map() {
    for (points, quadrature) in SVI_CONFIGURATIONS {
        for z in GRID {
            let closed = svi_closed_form(points, quadrature, z).unwrap();
            let tangent = stability_matrix(&svi(points, quadrature), z).unwrap();
            let difference = relative_difference(&closed, &tangent);
            assert!(
                difference <= 1e-12,
                "Cheb {points}/Gau {quadrature}, z = {z}: {difference:e}\n{closed}{tangent}"
            );
        }
    }
}

#[test]
fn collocation_closed_form_matches_tangent_map() {
    for points in SC_POINTS {
        for z in GRID {
            let closed = collocation_closed_form(points, z).unwrap();
            let tangent = stability_matrix(&SpectralCollocation::new(points), z).unwrap();
            let difference = relative_difference(&closed, &tangent);
            assert!(
                difference <= 1e-12,
                "SC {points}, z = {z}: {difference:e}\n{closed}{tangent}"
            );
        }
    }
}

/// SVI is symplectic: det S₁ = 1 (Fig. 5, left and middle).
#[test]
fn svi_determinant_is_one() {
    for (points, quadrature) in SVI_CONFIGURATIONS {
        for z in GRID {
            let closed = svi_closed_form(points, quadrature, z)
                .unwrap()
                .determinant();
            let tangent = stability_matrix(&svi(points, quadrature), z)
                .unwrap()
                .determinant();
            for det in [closed, tangent] {
                assert!(
                    (det - 1.0).abs() <= 1e-12,
                    "Cheb {points}/Gau {quadrature}, z = {z}: det = {det}"
                );
            }
        }
    }
}

/// SC is the s-stage collocation Runge–Kutta method with nodes c_i = (1 + x_i)/2, i = 1..s,
/// so S₂(z) is similar to R(hJ) with J = [[0, 1], [−1, 0]]: tr S₂ = 2 Re R(i√z) and
/// det S₂ = |R(i√z)|², with R(w) = 1 + w bᵀ(I − wA)⁻¹1 from the Butcher tableau
/// a_ij = ∫₀^{c_i} ℓ_j, b_j = ∫₀¹ ℓ_j (integrated here with Gauss–Legendre rules).
#[test]
fn collocation_matches_the_runge_kutta_stability_function() {
    for points in SC_POINTS {
        let s = points - 1;
        let nodes: Vec<f64> = chebyshev_gauss_lobatto(points).unwrap()[1..]
            .iter()
            .map(|x| 0.5 * (x + 1.0))
            .collect();
        let basis = LagrangeBasis::new(nodes.clone()).unwrap();
        let gauss = GaussLegendre::new(s).unwrap();
        // ∫₀^c ℓ_j for every j.
        let integrals = |c: f64| {
            let points: Vec<f64> = gauss.nodes().iter().map(|x| 0.5 * c * (x + 1.0)).collect();
            let values = basis.value_matrix(&points);
            let weights = DVector::from_iterator(s, gauss.weights().iter().map(|w| 0.5 * c * w));
            values.transpose() * weights
        };
        let a = DMatrix::from_fn(s, s, |i, j| integrals(nodes[i])[j]);
        let b = integrals(1.0);
        for z in GRID {
            let w = Complex::new(0.0, z.sqrt());
            let system = DMatrix::from_fn(s, s, |i, j| {
                let identity = if i == j { 1.0 } else { 0.0 };
                Complex::new(identity, 0.0) - w * a[(i, j)]
            });
            let stages = system
                .lu()
                .solve(&DVector::from_element(s, Complex::new(1.0, 0.0)))
                .unwrap();
            let r = Complex::new(1.0, 0.0)
                + w * stages
                    .iter()
                    .zip(b.iter())
                    .map(|(k, b)| k * *b)
                    .sum::<Complex<f64>>();
            let closed = collocation_closed_form(points, z).unwrap();
            assert!(
                (closed.determinant() - r.norm_sqr()).abs() <= 1e-12,
                "SC {points}, z = {z}: det {} vs |R|² {}",
                closed.determinant(),
                r.norm_sqr()
            );
            assert!(
                (closed.trace() - 2.0 * r.re).abs() <= 1e-12,
                "SC {points}, z = {z}: tr {} vs 2 Re R {}",
                closed.trace(),
                2.0 * r.re
            );
        }
    }
}

/// det S₂ (Fig. 5, right): with 3 CGL points it is below 1 and decreasing on the whole grid;
/// with 5 and 9 it first rises above 1 (ρ > 1: weakly unstable) and only falls below 1 beyond
/// z = 16 (5 points) and z = 29.93 (9 points). Exact for 5 points (sympy, from the collocation
/// stability function): det S₂ − 1 = z³(16 − z)/(147456 |D(i√z)|²), D(w) = 1 − 5w/8 + 17w²/96
/// − 11w³/384 + w⁴/384, so det S₂ − 1 ≈ z³/9216 for small z.
#[test]
fn collocation_determinant_rises_above_one_before_it_falls() {
    let det = |points: usize, z: f64| collocation_closed_form(points, z).unwrap().determinant();
    for pair in GRID.windows(2) {
        assert!(det(3, pair[0]) < 1.0 - 1e-6, "SC 3, z = {}", pair[0]);
        assert!(det(3, pair[1]) < det(3, pair[0]), "SC 3 at {pair:?}");
    }
    for z in GRID.into_iter().filter(|&z| z <= 12.1) {
        let denominator = Complex::new(0.0, z.sqrt());
        let d = Complex::new(1.0, 0.0) - denominator * 5.0 / 8.0
            + denominator.powi(2) * 17.0 / 96.0
            - denominator.powi(3) * 11.0 / 384.0
            + denominator.powi(4) / 384.0;
        let exact = z.powi(3) * (16.0 - z) / (147456.0 * d.norm_sqr());
        let excess = det(5, z) - 1.0;
        assert!(excess > 0.0, "SC 5, z = {z}: det − 1 = {excess:e}");
        assert!(
            (excess - exact).abs() <= 1e-14 + 1e-10 * exact,
            "SC 5, z = {z}: det − 1 = {excess:e}, exact {exact:e}"
        );
    }
    assert!((det(5, 12.0) - 1.031).abs() < 1e-3, "the hump of SC 5");
    for z in [1.0, 4.0, 11.9, 12.1] {
        assert!(
            det(9, z) > 1.0 + 1e-11,
            "SC 9, z = {z}: det = {}",
            det(9, z)
        );
    }
    // Below z ≈ 0.4 the excess of SC 9 (about 1e−10 z⁵) is below round-off.
    for z in [0.01, 0.1] {
        assert!((det(9, z) - 1.0).abs() < 1e-13, "SC 9, z = {z}");
    }
    let large: Vec<f64> = GRID.into_iter().filter(|&z| z >= 50.0).collect();
    for points in [5, 9] {
        for pair in large.windows(2) {
            assert!(
                det(points, pair[0]) < 1.0 - 1e-3,
                "SC {points}, z = {}",
                pair[0]
            );
            assert!(
                det(points, pair[1]) < det(points, pair[0]),
                "SC {points} at {pair:?}"
            );
        }
    }
}

/// Degree 1 with 2 Gauss points: tr S₁ = 2 − 6z/(6 + z) and det S₁ = 1, so ρ = 1 exactly for
/// 0 < z ≤ 12 and ρ > 1 beyond: the bound hσ < 2√3 of Porcù and Penati's slides.
#[test]
fn linear_svi_with_two_gauss_points_is_stable_exactly_up_to_twelve() {
    let report = analyse(&svi(2, 2), Z_MIN, Z_MAX, SAMPLES).unwrap();
    print_report("Cheb 2 / Gau 2", &report);
    assert_intervals("R_s", &report.stable, &[(Z_MIN, 12.0)], 1e-9);
    assert_intervals("R_p", &report.periodic, &[(Z_MIN, 12.0)], 1e-9);
    assert!(report.strongly_stable.is_empty());
    assert!(!report.a_stable && !report.p_stable);
    for point in &report.points {
        let trace = 2.0 - 6.0 * point.z / (6.0 + point.z);
        assert!((point.trace - trace).abs() <= 1e-13, "z = {}", point.z);
        assert_eq!(point.is_stable(), point.z <= 12.0, "z = {}", point.z);
    }
}

/// With as many Gauss points as the degree, SVI is the Gauss–Legendre collocation method: it
/// conserves q² + p², so ρ = 1 for every z.
#[test]
fn gauss_collocation_svi_is_a_stable_and_p_stable() {
    for (points, quadrature) in [(5, 4), (9, 8)] {
        let report = analyse(&svi(points, quadrature), Z_MIN, Z_MAX, SAMPLES).unwrap();
        for point in &report.points {
            assert!(
                (point.rho - 1.0).abs() <= 1e-12,
                "Cheb {points}/Gau {quadrature}, z = {}: ρ = {}",
                point.z,
                point.rho
            );
        }
        assert!(report.a_stable && report.p_stable);
        assert_intervals("R_s", &report.stable, &[(Z_MIN, Z_MAX)], 0.0);
        assert_intervals("R_p", &report.periodic, &[(Z_MIN, Z_MAX)], 0.0);
        assert!(report.strongly_stable.is_empty());
    }
}

/// The 4-stage Gauss method's stability function is the (4, 4) Padé approximant P(w)/P(−w),
/// P(w) = 1 + w/2 + 3w²/28 + w³/84 + w⁴/1680. It is −1 where Re P(i√z) = 0,
/// z = 90 ∓ √6420, and +1 where Im P(i√z) = 0, z = 42: there Cheb 5 / Gau 4 has S = ∓I
/// (tr² = 4 det: isolated points that Definition 4.1 leaves out of R_p).
#[test]
fn gauss_collocation_svi_resonances_are_plus_minus_identity() {
    for (z, sign) in [
        (90.0 - 6420f64.sqrt(), -1.0),
        (42.0, 1.0),
        (90.0 + 6420f64.sqrt(), -1.0),
    ] {
        let matrix = stability_matrix(&svi(5, 4), z).unwrap();
        let difference = (matrix - Matrix2::identity() * sign).amax();
        assert!(difference <= 1e-13, "z = {z}: {matrix}");
    }
}

/// Cheb 5 / Gau 10 leaves R_s first on a narrow band just above (π)², ending exactly at the
/// first resonance 90 − √6420 of Cheb 5 / Gau 4. The Brent boundaries of `analyse` (sampling
/// about once per unit of z) are compared with bisection (200 halvings) on |tr S₁| − 2 of the
/// closed form, after a scan with step 1e−4, and with 40-digit mpmath values.
#[test]
fn cheb5_gau10_first_instability_band() {
    let margin = |z: f64| svi_closed_form(5, 10, z).unwrap().trace().abs() - 2.0;
    let bisect = |mut stable: f64, mut unstable: f64| {
        for _ in 0..200 {
            let middle = 0.5 * (stable + unstable);
            if margin(middle) <= 0.0 {
                stable = middle;
            } else {
                unstable = middle;
            }
        }
        0.5 * (stable + unstable)
    };
    let grid: Vec<f64> = (0..2000).map(|i| 9.8 + 1e-4 * i as f64).collect();
    let first = grid.iter().position(|&z| margin(z) > 0.0).unwrap();
    let last = first
        + grid[first..]
            .iter()
            .position(|&z| margin(z) <= 0.0)
            .unwrap();
    let lower = bisect(grid[first - 1], grid[first]);
    let upper = bisect(grid[last], grid[last - 1]);
    // mpmath, 40 digits: 9.8697496213168164426 and 9.8750975039594821973.
    assert!((lower - 9.869_749_621_316_816).abs() < 1e-9, "{lower}");
    assert!((upper - (90.0 - 6420f64.sqrt())).abs() < 1e-9, "{upper}");

    let report = analyse(&svi(5, 10), Z_MIN, Z_MAX, SAMPLES).unwrap();
    println!("Cheb 5 / Gau 10: first unstable band ({lower}, {upper}) by bisection");
    println!("  analyse: R_s begins {:?}", &ends(&report.stable)[..2]);
    assert_eq!(report.stable[0].lower, Z_MIN);
    assert!(
        (report.stable[0].upper - lower).abs() < 1e-9,
        "{:?}",
        report.stable[0]
    );
    assert!(
        (report.stable[1].lower - upper).abs() < 1e-9,
        "{:?}",
        report.stable[1]
    );
    assert!(!report.a_stable);
}

/// The configurations of Figs. 3–6 on z ∈ [1e−6, 900]. References: SVI boundaries from 40-digit
/// mpmath bisection on |tr S₁| − 2 of the closed form with exact integrals (the Gauss rules with
/// 2·(points) nodes are exact on the oscillator); SC boundaries from the collocation stability
/// function (16 exactly, by sympy; 29.933937906047729 by mpmath). The edges of the round-off
/// band (det S − 1 = ±1e−12, near 0) are only determined to the accuracy of det S itself.
#[test]
fn figure_configurations() {
    let resonances = [90.0 - 6420f64.sqrt(), 90.0 + 6420f64.sqrt()];
    let cases = [
        (5, 4, vec![(Z_MIN, Z_MAX)]),
        (
            5,
            10,
            vec![
                (Z_MIN, 9.869_749_621_316_816),
                (resonances[0], 39.764_868_490_666_71),
                (42.0, 102.130_250_378_683_18),
                (resonances[1], 380.235_131_509_333_3),
            ],
        ),
        (9, 8, vec![(Z_MIN, Z_MAX)]),
        (
            9,
            18,
            vec![
                (Z_MIN, 39.478_419_427_932_9),
                (39.478_473_394_663_13, 88.829_468_174_796_81),
                (88.863_797_576_801_92, 158.255_151_672_165_1),
                (159.991_915_542_552_96, 254.417_841_743_615_7),
                (275.769_713_496_609_5, 422.820_418_724_170_9),
                (570.529_611_062_783_9, 878.883_085_680_495_5),
            ],
        ),
    ];
    for (points, quadrature, expected) in cases {
        let name = format!("Cheb {points} / Gau {quadrature}");
        let report = analyse(&svi(points, quadrature), Z_MIN, Z_MAX, SAMPLES).unwrap();
        print_report(&name, &report);
        // The band (39.478419, 39.478473) of Cheb 9 / Gau 18 rises only 4.6e−12 above
        // |tr| = 2: its ends are conditioned at the 1e−10 level in double precision.
        let tolerance = if points == 9 { 2e-9 } else { 1e-9 };
        assert_intervals(&name, &report.stable, &expected, tolerance);
        assert_eq!(
            report.periodic, report.stable,
            "{name}: symplectic, so R_p = R_s"
        );
        assert!(
            report.strongly_stable.is_empty(),
            "{name}: det = 1, never strongly stable"
        );
        assert_eq!(report.a_stable, expected.len() == 1);
        assert_eq!(report.p_stable, expected.len() == 1);
    }

    let sc5 = analyse(&SpectralCollocation::new(5), Z_MIN, Z_MAX, SAMPLES).unwrap();
    let sc9 = analyse(&SpectralCollocation::new(9), Z_MIN, Z_MAX, SAMPLES).unwrap();
    print_report("SC 5", &sc5);
    print_report("SC 9", &sc9);
    // Round-off band: det S₂ − 1 ≈ z³/9216 (SC 5) and ≈ 1.01e−10 z⁵ (SC 9) reaches 1e−12.
    for (report, edge, crossing) in [
        (&sc5, 0.002_096_6, 16.0),
        (&sc9, 0.397, 29.933_937_906_047_73),
    ] {
        assert_eq!(report.stable.len(), 2);
        assert_eq!(report.stable[0].lower, Z_MIN);
        assert!(
            (report.stable[0].upper / edge - 1.0).abs() < 0.02,
            "{:?}",
            report.stable
        );
        assert_intervals(
            "R_s beyond the hump",
            &report.stable[1..],
            &[(crossing, Z_MAX)],
            1e-9,
        );
        assert_eq!(report.periodic, report.stable[..1]);
        assert_intervals("R_q", &report.strongly_stable, &[(crossing, Z_MAX)], 1e-9);
        assert!(!report.a_stable && !report.p_stable);
    }
}

#[test]
fn bad_inputs_give_typed_errors() {
    fn name<T: std::fmt::Debug>(result: Result<T, Error>) -> String {
        match result {
            Err(Error::InvalidParameter { name, .. }) => name,
            other => panic!("expected InvalidParameter, got {other:?}"),
        }
    }
    let method = svi(5, 10);
    for z in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(name(stability_matrix(&method, z)), "z");
        assert_eq!(name(svi_closed_form(5, 10, z)), "z");
        assert_eq!(name(collocation_closed_form(5, z)), "z");
    }
    assert_eq!(name(analyse(&method, 0.0, 900.0, 900)), "z_min");
    assert_eq!(name(analyse(&method, f64::NAN, 900.0, 900)), "z_min");
    assert_eq!(name(analyse(&method, 1.0, f64::INFINITY, 900)), "z_max");
    assert_eq!(name(analyse(&method, 900.0, 1.0, 900)), "z_max");
    assert_eq!(name(analyse(&method, 1.0, 1.0, 900)), "z_max");
    assert_eq!(name(analyse(&method, 1.0, 900.0, 1)), "samples");
    assert_eq!(name(analyse(&Svi::new(1), 1.0, 900.0, 900)), "points");
    assert_eq!(name(svi_closed_form(1, 2, 1.0)), "points");
    assert_eq!(name(svi_closed_form(5, 0, 1.0)), "quadrature");
    assert_eq!(name(collocation_closed_form(1, 1.0)), "points");
    let no_iterations = SpectralCollocation::new(5).with_max_iterations(0);
    assert_eq!(
        name(stability_matrix(&no_iterations, 1.0)),
        "max_iterations"
    );
    // One Gauss point for degree 4: the stage system is singular for every z. The method and
    // the closed form both refuse it up front, naming the quadrature.
    let underintegrated = svi(5, 1);
    assert_eq!(name(stability_matrix(&underintegrated, 1.0)), "quadrature");
    assert_eq!(name(analyse(&underintegrated, 0.1, 1.0, 10)), "quadrature");
    assert_eq!(name(svi_closed_form(5, 1, 1.0)), "quadrature");
}
