//! What is learned from runs rather than produced by them: linear stability of a method
//! ([`stability`], Li–Wu–Leok §4), long-time energy drift ([`drift`]) and observed
//! convergence orders ([`verify`]).

pub mod drift;
pub mod stability;
pub mod verify;
