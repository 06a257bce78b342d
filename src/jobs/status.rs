//! The one place that names a job's status.

use serde::{Deserialize, Serialize};

/// Life cycle: `queued -> running -> succeeded | failed | cancelled`; a
/// running job whose worker vanished goes back to `queued` (its lease
/// expires) or to `failed` once it has used all its attempts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JobStatus {
    Queued,
    Running,
    Succeeded,
    Failed,
    Cancelled,
}

impl JobStatus {
    pub const ALL: [JobStatus; 5] = [
        JobStatus::Queued,
        JobStatus::Running,
        JobStatus::Succeeded,
        JobStatus::Failed,
        JobStatus::Cancelled,
    ];

    pub const fn as_str(self) -> &'static str {
        match self {
            JobStatus::Queued => "queued",
            JobStatus::Running => "running",
            JobStatus::Succeeded => "succeeded",
            JobStatus::Failed => "failed",
            JobStatus::Cancelled => "cancelled",
        }
    }

    pub fn parse(s: &str) -> Option<JobStatus> {
        JobStatus::ALL.into_iter().find(|j| j.as_str() == s)
    }

    /// Whether the job will not change any more.
    pub fn is_final(self) -> bool {
        matches!(
            self,
            JobStatus::Succeeded | JobStatus::Failed | JobStatus::Cancelled
        )
    }
}

/// A stored status name (rows are read through this; both databases keep
/// the name as text).
impl TryFrom<String> for JobStatus {
    type Error = String;

    fn try_from(name: String) -> Result<JobStatus, String> {
        JobStatus::parse(&name).ok_or_else(|| format!("unknown job status {name:?}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_match_serde() {
        for s in JobStatus::ALL {
            assert_eq!(JobStatus::parse(s.as_str()), Some(s));
            assert_eq!(serde_json::to_value(s).unwrap(), s.as_str());
        }
    }

    #[test]
    fn names_match_the_schema_check_constraint() {
        let list = JobStatus::ALL
            .map(|s| format!("'{}'", s.as_str()))
            .join(", ");
        for schema in [
            include_str!("../../migrations/sqlite/0001_jobs.sql"),
            include_str!("../../migrations/postgres/0001_jobs.sql"),
        ] {
            assert!(schema.contains(&format!("status IN ({list})")), "{list}");
        }
    }
}
