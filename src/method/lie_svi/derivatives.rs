//! ℓ(η, a, b) = L(R_k exp(η) exp(a), dexp_{−a} b), the Lagrangian at one quadrature point,
//! and its first two derivatives in (η, a, b) by num-dual (§5.3.2): the attitude and the body
//! angular velocity are built as 9-variable second-order duals from 3- and 6-variable ones,
//! so that the 9-variable arithmetic is spent on the user's Lagrangian alone; in the reduced
//! form (§5.4) only the (a, b) blocks of l(dexp_{−a} b).

use crate::model::rigid_body::RigidBodyLagrangian;
use crate::model::so3::{Matrix3, Vector3, body_velocity, exp};
use nalgebra::{Const, SMatrix, SVector};
use num_dual::{Derivative, Dual2Vec, hessian};

/// Value, gradient and Hessian of ℓ(η, a, b) at one quadrature point, variables ordered
/// (η, a, b).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PointDerivatives {
    pub(super) gradient: SVector<f64, 9>,
    pub(super) hessian: SMatrix<f64, 9, 9>,
}

impl PointDerivatives {
    pub(super) fn zeros() -> Self {
        PointDerivatives {
            gradient: SVector::zeros(),
            hessian: SMatrix::zeros(),
        }
    }
}

type D3 = Dual2Vec<f64, Const<3>>;
type D6 = Dual2Vec<f64, Const<6>>;
type D9 = Dual2Vec<f64, Const<9>>;

/// Value, gradient and Hessian of a second-order dual number.
fn parts<const K: usize>(
    x: &Dual2Vec<f64, Const<K>>,
) -> (f64, SVector<f64, K>, SMatrix<f64, K, K>) {
    let gradient = x.v1.unwrap_generic(Const::<1>, Const::<K>).transpose();
    let hessian = x.v2.unwrap_generic(Const::<K>, Const::<K>);
    (x.re, gradient, hessian)
}

/// A 9-variable second-order dual number from its parts.
fn assemble_dual(value: f64, gradient: SVector<f64, 9>, hessian: SMatrix<f64, 9, 9>) -> D9 {
    D9::new(
        value,
        Derivative::some(gradient.transpose()),
        Derivative::some(hessian),
    )
}

/// The body angular velocity Ω(a, b) = dexp_{−a} b as 9-variable duals in (η, a, b).
fn body_velocity_duals(a: &Vector3<f64>, b: &Vector3<f64>) -> Vector3<D9> {
    let (_, omega) = {
        let x = SVector::<f64, 6>::new(a[0], a[1], a[2], b[0], b[1], b[2]);
        let y: SVector<D6, 6> = SVector::from_fn(|i, _| D6::from_re(x[i]).derivative(i));
        let a = y.fixed_rows::<3>(0).into_owned();
        let b = y.fixed_rows::<3>(3).into_owned();
        ((), body_velocity(&a, &b))
    };
    omega.map(|w| {
        let (value, g6, h6) = parts(&w);
        let mut gradient = SVector::<f64, 9>::zeros();
        let mut hessian = SMatrix::<f64, 9, 9>::zeros();
        gradient.fixed_rows_mut::<6>(3).copy_from(&g6);
        hessian.fixed_view_mut::<6, 6>(3, 3).copy_from(&h6);
        assemble_dual(value, gradient, hessian)
    })
}

/// The attitude R_k exp(η) exp(a) as 9-variable duals in (η, a, b), exact to second order in
/// (η, a) at η = 0.
///
/// Built from exp(a) in 3-variable duals and f64 products, so the 9-variable arithmetic is
/// spent on the user's Lagrangian alone.
fn attitude_duals(r: &Matrix3<f64>, a: &Vector3<f64>) -> Matrix3<D9> {
    let x: Vector3<D3> = Vector3::from_fn(|i, _| D3::from_re(a[i]).derivative(i));
    let e = exp(&x);
    // Value, first and second derivatives of E = exp(a), entry by entry.
    let mut value = Matrix3::zeros();
    let mut first = [Matrix3::zeros(); 3];
    let mut second = [[Matrix3::zeros(); 3]; 3];
    for (k, z) in e.iter().enumerate() {
        let (re, g, h) = parts(z);
        value[k] = re;
        for m in 0..3 {
            first[m][k] = g[m];
            for n in 0..3 {
                second[m][n][k] = h[(m, n)];
            }
        }
    }
    let axes: [Matrix3<f64>; 3] =
        std::array::from_fn(|l| r * crate::model::so3::hat(&Vector3::ith(l, 1.0)));
    let base = r * value;
    let base_first: [Matrix3<f64>; 3] = std::array::from_fn(|m| r * first[m]);
    let base_second: [[Matrix3<f64>; 3]; 3] =
        std::array::from_fn(|m| std::array::from_fn(|n| r * second[m][n]));
    let moved: [Matrix3<f64>; 3] = std::array::from_fn(|l| axes[l] * value);
    let mixed: [[Matrix3<f64>; 3]; 3] =
        std::array::from_fn(|l| std::array::from_fn(|m| axes[l] * first[m]));
    // ∂²exp(η)/∂η_l∂η_m at 0 = ½(ê_l ê_m + ê_m ê_l).
    let generators: [Matrix3<f64>; 3] =
        std::array::from_fn(|l| crate::model::so3::hat(&Vector3::ith(l, 1.0)));
    let curvature: [[Matrix3<f64>; 3]; 3] = std::array::from_fn(|l| {
        std::array::from_fn(|m| {
            r * (generators[l] * generators[m] + generators[m] * generators[l]) * value * 0.5
        })
    });
    Matrix3::from_fn(|i, j| {
        let mut gradient = SVector::<f64, 9>::zeros();
        let mut hessian = SMatrix::<f64, 9, 9>::zeros();
        for l in 0..3 {
            gradient[l] = moved[l][(i, j)];
            gradient[3 + l] = base_first[l][(i, j)];
            for m in 0..3 {
                hessian[(l, 3 + m)] = mixed[l][m][(i, j)];
                hessian[(3 + m, l)] = mixed[l][m][(i, j)];
                hessian[(3 + l, 3 + m)] = base_second[l][m][(i, j)];
                hessian[(l, m)] = curvature[l][m][(i, j)];
            }
        }
        assemble_dual(base[(i, j)], gradient, hessian)
    })
}

