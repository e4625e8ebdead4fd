//! The commands of `svi` besides the scene run: work–precision sweeps (`bench`), linear
//! stability (`stability`) and stress tests (`stress`).

pub mod bench;
pub mod stability;
pub mod stress;
