//! The job queue: what may be queued, statuses, failures and the store
//! (SQLite or PostgreSQL).

pub mod admission;
pub mod failure;
mod status;
pub mod store;

pub use failure::{Failure, FailureKind};
pub use status::JobStatus;
pub use store::{
    Backend, CancelOutcome, Claimed, DeleteOutcome, Earlier, Inserted, JobRow, NewJob, Requeued,
    StepHead, StepPart, Store,
};