/// ℓ(η, a, b) = L(R_k exp(η) exp(a), dexp_{−a} b) and its first two derivatives at (0, a, b)
/// (variables ordered (η, a, b); in the reduced form only the (a, b) blocks, with R = I).
pub(super) fn point_derivatives<L: RigidBodyLagrangian>(
    model: &L,
    reduced: bool,
    r: &Matrix3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
) -> PointDerivatives {
    if reduced {
        let x = SVector::<f64, 6>::new(a[0], a[1], a[2], b[0], b[1], b[2]);
        let identity = Matrix3::<D6>::identity();
        let (_, g, h) = hessian(
            |y: SVector<D6, 6>| {
                let a = y.fixed_rows::<3>(0).into_owned();
                let b = y.fixed_rows::<3>(3).into_owned();
                model.lagrangian(&identity, &body_velocity(&a, &b))
            },
            &x,
        );
        let mut out = PointDerivatives::zeros();
        out.gradient.fixed_rows_mut::<6>(3).copy_from(&g);
        out.hessian.fixed_view_mut::<6, 6>(3, 3).copy_from(&h);
        out
    } else {
        let attitude = attitude_duals(r, a);
        let omega = body_velocity_duals(a, b);
        let (_, gradient, hessian) = parts(&model.lagrangian(&attitude, &omega));
        PointDerivatives { gradient, hessian }
    }
}

/// Reference implementation of [`point_derivatives`] (full form) by one 9-variable Hessian
/// through both exponentials, for the tests.
#[cfg(test)]
fn point_derivatives_reference<L: RigidBodyLagrangian>(
    model: &L,
    r: &Matrix3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
) -> PointDerivatives {
    let x = SVector::<f64, 9>::from([0.0, 0.0, 0.0, a[0], a[1], a[2], b[0], b[1], b[2]]);
    let base = r.map(D9::from_re);
    let (_, gradient, hessian) = hessian(
        |y: SVector<D9, 9>| {
            let eta = y.fixed_rows::<3>(0).into_owned();
            let a = y.fixed_rows::<3>(3).into_owned();
            let b = y.fixed_rows::<3>(6).into_owned();
            let rotation = base * exp(&eta) * exp(&a);
            model.lagrangian(&rotation, &body_velocity(&a, &b))
        },
        &x,
    );
    PointDerivatives { gradient, hessian }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Pendulum;
    impl RigidBodyLagrangian for Pendulum {
        fn lagrangian<D: crate::scalar::Scalar>(&self, r: &Matrix3<D>, w: &Vector3<D>) -> D {
            let kinetic = (w[0] * w[0] + w[1] * w[1] * 1.5 + w[2] * w[2] * 2.0) * 0.5;
            // A deliberately nonlinear potential in R, and a coupling of R and Ω.
            let height = r[(2, 0)] * 0.1 + r[(2, 1)] * 0.05 - r[(2, 2)] * 0.5;
            kinetic - height * 9.81 + (r[(0, 1)] * w[2]).powi(2) * 0.3 + r[(1, 2)].sin()
        }
    }

    #[test]
    fn fast_point_derivatives_match_the_reference_hessian() {
        let r = exp(&Vector3::new(0.3, -0.7, 1.1));
        for (a, b) in [
            (Vector3::zeros(), Vector3::new(0.1, -0.2, 0.3)),
            (
                Vector3::new(1e-4, 2e-4, -1e-4),
                Vector3::new(0.1, -0.2, 0.3),
            ),
            (Vector3::new(0.2, -0.4, 0.5), Vector3::new(-1.0, 0.4, 2.0)),
        ] {
            let fast = point_derivatives(&Pendulum, false, &r, &a, &b);
            let reference = point_derivatives_reference(&Pendulum, &r, &a, &b);
            assert!((fast.gradient - reference.gradient).amax() < 1e-13);
            let difference = fast.hessian - reference.hessian;
            assert!(difference.amax() < 1e-13, "{difference}");
        }
    }
}
