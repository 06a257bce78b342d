//! Jobs and their results in SQLite: every statement the service runs.
//!
//! Claiming is one compare-and-set `UPDATE ... RETURNING`, never a SELECT
//! followed by an UPDATE: in SQLite a deferred transaction doing both gives
//! `database is locked` under competing workers, which busy_timeout does not
//! cure. A claimed job carries a lease (owner, expiry) that its worker renews
//! while it runs; a job whose lease expired is claimable again, up to the
//! attempt limit.
//!
//! The few statements assembled with `format!` insert only constants of this
//! module (column lists, status names from [`JobStatus`]); every value from a
//! request is a bind parameter.

use std::path::Path;
use std::str::FromStr;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use sqlx::query::Query;
use sqlx::sqlite::{
    SqliteArguments, SqliteConnectOptions, SqliteJournalMode, SqlitePoolOptions, SqliteSynchronous,
};
use sqlx::{AssertSqlSafe, FromRow, Sqlite, SqliteExecutor, SqlitePool};

use super::{Failure, FailureKind, JobStatus};
use crate::step::StoredStep;

/// Unix time in seconds.
pub fn now() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default()
        .as_secs_f64()
}

/// A row of `jobs`, without the case text.
#[derive(Debug, Clone, FromRow)]
pub struct JobRow {
    pub id: i64,
    pub status: JobStatus,
    pub title: Option<String>,
    pub points: i64,
    pub load_steps: i64,
    pub steps_done: i64,
    pub newton_iterations: i64,
    pub attempts: i64,
    pub cancel_requested: bool,
    pub created_at: f64,
    pub started_at: Option<f64>,
    pub finished_at: Option<f64>,
    pub solve_seconds: Option<f64>,
    pub error: Option<String>,
}

const QUEUED: &str = JobStatus::Queued.as_str();
const RUNNING: &str = JobStatus::Running.as_str();
const CANCELLED: &str = JobStatus::Cancelled.as_str();

const JOB_COLUMNS: &str = "id, status, title, points, load_steps, steps_done, newton_iterations, attempts, \
     cancel_requested, created_at, started_at, finished_at, solve_seconds, error";

/// A job a worker has just claimed.
#[derive(Debug, Clone, FromRow)]
pub struct Claimed {
    pub id: i64,
    pub case_json: String,
    pub attempts: i64,
}

/// A job to queue.
#[derive(Debug, Clone, Copy)]
pub struct NewJob<'a> {
    pub case_json: &'a str,
    pub title: Option<&'a str>,
    pub points: i64,
    pub load_steps: i64,
    /// The client's `Idempotency-Key`, if it sent one.
    pub idempotency_key: Option<&'a str>,
}

/// The job an idempotency key was first used for, and the body it came with.
#[derive(Debug, Clone, FromRow)]
pub struct Earlier {
    pub id: i64,
    pub case_json: String,
}

/// What [`Store::insert`] did.
#[derive(Debug, Clone)]
pub enum Inserted {
    New(i64),
    /// The key was taken (by a request that raced this one, or earlier).
    Earlier(Earlier),
}

/// What `POST /jobs/{id}/cancel` did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CancelOutcome {
    /// It was queued and is now cancelled.
    Cancelled,
    /// It is running and will stop at its next Newton iteration.
    Requested,
    /// It had already finished with this status.
    AlreadyFinal(JobStatus),
    NotFound,
}

#[derive(Clone)]
pub struct Store {
    pool: SqlitePool,
}

impl Store {
    /// Opens (creating if needed) the database at `path` in WAL mode with a
    /// busy timeout, and applies the embedded migrations.
    pub async fn open(path: &Path) -> Result<Store, sqlx::Error> {
        let options = SqliteConnectOptions::from_str("sqlite:")?
            .filename(path)
            .create_if_missing(true)
            .journal_mode(SqliteJournalMode::Wal)
            .synchronous(SqliteSynchronous::Normal)
            .busy_timeout(Duration::from_secs(10))
            .foreign_keys(true);
        let pool = SqlitePoolOptions::new()
            .max_connections(8)
            .connect_with(options)
            .await?;
        sqlx::migrate!("./migrations").run(&pool).await?;
        Ok(Store { pool })
    }

