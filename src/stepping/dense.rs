//! Dense output of a whole solve on ℝᴺ: every accepted step's own polynomial, kept so that
//! the solution can be evaluated at any time of the span after the solve (`sol(t)`).
//!
//! A step of SVI or SC carries its interpolating polynomial of degree s − 1 (s points,
//! [`crate::Method::dense_output`]); a method without one is read off the cubic Hermite
//! polynomial of its end points (as output times are, [`super::solve`]). Either polynomial is
//! determined by its values at K = max(s, 4) points, so the step keeps (q, q̇) at the K
//! Chebyshev–Gauss points θ_j = (1 − cos((2j + 1)π/(2K)))/2 of the step (interior points: no
//! ambiguity between a step's end and the next step's start) and evaluates them by the
//! barycentric formula of the first kind's Chebyshev points,
//!
//! f(θ) = Σ_j w_j f_j/(θ − θ_j) / Σ_j w_j/(θ − θ_j),  w_j = (−1)^j sin((2j + 1)π/(2K)),
//!
//! which reproduces a polynomial of degree < K to rounding (Berrut & Trefethen 2004, §5):
//! evaluating the kept step at t gives the method's own dense output at t, and the method's
//! accuracy between steps. p is kept the same way, from the Legendre map at the K points: a
//! polynomial again for a constant mass (p = M q̇), an interpolant of the method's order of
//! accuracy otherwise.
//!
//! Cost: K (q, q̇, p) per step, each one evaluation of the step polynomial and the Legendre map.

use crate::error::Error;

/// The dense output of a solve ([`crate::solve::SolveOptions::dense`]): each accepted step's
/// polynomial, kept as its values at K Chebyshev–Gauss points (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct DenseOutput {
    dimension: usize,
    /// θ_j ∈ (0, 1): the sample points of a step, as fractions of it.
    nodes: Vec<f64>,
    /// The barycentric weights of `nodes`.
    weights: Vec<f64>,
    /// The start of each step, increasing; `ends[k]` is its end.
    starts: Vec<f64>,
    ends: Vec<f64>,
    /// (q, q̇, p) at the sample points, step by step, point by point, `dimension` each.
    q: Vec<f64>,
    v: Vec<f64>,
    p: Vec<f64>,
}

/// A point of the dense output: the position, velocity and momentum at a time.
#[derive(Debug, Clone, PartialEq)]
pub struct DensePoint {
    /// The time.
    pub t: f64,
    /// Configuration q(t).
    pub q: Vec<f64>,
    /// Velocity q̇(t).
    pub v: Vec<f64>,
    /// Momentum p(t).
    pub p: Vec<f64>,
}

impl DenseOutput {
    /// An empty dense output of points of `dimension` numbers, with `samples` points per
    /// step (at least 4: the cubic Hermite interpolant).
    pub(crate) fn new(dimension: usize, samples: usize) -> Self {
        let k = samples.max(4);
        let angle = |j: usize| (2 * j + 1) as f64 * std::f64::consts::PI / (2 * k) as f64;
        DenseOutput {
            dimension,
            nodes: (0..k).map(|j| 0.5 * (1.0 - angle(j).cos())).collect(),
            weights: (0..k)
                .map(|j| if j % 2 == 0 { 1.0 } else { -1.0 } * angle(j).sin())
                .collect(),
            starts: Vec::new(),
            ends: Vec::new(),
            q: Vec::new(),
            v: Vec::new(),
            p: Vec::new(),
        }
    }

    /// Room for `steps` more steps (their count known ahead: fixed steps).
    pub(crate) fn reserve(&mut self, steps: usize) {
        let values = steps.saturating_mul(self.nodes.len() * self.dimension);
        self.starts.reserve(steps);
        self.ends.reserve(steps);
        for buffer in [&mut self.q, &mut self.v, &mut self.p] {
            buffer.reserve(values);
        }
    }

    /// The number K of samples per step.
    pub(crate) fn samples(&self) -> usize {
        self.nodes.len()
    }

    /// The `j`-th sample time of the step from `t` to `end`.
    pub(crate) fn sample_time(&self, j: usize, t: f64, end: f64) -> f64 {
        t + self.nodes[j] * (end - t)
    }

    /// Add the (q, q̇, p) of the current step at its next sample time.
    pub(crate) fn push_sample(&mut self, q: &[f64], v: &[f64], p: &[f64]) {
        self.q.extend_from_slice(q);
        self.v.extend_from_slice(v);
        self.p.extend_from_slice(p);
    }

    /// Close the step from `t` to `end`, whose samples were pushed (all K of them).
    pub(crate) fn end_step(&mut self, t: f64, end: f64) {
        self.starts.push(t);
        self.ends.push(end);
        debug_assert_eq!(
            self.q.len(),
            self.starts.len() * self.nodes.len() * self.dimension
        );
    }

    /// The number of steps kept.
    pub fn steps(&self) -> usize {
        self.starts.len()
    }

