//! What is learned from runs rather than produced by them: linear stability of a method
//! ([`stability`], Li–Wu–Leok §4), long-time energy drift ([`drift`]) and observed
//! convergence orders ([`verify`]), derivatives of whole runs with respect to the initial
//! state and the model's parameters ([`sensitivity`]), and chaos indicators from the exact tangent maps of a
//! run — Lyapunov exponents, MEGNO, SALI and GALI ([`chaos`]).

pub mod chaos;
pub mod drift;
pub mod sensitivity;
pub mod stability;
pub mod verify;
