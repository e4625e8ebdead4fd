//! The one stepping loop and what drives it: the time grid ([`grid`]), runs with recovery and
//! observers ([`run`], [`rigid_body`]), output times and adaptivity ([`solve`]), and the
//! observers themselves ([`observer`], [`rigid_observer`]).

pub mod grid;
pub mod observer;
pub mod rigid_body;
pub mod rigid_observer;
pub mod run;
pub mod solve;