    /// Forget the steps from the `steps`-th on (a rejected trial step of the adaptive modes).
    pub(crate) fn truncate(&mut self, steps: usize) {
        let values = steps * self.nodes.len() * self.dimension;
        self.starts.truncate(steps);
        self.ends.truncate(steps);
        self.q.truncate(values);
        self.v.truncate(values);
        self.p.truncate(values);
    }

    /// Forget the steps that start at or after `time` (a solve stopped inside a pair of trial
    /// steps).
    pub(crate) fn truncate_from(&mut self, time: f64) {
        let kept = self.starts.partition_point(|&start| start < time);
        self.truncate(kept);
    }

    /// The span covered: the first step's start and the last step's end (`None` before the
    /// first step).
    pub fn span(&self) -> Option<(f64, f64)> {
        Some((*self.starts.first()?, *self.ends.last()?))
    }

    /// The number of coordinates.
    pub fn dimension(&self) -> usize {
        self.dimension
    }

    /// The solution at `time`, read off the polynomial of the step that contains it (at a
    /// time where two steps meet, the later step).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`time`) for a non-finite time or one outside the span.
    pub fn at(&self, time: f64) -> Result<DensePoint, Error> {
        let mut point = DensePoint {
            t: time,
            q: vec![0.0; self.dimension],
            v: vec![0.0; self.dimension],
            p: vec![0.0; self.dimension],
        };
        self.evaluate(time, &mut point.q, &mut point.v, &mut point.p)?;
        Ok(point)
    }

    /// [`DenseOutput::at`] into the caller's buffers (`dimension` numbers each): no
    /// allocation.
    ///
    /// # Errors
    /// As [`DenseOutput::at`]; [`Error::InvalidParameter`] (`buffers`) for buffers of the
    /// wrong length.
    pub fn evaluate(
        &self,
        time: f64,
        q: &mut [f64],
        v: &mut [f64],
        p: &mut [f64],
    ) -> Result<(), Error> {
        let n = self.dimension;
        if q.len() != n || v.len() != n || p.len() != n {
            return Err(Error::invalid(
                "buffers",
                format!("must have {n} numbers each, the model's coordinates"),
            ));
        }
        let Some((first, last)) = self.span() else {
            return Err(Error::invalid("time", "the solve kept no step"));
        };
        if !(first..=last).contains(&time) {
            return Err(Error::invalid(
                "time",
                format!("{time:?} is outside the solved span [{first:?}, {last:?}]"),
            ));
        }
        let step = self
            .starts
            .partition_point(|&start| start <= time)
            .saturating_sub(1);
        let (t, end) = (self.starts[step], self.ends[step]);
        let theta = (time - t) / (end - t);
        let k = self.nodes.len();
        let base = step * k * n;
        let exact = self.nodes.iter().position(|&node| node == theta);
        for (out, values) in [(q, &self.q), (v, &self.v), (p, &self.p)] {
            let samples = &values[base..base + k * n];
            if let Some(j) = exact {
                out.copy_from_slice(&samples[j * n..(j + 1) * n]);
                continue;
            }
            out.fill(0.0);
            let mut denominator = 0.0;
            for (j, (node, weight)) in self.nodes.iter().zip(&self.weights).enumerate() {
                let c = weight / (theta - node);
                denominator += c;
                for (o, x) in out.iter_mut().zip(&samples[j * n..(j + 1) * n]) {
                    *o += c * x;
                }
            }
            for o in out.iter_mut() {
                *o /= denominator;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A polynomial of degree K − 1 kept on two steps is reproduced to rounding anywhere in
    /// them, its derivative too; times outside the span are refused.
    #[test]
    fn reproduces_polynomials_of_degree_below_the_sample_count() {
        let f = |t: f64| 1.0 - 2.0 * t + 0.5 * t.powi(3) - 0.25 * t.powi(5);
        let df = |t: f64| -2.0 + 1.5 * t * t - 1.25 * t.powi(4);
        let mut dense = DenseOutput::new(1, 6);
        for (t, end) in [(0.0, 0.7), (0.7, 1.5)] {
            for j in 0..dense.samples() {
                let s = dense.sample_time(j, t, end);
                dense.push_sample(&[f(s)], &[df(s)], &[2.0 * df(s)]);
            }
            dense.end_step(t, end);
        }
        for &time in &[0.0, 0.1, 0.35, 0.7, 1.0, 1.2345, 1.5] {
            let point = dense.at(time).unwrap();
            assert!(
                (point.q[0] - f(time)).abs() < 1e-14,
                "{time}: {}",
                point.q[0] - f(time)
            );
            assert!((point.v[0] - df(time)).abs() < 1e-14);
            assert!((point.p[0] - 2.0 * df(time)).abs() < 1e-14);
        }
        for bad in [-1e-9, 1.5 + 1e-9, f64::NAN] {
            assert!(
                matches!(dense.at(bad), Err(Error::InvalidParameter { .. })),
                "{bad}"
            );
        }
        dense.truncate_from(0.7);
        assert_eq!(dense.steps(), 1);
        assert_eq!(dense.span(), Some((0.0, 0.7)));
    }
}
