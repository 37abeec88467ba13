//! The paper's claims tested (Pomeau & Le Berre, *Critical speed-up vs critical slow-down*):
//! the one claim type ([`claims`]), the paper's quoted values set beside ours ([`quoted`]),
//! and the two analyses that exist to test its theory, the matched asymptotics
//! ([`asymptotics`]) and the Lyapunov analysis along the cycle ([`lyapunov`]), on one period
//! of the converged cycle re-ordered around its peak ([`cycle_period`]). The figures that
//! show them are the `stickslip` command's (`reproduce`).

pub mod asymptotics;
pub mod claims;
pub mod cycle_period;
pub mod lyapunov;
pub mod quoted;
