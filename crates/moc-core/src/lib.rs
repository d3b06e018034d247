//! TSNet's method-of-characteristics (MOC) time loop over a whole pipe network.
//!
//! `burstloc.sim.moc_layout` lays a TSNet model out as flat arrays (every pipe's points in
//! one array, the pipe ends grouped by boundary kind); [`Model::run`] steps it in time with
//! the equations of TSNet 0.3.1's `MOCSimulator` (steady friction), each expression in the
//! order of operations of burstloc's vectorized NumPy solver (`burstloc.sim.moc`), which is
//! TSNet's: the heads are that solver's to the last bit.
//!
//! Two details keep them so:
//! * squares are the C library's `pow(x, 2)` ([`pow2`]), as TSNet's scalar arithmetic
//!   computes them: it differs from `x * x` in the last place for about one value in a
//!   thousand;
//! * a junction's sum over its pipes adds in `np.dot`'s order (OpenBLAS's four lanes, given
//!   per entry by the caller as [`Contribution::lane`]).

mod model;
mod pow;
mod step;

pub use model::{
    Contribution, DeadEnd, Element, ElementKind, End, Junction, Model, Output, Pipe, Reservoir,
    ValveEnd,
};
pub use pow::pow2;

/// A model whose arrays do not fit together (an index out of range, a series too short); the
/// message names the array and the entry.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error(pub String);

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Error {}

/// TSNet's tolerance: a quadratic's discriminant above `-ROOT_TOLERANCE` counts as zero.
pub const ROOT_TOLERANCE: f64 = 1.0e-7;
/// TSNet's gravitational acceleration, m/s².
pub const G: f64 = 9.8;
