//! Tests of the model zoo against exact solutions and the registry.
//!
//! All integration tests of this crate are modules of this one test binary (`cargo test
//! --release --test integration [FILTER]`): one link, and each generic function the tests
//! share is compiled once instead of once per file.

mod exact_solutions;
mod forced_models;
mod group_models;
mod hamiltonian_models;
mod registry;
mod restricted_three_body;
mod rigid_models;
