//! The two drivers of the sans-IO core: [`tokio`] for real buses and
//! [`sim`] for the deterministic virtual bus in simulated time.

pub mod sim;
pub(crate) mod tokio;
