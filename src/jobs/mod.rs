//! The job queue: statuses and the SQLite store.

mod status;
pub mod store;

pub use status::JobStatus;
pub use store::{CancelOutcome, Claimed, JobRow, StepJson, Store};