    pub async fn ping(&self) -> Result<(), sqlx::Error> {
        sqlx::query("SELECT 1")
            .execute(&self.pool)
            .await
            .map(|_| ())
    }

    /// Queues a job. With an idempotency key already taken, nothing is
    /// inserted and the job that holds the key is returned instead.
    pub async fn insert(&self, job: &NewJob<'_>) -> Result<Inserted, sqlx::Error> {
        let inserted = sqlx::query_scalar(
            "INSERT INTO jobs (status, case_json, title, points, load_steps, created_at, idempotency_key) \
             VALUES (?, ?, ?, ?, ?, ?, ?) RETURNING id",
        )
        .bind(JobStatus::Queued)
        .bind(job.case_json)
        .bind(job.title)
        .bind(job.points)
        .bind(job.load_steps)
        .bind(now())
        .bind(job.idempotency_key)
        .fetch_one(&self.pool)
        .await;
        match (inserted, job.idempotency_key) {
            (Ok(id), _) => Ok(Inserted::New(id)),
            (Err(e), Some(key))
                if e.as_database_error()
                    .is_some_and(|d| d.is_unique_violation()) =>
            {
                match self.by_idempotency_key(key).await? {
                    Some(earlier) => Ok(Inserted::Earlier(earlier)),
                    // Jobs are never deleted: the key's holder is there.
                    None => Err(e),
                }
            }
            (Err(e), _) => Err(e),
        }
    }

    /// The job that holds an idempotency key.
    pub async fn by_idempotency_key(&self, key: &str) -> Result<Option<Earlier>, sqlx::Error> {
        sqlx::query_as("SELECT id, case_json FROM jobs WHERE idempotency_key = ?")
            .bind(key)
            .fetch_optional(&self.pool)
            .await
    }

    pub async fn get(&self, id: i64) -> Result<Option<JobRow>, sqlx::Error> {
        sqlx::query_as(AssertSqlSafe(format!(
            "SELECT {JOB_COLUMNS} FROM jobs WHERE id = ?"
        )))
        .bind(id)
        .fetch_optional(&self.pool)
        .await
    }

    pub async fn case_json(&self, id: i64) -> Result<Option<String>, sqlx::Error> {
        sqlx::query_scalar("SELECT case_json FROM jobs WHERE id = ?")
            .bind(id)
            .fetch_optional(&self.pool)
            .await
    }

    /// Jobs newest first, optionally of one status; and how many there are.
    pub async fn list(
        &self,
        status: Option<JobStatus>,
        limit: i64,
        offset: i64,
    ) -> Result<(Vec<JobRow>, i64), sqlx::Error> {
        let filter = if status.is_some() {
            "WHERE status = ?"
        } else {
            ""
        };
        let mut rows = sqlx::query_as(AssertSqlSafe(format!(
            "SELECT {JOB_COLUMNS} FROM jobs {filter} ORDER BY id DESC LIMIT ? OFFSET ?"
        )));
        let mut count =
            sqlx::query_scalar(AssertSqlSafe(format!("SELECT COUNT(*) FROM jobs {filter}")));
        if let Some(s) = status {
            rows = rows.bind(s);
            count = count.bind(s);
        }
        let rows = rows.bind(limit).bind(offset).fetch_all(&self.pool).await?;
        let total = count.fetch_one(&self.pool).await?;
        Ok((rows, total))
    }

    /// The database's size in bytes (its pages; the write-ahead log aside).
    pub async fn size_bytes(&self) -> Result<i64, sqlx::Error> {
        sqlx::query_scalar(
            "SELECT page_count * page_size FROM pragma_page_count(), pragma_page_size()",
        )
        .fetch_one(&self.pool)
        .await
    }

    /// Jobs waiting in the queue.
    pub async fn queued(&self) -> Result<i64, sqlx::Error> {
        sqlx::query_scalar("SELECT COUNT(*) FROM jobs WHERE status = 'queued'")
            .fetch_one(&self.pool)
            .await
    }

