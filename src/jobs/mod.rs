//! The job queue: what may be queued, statuses, failures and the SQLite
//! store.

pub mod admission;
mod failure;
mod status;
pub mod store;

pub use failure::{Failure, FailureKind};
pub use status::JobStatus;
pub use store::{CancelOutcome, Claimed, Earlier, Inserted, JobRow, NewJob, Store};
