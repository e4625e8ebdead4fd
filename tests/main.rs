//! Integration tests of `svi` (they may use the zoo, `svi-models`).
//!
//! All integration tests of this crate are modules of this one test binary (`cargo test
//! --release --test integration [FILTER]`): one link, and each generic function the tests
//! share is compiled once instead of once per file.

#[path = "common/allocations.rs"]
mod allocations;
#[path = "common/hostile_cases.rs"]
mod hostile_cases;

mod allocation;
mod any_size;
mod chaos;
mod classic_methods;
mod constraints;
mod convergence;
mod derivatives;
mod errors;
mod events;
mod field;
mod forces;
mod geometry;
mod hostile;
mod lie_group;
mod lie_groups;
mod local;
mod logh;
mod multiscale;
mod newton;
mod octave_call;
mod pendulum_chain;
mod polymer;
mod pseudospectral;
mod reparam;
mod sem;
mod sensitivity;
mod solve;
mod stability;
mod step_doubling;
mod stress;
mod text;
mod text_chain;
mod text_tangent;