    /// Fails running jobs whose lease has expired and that have used all
    /// their attempts. Returns how many.
    pub async fn fail_exhausted(&self, max_attempts: i64) -> Result<u64, sqlx::Error> {
        let error = Failure::new(
            FailureKind::AttemptsExhausted,
            format!(
                "the worker running this job stopped (crashed or was killed) {max_attempts} times"
            ),
        )
        .json();
        let t = now();
        let done = sqlx::query(
            "UPDATE jobs SET status = ?, error = ?, finished_at = ?, lease_owner = NULL, lease_expires_at = NULL \
             WHERE status = ? AND lease_expires_at < ? AND attempts >= ?",
        )
        .bind(JobStatus::Failed)
        .bind(error)
        .bind(t)
        .bind(JobStatus::Running)
        .bind(t)
        .bind(max_attempts)
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected())
    }

    /// Claims the oldest queued job, or a running one whose lease expired,
    /// for `owner` until `now + lease`. A reclaimed job restarts from its
    /// first step, so its old step rows are removed.
    pub async fn claim(
        &self,
        owner: &str,
        lease: Duration,
    ) -> Result<Option<Claimed>, sqlx::Error> {
        let t = now();
        // A job whose worker died after a cancel request ends as cancelled,
        // keeping its steps, rather than being run again.
        sqlx::query(AssertSqlSafe(format!(
            "UPDATE jobs SET status = '{CANCELLED}', finished_at = ? \
             WHERE status = '{RUNNING}' AND cancel_requested = 1 AND lease_expires_at < ?"
        )))
        .bind(t)
        .bind(t)
        .execute(&self.pool)
        .await?;
        let claimable =
            format!("(status = '{QUEUED}' OR (status = '{RUNNING}' AND lease_expires_at < ?))");
        let claimed: Option<Claimed> = sqlx::query_as(AssertSqlSafe(format!(
            "UPDATE jobs SET status = '{RUNNING}', attempts = attempts + 1, lease_owner = ?, lease_expires_at = ?, \
                 started_at = ?, steps_done = 0, newton_iterations = 0 \
             WHERE id = (SELECT id FROM jobs WHERE {claimable} ORDER BY id LIMIT 1) AND {claimable} \
             RETURNING id, case_json, attempts"
        )))
        .bind(owner)
        .bind(t + lease.as_secs_f64())
        .bind(t)
        .bind(t)
        .bind(t)
        .fetch_optional(&self.pool)
        .await?;
        if let Some(c) = &claimed {
            sqlx::query("DELETE FROM steps WHERE job_id = ?")
                .bind(c.id)
                .execute(&self.pool)
                .await?;
        }
        Ok(claimed)
    }

    /// Extends `owner`'s lease. `None` if the lease was lost (another worker
    /// took the job over); otherwise whether a cancel was requested.
    pub async fn renew(
        &self,
        id: i64,
        owner: &str,
        lease: Duration,
    ) -> Result<Option<bool>, sqlx::Error> {
        sqlx::query_scalar(AssertSqlSafe(format!(
            "UPDATE jobs SET lease_expires_at = ? WHERE id = ? AND lease_owner = ? AND status = '{RUNNING}' \
             RETURNING cancel_requested"
        )))
        .bind(now() + lease.as_secs_f64())
        .bind(id)
        .bind(owner)
        .fetch_optional(&self.pool)
        .await
    }

    /// Stores a finished step (report, points and boundaries as JSON text)
    /// and advances the job's progress, in one transaction. Returns false if
    /// `owner` no longer holds the job.
    pub async fn save_step(
        &self,
        id: i64,
        owner: &str,
        step: i64,
        iterations: i64,
        document: &StoredStep,
    ) -> Result<bool, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        let held = update_held(
            &mut *tx,
            "steps_done = ?, newton_iterations = newton_iterations + ?",
            |q| q.bind(step).bind(iterations),
            id,
            owner,
        )
        .await?;
        if held {
            sqlx::query(
                "INSERT OR REPLACE INTO steps (job_id, step, report, points, boundaries) VALUES (?, ?, ?, ?, ?)",
            )
            .bind(id)
            .bind(step)
            .bind(document.report.get())
            .bind(document.points.get())
            .bind(document.boundaries.get())
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(held)
    }

    /// Ends `owner`'s run of a job with a final status.
    pub async fn finish(
        &self,
        id: i64,
        owner: &str,
        status: JobStatus,
        solve_seconds: f64,
        error: Option<&str>,
    ) -> Result<bool, sqlx::Error> {
        update_held(
            &self.pool,
            "status = ?, finished_at = ?, solve_seconds = ?, error = ?, lease_owner = NULL, \
             lease_expires_at = NULL",
            |q| q.bind(status).bind(now()).bind(solve_seconds).bind(error),
            id,
            owner,
        )
        .await
    }

    /// Puts a job `owner` was running back in the queue (shutdown): the
    /// attempt does not count and its partial steps are dropped.
    pub async fn requeue(&self, id: i64, owner: &str) -> Result<(), sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        let held = update_held(
            &mut *tx,
            &format!(
                "status = '{QUEUED}', attempts = MAX(attempts - 1, 0), lease_owner = NULL, \
                 lease_expires_at = NULL, started_at = NULL, steps_done = 0, newton_iterations = 0"
            ),
            |q| q,
            id,
            owner,
        )
        .await?;
        if held {
            sqlx::query("DELETE FROM steps WHERE job_id = ?")
                .bind(id)
                .execute(&mut *tx)
                .await?;
        }
        tx.commit().await
    }

    /// Cancels a queued job at once, or asks a running one to stop.
    pub async fn cancel(&self, id: i64) -> Result<CancelOutcome, sqlx::Error> {
        let t = now();
        let queued = sqlx::query(AssertSqlSafe(format!(
            "UPDATE jobs SET status = '{CANCELLED}', finished_at = ? WHERE id = ? AND status = '{QUEUED}'"
        )))
            .bind(t)
            .bind(id)
            .execute(&self.pool)
            .await?;
        if queued.rows_affected() == 1 {
            return Ok(CancelOutcome::Cancelled);
        }
        // Running, but its worker is gone (the lease expired): no one would
        // stop it, so it ends here, its finished steps kept.
        let orphaned = sqlx::query(AssertSqlSafe(format!(
            "UPDATE jobs SET status = '{CANCELLED}', finished_at = ? \
             WHERE id = ? AND status = '{RUNNING}' AND lease_expires_at < ?"
        )))
        .bind(t)
        .bind(id)
        .bind(t)
        .execute(&self.pool)
        .await?;
        if orphaned.rows_affected() == 1 {
            return Ok(CancelOutcome::Cancelled);
        }
        let running = sqlx::query(AssertSqlSafe(format!(
            "UPDATE jobs SET cancel_requested = 1 WHERE id = ? AND status = '{RUNNING}'"
        )))
        .bind(id)
        .execute(&self.pool)
        .await?;
        if running.rows_affected() == 1 {
            return Ok(CancelOutcome::Requested);
        }
        Ok(match self.get(id).await? {
            Some(job) => CancelOutcome::AlreadyFinal(job.status),
            None => CancelOutcome::NotFound,
        })
    }

    /// Step reports (JSON text) of a job, in step order.
    pub async fn step_reports(&self, id: i64) -> Result<Vec<String>, sqlx::Error> {
        sqlx::query_scalar("SELECT report FROM steps WHERE job_id = ? ORDER BY step")
            .bind(id)
            .fetch_all(&self.pool)
            .await
    }

    /// One step's report, points and boundaries.
    pub async fn step(&self, id: i64, step: i64) -> Result<Option<StoredStep>, sqlx::Error> {
        let row: Option<(String, String, String)> = sqlx::query_as(
            "SELECT report, points, boundaries FROM steps WHERE job_id = ? AND step = ?",
        )
        .bind(id)
        .bind(step)
        .fetch_optional(&self.pool)
        .await?;
        row.map(|(report, points, boundaries)| {
            StoredStep::from_text(report, points, boundaries)
                .map_err(|e| sqlx::Error::Decode(Box::new(e)))
        })
        .transpose()
    }
}

