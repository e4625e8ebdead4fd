//! The one stepping loop, for every method on every space: the time grid ([`grid`]), runs
//! with recovery, divergence limit and observers ([`run`]), output times and step or degree
//! adaptivity on the same loop ([`solve`]), runs by the exact tangent map for chaos indicators
//! ([`tangent`]), and the observers ([`observer`], with the rigid-body
//! ones in [`rigid_observer`]).

pub mod adapt;
pub mod dense;
pub mod event;
pub mod grid;
pub mod group_observer;
pub mod logh;
pub mod observer;
mod outputs;
pub mod reparam;
pub mod rigid_observer;
pub mod run;
pub mod sem;
pub mod solve;
pub mod tangent;