type SqliteQuery = Query<'static, Sqlite, SqliteArguments>;

/// `UPDATE jobs SET {set}` on job `id` if `owner` still holds it (it runs
/// under `owner`'s lease); `bind` binds the values `set` asks for. `set` is
/// a constant of this module. Returns whether `owner` held the job.
async fn update_held<'c>(
    executor: impl SqliteExecutor<'c>,
    set: &str,
    bind: impl FnOnce(SqliteQuery) -> SqliteQuery,
    id: i64,
    owner: &str,
) -> Result<bool, sqlx::Error> {
    let update = sqlx::query(AssertSqlSafe(format!(
        "UPDATE jobs SET {set} WHERE id = ? AND lease_owner = ? AND status = '{RUNNING}'"
    )));
    let done = bind(update).bind(id).bind(owner).execute(executor).await?;
    Ok(done.rows_affected() == 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    async fn store(tag: &str) -> Store {
        let dir = std::env::temp_dir().join(format!("mpm-store-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Store::open(&dir.join("jobs.sqlite")).await.unwrap()
    }

    /// A running job with one finished step, claimed by `owner` with `lease`.
    async fn running_job(store: &Store, owner: &str, lease: Duration) -> i64 {
        let id = match store
            .insert(&NewJob {
                case_json: "{}",
                title: None,
                points: 1,
                load_steps: 10,
                idempotency_key: None,
            })
            .await
            .unwrap()
        {
            Inserted::New(id) => id,
            other => panic!("{other:?}"),
        };
        let claimed = store.claim(owner, lease).await.unwrap().unwrap();
        assert_eq!(claimed.id, id);
        let step = StoredStep::from_text("{}".into(), "{}".into(), "[]".into()).unwrap();
        assert!(store.save_step(id, owner, 1, 3, &step).await.unwrap());
        id
    }

    /// Cancelling a running job whose server was killed answered 202, then
    /// the job was claimed again, its steps deleted, run again and only
    /// then cancelled. A job whose worker is gone ends as cancelled at
    /// once, and one whose worker dies after a cancel request is never
    /// claimed again; both keep their finished steps.
    #[tokio::test]
    async fn a_cancelled_job_whose_worker_died_is_not_run_again() {
        let store = store("orphan").await;
        let orphan = running_job(&store, "dead", Duration::ZERO).await;
        tokio::time::sleep(Duration::from_millis(10)).await;
        assert_eq!(
            store.cancel(orphan).await.unwrap(),
            CancelOutcome::Cancelled
        );

        let requested = running_job(&store, "dying", Duration::from_millis(300)).await;
        assert_eq!(
            store.cancel(requested).await.unwrap(),
            CancelOutcome::Requested
        );
        tokio::time::sleep(Duration::from_millis(400)).await;
        assert!(
            store
                .claim("next", Duration::from_secs(30))
                .await
                .unwrap()
                .is_none()
        );

        for id in [orphan, requested] {
            let job = store.get(id).await.unwrap().unwrap();
            assert_eq!(job.status, JobStatus::Cancelled, "job {id}");
            assert_eq!(store.step_reports(id).await.unwrap().len(), 1, "job {id}");
        }
    }

    /// The second insert with a key gets the first's job, not an error:
    /// what a request that lost a race with its own retry sees.
    #[tokio::test]
    async fn an_idempotency_key_taken_returns_the_job_that_holds_it() {
        let store = store("idempotency").await;
        let job = |case_json| NewJob {
            case_json,
            title: None,
            points: 1,
            load_steps: 1,
            idempotency_key: Some("k"),
        };
        let Inserted::New(first) = store.insert(&job("{\"a\": 1}")).await.unwrap() else {
            panic!("the first insert makes a job");
        };
        match store.insert(&job("{\"b\": 2}")).await.unwrap() {
            Inserted::Earlier(earlier) => {
                assert_eq!(earlier.id, first);
                assert_eq!(earlier.case_json, "{\"a\": 1}");
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(store.list(None, 10, 0).await.unwrap().1, 1);
    }
}
