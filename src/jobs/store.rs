//! Jobs and their results in SQLite or PostgreSQL: every statement the
//! service runs.
//!
//! One text per statement serves both databases: `$n` placeholders (SQLite
//! reads them too), `TRUE`/`FALSE`, `ON CONFLICT` upserts, `CASE` for
//! `MAX`. Where the two differ (claiming, the database's size) the dialect
//! is spelled out. [`on_pool!`] runs a statement on whichever pool the
//! store holds, so each is type-checked against both drivers.
//!
//! Claiming is one compare-and-set `UPDATE ... RETURNING`, never a SELECT
//! followed by an UPDATE: in SQLite a deferred transaction doing both gives
//! `database is locked` under competing workers, which busy_timeout does not
//! cure; in PostgreSQL the candidate row is taken `FOR UPDATE SKIP LOCKED`,
//! so competing workers pass over each other's rows instead of waiting. A
//! claimed job carries a lease (owner, expiry) that its worker renews while
//! it runs; a job whose lease expired is claimable again, up to the attempt
//! limit, and resumes from its checkpoint if it has one.
//!
//! Every time the queue stores or compares (created, started and finished
//! times, lease expiries) is read from the database's clock, never the
//! caller's: a worker whose clock runs ahead would otherwise see other
//! workers' leases as expired and take their jobs.
//!
//! A SQLite connection goes back to the pool only outside a transaction
//! ([`released_outside_a_transaction`]); see docs/queue.md on the full disk
//! that taught this.
//!
//! The few statements assembled with `format!` insert only constants of this
//! module (column lists, status names from [`JobStatus`], the clock's SQL);
//! every value from a request is a bind parameter.

use std::future::Future;
use std::path::Path;
use std::pin::Pin;
use std::str::FromStr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use sqlx::postgres::{PgPool, PgPoolOptions};
use sqlx::sqlite::{
    SqliteConnectOptions, SqliteConnection, SqliteJournalMode, SqlitePoolOptions, SqliteSynchronous,
};
use sqlx::{AssertSqlSafe, Connection, Executor, FromRow, SqlitePool};

use super::{Failure, FailureKind, JobStatus};
use crate::step::StoredStep;

/// A row of `jobs`, without the case text.
#[derive(Debug, Clone, FromRow)]
pub struct JobRow {
    pub id: i64,
    #[sqlx(try_from = "String")]
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
    /// The step the latest run resumed after, if it resumed.
    pub resumed_from: Option<i64>,
}

const QUEUED: &str = JobStatus::Queued.as_str();
const RUNNING: &str = JobStatus::Running.as_str();
const CANCELLED: &str = JobStatus::Cancelled.as_str();

const JOB_COLUMNS: &str = "id, status, title, points, load_steps, steps_done, newton_iterations, attempts, \
     cancel_requested, created_at, started_at, finished_at, solve_seconds, error, resumed_from";

/// Removes the checkpoints of jobs that have ended: `finish` removes its
/// own; the other ends (cancelled while queued or orphaned, failed for its
/// attempts) run this.
const ENDED_CHECKPOINTS: &str = "DELETE FROM checkpoints WHERE job_id IN \
     (SELECT id FROM jobs WHERE status IN ('succeeded', 'failed', 'cancelled'))";

/// A job a worker has just claimed.
#[derive(Debug, Clone)]
pub struct Claimed {
    pub id: i64,
    pub case_json: String,
    pub attempts: i64,
    /// The solver's state to resume from (`mpm::Checkpoint` bytes) and the
    /// step it was taken after; `None` to start from step 1.
    pub checkpoint: Option<(i64, Vec<u8>)>,
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
    /// Nothing: the queue already held the limit's number of jobs.
    QueueFull,
}

/// What [`Store::requeue`] did with a job its worker hands back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Requeued {
    /// Back in the queue, to resume from its checkpoint.
    Queued,
    /// A cancel had been asked for: it ended as cancelled instead.
    Cancelled,
    /// The worker no longer held it.
    NotHeld,
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

/// What `DELETE /jobs/{id}` did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeleteOutcome {
    Deleted,
    /// It is queued or running: cancel it first.
    NotEnded(JobStatus),
    NotFound,
}

/// A stored step's report, and whether its points were stored with it.
#[derive(Debug)]
pub struct StepHead {
    pub report: String,
    pub has_points: bool,
    /// The stored parts' lengths, in characters.
    pub points_chars: usize,
    pub boundaries_chars: usize,
}

/// A stored step's parts that may be large, read a piece at a time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepPart {
    Points,
    Boundaries,
}

/// Which database a store uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Sqlite,
    Postgres,
}

#[derive(Clone)]
enum Pool {
    Sqlite(SqlitePool),
    Postgres(PgPool),
}

/// Runs `$body` with `$pool` bound to the store's pool, whichever database
/// it is: the body is compiled once per driver.
macro_rules! on_pool {
    ($store:expr, |$pool:ident| $body:expr) => {
        match &$store.pool {
            Pool::Sqlite($pool) => $body,
            Pool::Postgres($pool) => $body,
        }
    };
}

/// In one transaction on `$pool`: the [`update_held`] statement `$update`
/// bound to `$binds`, the job `$id` and its owner `$owner`; then, if that
/// owner still held the job, `$then` (statements on `$tx`). Returns from
/// the enclosing function with whether the owner held the job.
macro_rules! if_held {
    ($pool:ident, $update:expr, [$($bind:expr),*], $id:expr, $owner:expr, |$tx:ident| $then:block) => {{
        let mut $tx = $pool.begin().await?;
        let held = sqlx::query($update)
            $(.bind($bind))*
            .bind($id)
            .bind($owner)
            .execute(&mut *$tx)
            .await?
            .rows_affected()
            == 1;
        if held $then
        $tx.commit().await?;
        Ok(held)
    }};
}

#[derive(Clone)]
pub struct Store {
    pool: Pool,
    /// The last write that failed for want of space or on an I/O error,
    /// until a later write that stores data succeeds: what `/health` reports.
    trouble: Arc<Mutex<Option<String>>>,
}

/// Whether an error is the database's storage failing (a full disk, an I/O
/// error), rather than the statement or the request.
pub fn is_storage_error(e: &sqlx::Error) -> bool {
    match e {
        sqlx::Error::Io(_) => true,
        sqlx::Error::Database(d) => {
            let code = d.code();
            let code = code.as_deref().unwrap_or("");
            // SQLite's primary result codes (the low byte of extended ones):
            // 13 SQLITE_FULL, 10 SQLITE_IOERR. PostgreSQL's SQLSTATE classes
            // 53 (insufficient resources: 53100 disk_full) and 58 (I/O).
            let sqlite_primary = code.parse::<i64>().ok().map(|c| c & 0xff);
            matches!(sqlite_primary, Some(13 | 10))
                || code.starts_with("53")
                || code.starts_with("58")
        }
        _ => false,
    }
}

/// Whether an error is the database's disk being full.
pub fn is_disk_full(e: &sqlx::Error) -> bool {
    match e {
        sqlx::Error::Database(d) => {
            let code = d.code();
            let code = code.as_deref().unwrap_or("");
            code.parse::<i64>().is_ok_and(|c| c & 0xff == 13) || code == "53100"
        }
        _ => false,
    }
}

/// The `after_release` check of SQLite's pool: whether a connection may go
/// back to it. A SQLite transaction that a full disk ends (SQLITE_FULL on a
/// statement or a COMMIT rolls it back) leaves sqlx's count of open
/// transactions at 1, as its ROLLBACK then fails; sqlx's next `begin` on
/// that connection is a SAVEPOINT, and a failed one's rollback (`ROLLBACK
/// TO`) keeps the transaction open, write lock and all. Such a connection
/// sat in the pool: every other connection waited on its lock ("database
/// is locked"), and what ran on it was acknowledged but never committed.
/// A `BEGIN` fails inside a transaction; run after the queued rollback, it
/// and sqlx's count say whether the connection is clean. A connection that
/// is not is closed, which rolls back whatever it held.
fn released_outside_a_transaction(
    conn: &mut SqliteConnection,
) -> Pin<Box<dyn Future<Output = Result<bool, sqlx::Error>> + Send + '_>> {
    Box::pin(async move {
        let probed = conn.execute("BEGIN; ROLLBACK").await;
        if probed.is_err() || conn.is_in_transaction() {
            tracing::warn!(
                error = ?probed.err(),
                "a database connection was left inside a transaction; closing it"
            );
            return Ok(false);
        }
        Ok(true)
    })
}

/// `UPDATE jobs SET {set}` on job `$k+1` if owner `$k+2` still holds it
/// (it runs under that owner's lease); `set` uses `$1..$k`.
fn update_held(set: &str, k: usize) -> AssertSqlSafe<String> {
    AssertSqlSafe(format!(
        "UPDATE jobs SET {set} WHERE id = ${} AND lease_owner = ${} AND status = '{RUNNING}'",
        k + 1,
        k + 2
    ))
}

impl Store {
    /// Opens the database `url` names and applies its migrations:
    /// `postgres://...` (or `postgresql://`) for PostgreSQL; `sqlite://PATH`,
    /// `sqlite:PATH` or a bare path for a SQLite file, created if needed, in
    /// WAL mode with a busy timeout.
    pub async fn open(url: &str) -> Result<Store, sqlx::Error> {
        if url.starts_with("postgres://") || url.starts_with("postgresql://") {
            let pool = PgPoolOptions::new().max_connections(8).connect(url).await?;
            // Processes starting together take turns: sqlx holds an
            // advisory lock while it migrates.
            sqlx::migrate!("./migrations/postgres").run(&pool).await?;
            return Ok(Store::with(Pool::Postgres(pool)));
        }
        let path = url
            .strip_prefix("sqlite://")
            .or_else(|| url.strip_prefix("sqlite:"))
            .unwrap_or(url);
        let options = SqliteConnectOptions::from_str("sqlite:")?.filename(Path::new(path));
        Store::open_sqlite(options, 8).await
    }

    /// A SQLite store on `options` (its file named), with the service's
    /// settings added, and at most `connections` connections.
    async fn open_sqlite(
        options: SqliteConnectOptions,
        connections: u32,
    ) -> Result<Store, sqlx::Error> {
        let options = options
            .create_if_missing(true)
            .journal_mode(SqliteJournalMode::Wal)
            .synchronous(SqliteSynchronous::Normal)
            .busy_timeout(Duration::from_secs(10))
            .foreign_keys(true);
        let pool = SqlitePoolOptions::new()
            .max_connections(connections)
            .after_release(|conn, _| released_outside_a_transaction(conn))
            .connect_with(options)
            .await?;
        sqlx::migrate!("./migrations/sqlite").run(&pool).await?;
        Ok(Store::with(Pool::Sqlite(pool)))
    }

    fn with(pool: Pool) -> Store {
        Store {
            pool,
            trouble: Arc::default(),
        }
    }

    /// The last storage failure of a write (see [`is_storage_error`]), if no
    /// write that stores data has succeeded since.
    pub fn storage_trouble(&self) -> Option<String> {
        self.trouble.lock().expect("not poisoned").clone()
    }

    /// After a storage failure, tries a write of its own (one row
    /// rewritten), so that an idle service learns the space is back; then
    /// [`Store::storage_trouble`].
    pub async fn recheck_storage(&self) -> Option<String> {
        self.storage_trouble()?;
        let sql = AssertSqlSafe(format!(
            "INSERT INTO write_probe (id, at) VALUES (1, {0}) ON CONFLICT (id) DO UPDATE SET at = {0}",
            self.now()
        ));
        let probed = on_pool!(self, |pool| sqlx::query(sql)
            .execute(pool)
            .await
            .map(|_| ()));
        let _ = self.note(probed);
        self.storage_trouble()
    }

    /// Notes a failed write of any kind (a claim, a job's end) for
    /// [`Store::storage_trouble`], if the storage failed.
    pub fn note_failure(&self, e: &sqlx::Error) {
        if is_storage_error(e) {
            *self.trouble.lock().expect("not poisoned") = Some(e.to_string());
        }
    }

    /// Notes the outcome of a write that stores data (a job, a step) for
    /// [`Store::storage_trouble`]: a storage failure is kept, a success
    /// clears it.
    fn note<T>(&self, result: Result<T, sqlx::Error>) -> Result<T, sqlx::Error> {
        let mut trouble = self.trouble.lock().expect("not poisoned");
        match &result {
            Err(e) if is_storage_error(e) => *trouble = Some(e.to_string()),
            Ok(_) => *trouble = None,
            Err(_) => {}
        }
        result
    }

    /// The database's clock as an SQL expression, in Unix seconds.
    fn now(&self) -> &'static str {
        match self.backend() {
            Backend::Sqlite => "((julianday('now') - 2440587.5) * 86400.0)",
            Backend::Postgres => "CAST(extract(epoch FROM clock_timestamp()) AS DOUBLE PRECISION)",
        }
    }

    /// The database's clock, in Unix seconds.
    pub async fn clock(&self) -> Result<f64, sqlx::Error> {
        let sql = format!("SELECT {}", self.now());
        on_pool!(self, |pool| sqlx::query_scalar(AssertSqlSafe(sql))
            .fetch_one(pool)
            .await)
    }

    pub fn backend(&self) -> Backend {
        match self.pool {
            Pool::Sqlite(_) => Backend::Sqlite,
            Pool::Postgres(_) => Backend::Postgres,
        }
    }

    pub async fn ping(&self) -> Result<(), sqlx::Error> {
        on_pool!(self, |pool| sqlx::query("SELECT 1")
            .execute(pool)
            .await
            .map(|_| ()))
    }

    /// Queues a job unless `max_queued` jobs already wait: the count and
    /// the insert are one step, so simultaneous submissions cannot pass the
    /// limit together (SQLite: `BEGIN IMMEDIATE` takes the write lock before
    /// counting; PostgreSQL: a transaction's advisory lock orders the
    /// submissions). With an idempotency key already taken, nothing is
    /// inserted and the job that holds the key is returned instead.
    pub async fn insert(&self, job: &NewJob<'_>, max_queued: i64) -> Result<Inserted, sqlx::Error> {
        let insert = AssertSqlSafe(format!(
            "INSERT INTO jobs (status, case_json, title, points, load_steps, created_at, idempotency_key) \
             SELECT $1, $2, $3, $4, $5, {}, $6 \
             WHERE (SELECT COUNT(*) FROM jobs WHERE status = '{QUEUED}') < $7 RETURNING id",
            self.now()
        ));
        let (begin, lock) = match self.backend() {
            Backend::Sqlite => ("BEGIN IMMEDIATE", None),
            // Any constant key: the queue's one lock of this kind.
            Backend::Postgres => ("BEGIN", Some("SELECT pg_advisory_xact_lock(7340001)")),
        };
        let inserted: Result<Option<i64>, _> = on_pool!(self, |pool| async {
            let mut tx = pool.begin_with(begin).await?;
            if let Some(lock) = lock {
                sqlx::query(lock).execute(&mut *tx).await?;
            }
            let id = sqlx::query_scalar(insert)
                .bind(QUEUED)
                .bind(job.case_json)
                .bind(job.title)
                .bind(job.points)
                .bind(job.load_steps)
                .bind(job.idempotency_key)
                .bind(max_queued)
                .fetch_optional(&mut *tx)
                .await?;
            tx.commit().await?;
            Ok(id)
        }
        .await);
        match (self.note(inserted), job.idempotency_key) {
            (Ok(Some(id)), _) => Ok(Inserted::New(id)),
            (Ok(None), _) => Ok(Inserted::QueueFull),
            (Err(e), Some(key))
                if e.as_database_error()
                    .is_some_and(|d| d.is_unique_violation()) =>
            {
                match self.by_idempotency_key(key).await? {
                    Some(earlier) => Ok(Inserted::Earlier(earlier)),
                    // The key's holder was deleted in between.
                    None => Err(e),
                }
            }
            (Err(e), _) => Err(e),
        }
    }

    /// The job that holds an idempotency key.
    pub async fn by_idempotency_key(&self, key: &str) -> Result<Option<Earlier>, sqlx::Error> {
        on_pool!(self, |pool| sqlx::query_as(
            "SELECT id, case_json FROM jobs WHERE idempotency_key = $1"
        )
        .bind(key)
        .fetch_optional(pool)
        .await)
    }

    pub async fn get(&self, id: i64) -> Result<Option<JobRow>, sqlx::Error> {
        let sql = format!("SELECT {JOB_COLUMNS} FROM jobs WHERE id = $1");
        on_pool!(self, |pool| sqlx::query_as(AssertSqlSafe(sql))
            .bind(id)
            .fetch_optional(pool)
            .await)
    }

    pub async fn case_json(&self, id: i64) -> Result<Option<String>, sqlx::Error> {
        on_pool!(self, |pool| sqlx::query_scalar(
            "SELECT case_json FROM jobs WHERE id = $1"
        )
        .bind(id)
        .fetch_optional(pool)
        .await)
    }

    /// Jobs newest first, optionally of one status; and how many there are.
    pub async fn list(
        &self,
        status: Option<JobStatus>,
        limit: i64,
        offset: i64,
    ) -> Result<(Vec<JobRow>, i64), sqlx::Error> {
        // With no status, `$1` is NULL and matches every row.
        let status = status.map(JobStatus::as_str);
        let filter = "WHERE ($1 IS NULL OR status = $1)";
        let rows_sql =
            format!("SELECT {JOB_COLUMNS} FROM jobs {filter} ORDER BY id DESC LIMIT $2 OFFSET $3");
        let count_sql = format!("SELECT COUNT(*) FROM jobs {filter}");
        on_pool!(self, |pool| {
            let rows = sqlx::query_as(AssertSqlSafe(rows_sql))
                .bind(status)
                .bind(limit)
                .bind(offset)
                .fetch_all(pool)
                .await?;
            let total = sqlx::query_scalar(AssertSqlSafe(count_sql))
                .bind(status)
                .fetch_one(pool)
                .await?;
            Ok((rows, total))
        })
    }

    /// The database's size in bytes (SQLite: its pages, the write-ahead log
    /// aside; PostgreSQL: `pg_database_size`).
    pub async fn size_bytes(&self) -> Result<i64, sqlx::Error> {
        match &self.pool {
            Pool::Sqlite(pool) => {
                sqlx::query_scalar(
                    "SELECT page_count * page_size FROM pragma_page_count(), pragma_page_size()",
                )
                .fetch_one(pool)
                .await
            }
            Pool::Postgres(pool) => {
                sqlx::query_scalar("SELECT pg_database_size(current_database())")
                    .fetch_one(pool)
                    .await
            }
        }
    }

    /// Jobs waiting in the queue.
    pub async fn queued(&self) -> Result<i64, sqlx::Error> {
        let sql = format!("SELECT COUNT(*) FROM jobs WHERE status = '{QUEUED}'");
        on_pool!(self, |pool| sqlx::query_scalar(AssertSqlSafe(sql))
            .fetch_one(pool)
            .await)
    }

    /// How many jobs have each status (every status, zero included).
    pub async fn counts(&self) -> Result<Vec<(JobStatus, i64)>, sqlx::Error> {
        let rows: Vec<(String, i64)> = on_pool!(self, |pool| sqlx::query_as(
            "SELECT status, COUNT(*) FROM jobs GROUP BY status"
        )
        .fetch_all(pool)
        .await?);
        Ok(JobStatus::ALL
            .into_iter()
            .map(|s| {
                let n = rows.iter().find(|(name, _)| name == s.as_str());
                (s, n.map_or(0, |(_, n)| *n))
            })
            .collect())
    }

    /// Fails running jobs whose lease has expired and that have used all
    /// their attempts: claims since their checkpoint last moved on (a run
    /// that stored a later checkpoint before its worker died made
    /// progress, and is not held against the job). Returns how many.
    pub async fn fail_exhausted(&self, max_attempts: i64) -> Result<u64, sqlx::Error> {
        let error = Failure::new(
            FailureKind::AttemptsExhausted,
            format!(
                "the worker running this job stopped (crashed or was killed) {max_attempts} times \
                 without the job getting past its last checkpoint"
            ),
        )
        .json();
        let now = self.now();
        let sql = format!(
            "UPDATE jobs SET status = $1, error = $2, finished_at = {now}, lease_owner = NULL, lease_expires_at = NULL \
             WHERE status = '{RUNNING}' AND lease_expires_at < {now} AND stalled_attempts >= $3"
        );
        on_pool!(self, |pool| {
            let done = sqlx::query(AssertSqlSafe(sql))
                .bind(JobStatus::Failed.as_str())
                .bind(&error)
                .bind(max_attempts)
                .execute(pool)
                .await?
                .rows_affected();
            if done > 0 {
                sqlx::query(ENDED_CHECKPOINTS).execute(pool).await?;
            }
            Ok(done)
        })
    }

    /// Claims the oldest queued job, or a running one whose lease expired,
    /// for `owner` until `now + lease`. A job with a checkpoint resumes from
    /// it: its steps after the checkpoint are removed (all of them when it
    /// has none) and its progress is the checkpoint's.
    pub async fn claim(
        &self,
        owner: &str,
        lease: Duration,
    ) -> Result<Option<Claimed>, sqlx::Error> {
        let now = self.now();
        // A job whose worker died or handed it back after a cancel request
        // ends as cancelled, keeping its steps, rather than being run again.
        let orphans = format!(
            "UPDATE jobs SET status = '{CANCELLED}', finished_at = {now}, lease_owner = NULL, lease_expires_at = NULL \
             WHERE cancel_requested = TRUE AND (status = '{QUEUED}' OR (status = '{RUNNING}' AND lease_expires_at < {now}))"
        );
        let lock = match self.backend() {
            Backend::Sqlite => "",
            Backend::Postgres => "FOR UPDATE SKIP LOCKED",
        };
        let claimable =
            format!("(status = '{QUEUED}' OR (status = '{RUNNING}' AND lease_expires_at < {now}))");
        let checkpoint = "(SELECT c.step FROM checkpoints c WHERE c.job_id = jobs.id)";
        let claim = format!(
            "UPDATE jobs SET status = '{RUNNING}', attempts = attempts + 1, \
                 stalled_attempts = CASE WHEN COALESCE({checkpoint}, 0) > COALESCE(resumed_from, 0) \
                     THEN 1 ELSE stalled_attempts + 1 END, lease_owner = $1, lease_expires_at = {now} + $2, \
                 started_at = {now}, resumed_from = {checkpoint}, steps_done = COALESCE({checkpoint}, 0), \
                 newton_iterations = COALESCE((SELECT c.newton_iterations FROM checkpoints c WHERE c.job_id = jobs.id), 0) \
             WHERE id = (SELECT id FROM jobs WHERE {claimable} ORDER BY id LIMIT 1 {lock}) AND {claimable} \
             RETURNING id, case_json, attempts, resumed_from"
        );
        // One transaction, so no one sees the claimed job with the steps of
        // its last run past the checkpoint. It starts with a write, which
        // SQLite's busy timeout waits for (a read first would not be).
        on_pool!(self, |pool| {
            let mut tx = pool.begin().await?;
            let orphaned = sqlx::query(AssertSqlSafe(orphans))
                .execute(&mut *tx)
                .await?
                .rows_affected();
            if orphaned > 0 {
                sqlx::query(ENDED_CHECKPOINTS).execute(&mut *tx).await?;
            }
            let claimed: Option<(i64, String, i64, Option<i64>)> =
                sqlx::query_as(AssertSqlSafe(claim))
                    .bind(owner)
                    .bind(lease.as_secs_f64())
                    .fetch_optional(&mut *tx)
                    .await?;
            let Some((id, case_json, attempts, resumed_from)) = claimed else {
                tx.commit().await?;
                return Ok(None);
            };
            sqlx::query("DELETE FROM steps WHERE job_id = $1 AND step > $2")
                .bind(id)
                .bind(resumed_from.unwrap_or(0))
                .execute(&mut *tx)
                .await?;
            let state: Option<Vec<u8>> = match resumed_from {
                Some(_) => {
                    sqlx::query_scalar("SELECT state FROM checkpoints WHERE job_id = $1")
                        .bind(id)
                        .fetch_optional(&mut *tx)
                        .await?
                }
                None => None,
            };
            tx.commit().await?;
            Ok(Some(Claimed {
                id,
                case_json,
                attempts,
                checkpoint: resumed_from.zip(state),
            }))
        })
    }

    /// Extends `owner`'s lease. `None` if the lease was lost (another worker
    /// took the job over); otherwise whether a cancel was requested.
    pub async fn renew(
        &self,
        id: i64,
        owner: &str,
        lease: Duration,
    ) -> Result<Option<bool>, sqlx::Error> {
        let sql = format!(
            "UPDATE jobs SET lease_expires_at = {} + $1 WHERE id = $2 AND lease_owner = $3 AND status = '{RUNNING}' \
             RETURNING cancel_requested",
            self.now()
        );
        on_pool!(self, |pool| sqlx::query_scalar(AssertSqlSafe(sql))
            .bind(lease.as_secs_f64())
            .bind(id)
            .bind(owner)
            .fetch_optional(pool)
            .await)
    }

    /// Stores a finished step (report, points and boundaries as JSON text)
    /// and advances the job's progress, with the solver's state after it
    /// when given (replacing the last), in one transaction. Returns false
    /// if `owner` no longer holds the job.
    pub async fn save_step(
        &self,
        id: i64,
        owner: &str,
        step: i64,
        iterations: i64,
        document: &StoredStep,
        checkpoint: Option<&[u8]>,
    ) -> Result<bool, sqlx::Error> {
        let saved = self
            .save_step_once(id, owner, step, iterations, document, checkpoint)
            .await;
        self.note(saved)
    }

    async fn save_step_once(
        &self,
        id: i64,
        owner: &str,
        step: i64,
        iterations: i64,
        document: &StoredStep,
        checkpoint: Option<&[u8]>,
    ) -> Result<bool, sqlx::Error> {
        let progress = update_held(
            "steps_done = $1, newton_iterations = newton_iterations + $2",
            2,
        );
        on_pool!(self, |pool| {
            if_held!(pool, progress, [step, iterations], id, owner, |tx| {
                sqlx::query(
                    "INSERT INTO steps (job_id, step, report, points, boundaries) VALUES ($1, $2, $3, $4, $5) \
                     ON CONFLICT (job_id, step) DO UPDATE SET report = excluded.report, \
                         points = excluded.points, boundaries = excluded.boundaries",
                )
                .bind(id)
                .bind(step)
                .bind(document.report.get())
                .bind(document.points.get())
                .bind(document.boundaries.get())
                .execute(&mut *tx)
                .await?;
                if let Some(state) = checkpoint {
                    sqlx::query(
                        "INSERT INTO checkpoints (job_id, step, newton_iterations, state) \
                         VALUES ($1, $2, (SELECT newton_iterations FROM jobs WHERE id = $1), $3) \
                         ON CONFLICT (job_id) DO UPDATE SET step = excluded.step, \
                             newton_iterations = excluded.newton_iterations, state = excluded.state",
                    )
                    .bind(id)
                    .bind(step)
                    .bind(state)
                    .execute(&mut *tx)
                    .await?;
                }
            })
        })
    }

    /// Ends `owner`'s run of a job with a final status; its checkpoint goes.
    pub async fn finish(
        &self,
        id: i64,
        owner: &str,
        status: JobStatus,
        solve_seconds: f64,
        error: Option<&str>,
    ) -> Result<bool, sqlx::Error> {
        let end = update_held(
            &format!(
                "status = $1, finished_at = {}, solve_seconds = $2, error = $3, lease_owner = NULL, \
                 lease_expires_at = NULL",
                self.now()
            ),
            3,
        );
        on_pool!(self, |pool| {
            if_held!(
                pool,
                end,
                [status.as_str(), solve_seconds, error],
                id,
                owner,
                |tx| {
                    sqlx::query("DELETE FROM checkpoints WHERE job_id = $1")
                        .bind(id)
                        .execute(&mut *tx)
                        .await?;
                }
            )
        })
    }

    /// Puts a job `owner` was running back in the queue (shutdown): the
    /// attempt does not count, and the job keeps its steps up to its
    /// checkpoint, from which it will resume. A job whose cancel was asked
    /// for ends as cancelled instead, its finished steps kept: the request
    /// may have reached the database after the worker last renewed its
    /// lease, so the worker need not have seen it.
    pub async fn requeue(&self, id: i64, owner: &str) -> Result<Requeued, sqlx::Error> {
        let cancel = update_held(
            &format!(
                "status = '{CANCELLED}', finished_at = {}, lease_owner = NULL, lease_expires_at = NULL",
                self.now()
            ),
            0,
        );
        let back = update_held(
            &format!(
                "status = '{QUEUED}', attempts = CASE WHEN attempts > 0 THEN attempts - 1 ELSE 0 END, \
                 stalled_attempts = CASE WHEN stalled_attempts > 0 THEN stalled_attempts - 1 ELSE 0 END, \
                 lease_owner = NULL, lease_expires_at = NULL, started_at = NULL, \
                 steps_done = COALESCE((SELECT c.step FROM checkpoints c WHERE c.job_id = jobs.id), 0), \
                 newton_iterations = COALESCE((SELECT c.newton_iterations FROM checkpoints c WHERE c.job_id = jobs.id), 0)"
            ),
            0,
        );
        on_pool!(self, |pool| {
            let mut tx = pool.begin().await?;
            let cancelled = sqlx::query(AssertSqlSafe(format!(
                "{} AND cancel_requested = TRUE",
                cancel.0
            )))
            .bind(id)
            .bind(owner)
            .execute(&mut *tx)
            .await?
            .rows_affected()
                == 1;
            if cancelled {
                sqlx::query("DELETE FROM checkpoints WHERE job_id = $1")
                    .bind(id)
                    .execute(&mut *tx)
                    .await?;
                tx.commit().await?;
                return Ok(Requeued::Cancelled);
            }
            let held = sqlx::query(back)
                .bind(id)
                .bind(owner)
                .execute(&mut *tx)
                .await?
                .rows_affected()
                == 1;
            if held {
                sqlx::query(
                    "DELETE FROM steps WHERE job_id = $1 AND step > (SELECT steps_done FROM jobs WHERE id = $1)",
                )
                .bind(id)
                .execute(&mut *tx)
                .await?;
            }
            tx.commit().await?;
            Ok(if held {
                Requeued::Queued
            } else {
                Requeued::NotHeld
            })
        })
    }

    /// Makes `owner`'s claimed job start over from step 1: its checkpoint
    /// could not be restored (a solver of another version wrote it). Its
    /// progress, steps past step 0 and checkpoint go.
    pub async fn start_over(&self, id: i64, owner: &str) -> Result<bool, sqlx::Error> {
        let reset = update_held(
            "steps_done = 0, newton_iterations = 0, resumed_from = NULL",
            0,
        );
        on_pool!(self, |pool| {
            if_held!(pool, reset, [], id, owner, |tx| {
                sqlx::query("DELETE FROM steps WHERE job_id = $1 AND step > 0")
                    .bind(id)
                    .execute(&mut *tx)
                    .await?;
                sqlx::query("DELETE FROM checkpoints WHERE job_id = $1")
                    .bind(id)
                    .execute(&mut *tx)
                    .await?;
            })
        })
    }

    /// Cancels a queued job at once, or asks a running one to stop.
    pub async fn cancel(&self, id: i64) -> Result<CancelOutcome, sqlx::Error> {
        let now = self.now();
        let queued = format!(
            "UPDATE jobs SET status = '{CANCELLED}', finished_at = {now} WHERE id = $1 AND status = '{QUEUED}'"
        );
        // Running, but its worker is gone (the lease expired): no one would
        // stop it, so it ends here, its finished steps kept.
        let orphaned = format!(
            "UPDATE jobs SET status = '{CANCELLED}', finished_at = {now}, lease_owner = NULL, lease_expires_at = NULL \
             WHERE id = $1 AND status = '{RUNNING}' AND lease_expires_at < {now}"
        );
        let running = format!(
            "UPDATE jobs SET cancel_requested = TRUE WHERE id = $1 AND status = '{RUNNING}'"
        );
        let done = on_pool!(self, |pool| {
            let queued = sqlx::query(AssertSqlSafe(queued))
                .bind(id)
                .execute(pool)
                .await?;
            if queued.rows_affected() == 1 {
                // A job SIGTERM put back in the queue has a checkpoint.
                sqlx::query(ENDED_CHECKPOINTS).execute(pool).await?;
                return Ok(CancelOutcome::Cancelled);
            }
            let orphaned = sqlx::query(AssertSqlSafe(orphaned))
                .bind(id)
                .execute(pool)
                .await?;
            if orphaned.rows_affected() == 1 {
                sqlx::query(ENDED_CHECKPOINTS).execute(pool).await?;
                return Ok(CancelOutcome::Cancelled);
            }
            sqlx::query(AssertSqlSafe(running))
                .bind(id)
                .execute(pool)
                .await?
                .rows_affected()
        });
        if done == 1 {
            return Ok(CancelOutcome::Requested);
        }
        Ok(match self.get(id).await? {
            Some(job) => CancelOutcome::AlreadyFinal(job.status),
            None => CancelOutcome::NotFound,
        })
    }

    /// Deletes an ended job with its steps and checkpoint.
    pub async fn delete(&self, id: i64) -> Result<DeleteOutcome, sqlx::Error> {
        let sql =
            format!("DELETE FROM jobs WHERE id = $1 AND status NOT IN ('{QUEUED}', '{RUNNING}')");
        let deleted = on_pool!(self, |pool| sqlx::query(AssertSqlSafe(sql))
            .bind(id)
            .execute(pool)
            .await?
            .rows_affected());
        if deleted == 1 {
            return Ok(DeleteOutcome::Deleted);
        }
        Ok(match self.get(id).await? {
            Some(job) => DeleteOutcome::NotEnded(job.status),
            None => DeleteOutcome::NotFound,
        })
    }

    /// Deletes the jobs that ended more than `age` ago. Returns how many.
    pub async fn prune(&self, age: Duration) -> Result<u64, sqlx::Error> {
        let sql = format!(
            "DELETE FROM jobs WHERE status NOT IN ('{QUEUED}', '{RUNNING}') AND finished_at < {} - $1",
            self.now()
        );
        on_pool!(self, |pool| Ok(sqlx::query(AssertSqlSafe(sql))
            .bind(age.as_secs_f64())
            .execute(pool)
            .await?
            .rows_affected()))
    }

    /// Step reports (JSON text) of a job, in step order.
    pub async fn step_reports(&self, id: i64) -> Result<Vec<String>, sqlx::Error> {
        on_pool!(self, |pool| sqlx::query_scalar(
            "SELECT report FROM steps WHERE job_id = $1 ORDER BY step"
        )
        .bind(id)
        .fetch_all(pool)
        .await)
    }

    /// One step's report, and whether its points were stored: what a
    /// response needs before it streams the rest (`step_part`).
    pub async fn step_head(&self, id: i64, step: i64) -> Result<Option<StepHead>, sqlx::Error> {
        let row: Option<(String, i32, i64, i64)> = on_pool!(self, |pool| sqlx::query_as(
            "SELECT report, CASE WHEN points = 'null' THEN 0 ELSE 1 END, \
             CAST(length(points) AS BIGINT), CAST(length(boundaries) AS BIGINT) \
             FROM steps WHERE job_id = $1 AND step = $2",
        )
        .bind(id)
        .bind(step)
        .fetch_optional(pool)
        .await?);
        Ok(
            row.map(|(report, has_points, points, boundaries)| StepHead {
                report,
                has_points: has_points == 1,
                points_chars: points as usize,
                boundaries_chars: boundaries as usize,
            }),
        )
    }

    /// Up to `chars` characters of one stored part of a step, from the
    /// `from`th (counting from 0): an empty string past its end, `None`
    /// if the step is gone. A response reads a large part this way, a
    /// piece at a time, rather than holding it whole.
    pub async fn step_part(
        &self,
        id: i64,
        step: i64,
        part: StepPart,
        from: usize,
        chars: usize,
    ) -> Result<Option<String>, sqlx::Error> {
        // SQL's substr counts characters from 1, in both databases.
        let sql = match part {
            StepPart::Points => {
                "SELECT substr(points, CAST($3 AS INTEGER), CAST($4 AS INTEGER)) \
                 FROM steps WHERE job_id = $1 AND step = $2"
            }
            StepPart::Boundaries => {
                "SELECT substr(boundaries, CAST($3 AS INTEGER), CAST($4 AS INTEGER)) \
                 FROM steps WHERE job_id = $1 AND step = $2"
            }
        };
        on_pool!(self, |pool| sqlx::query_scalar(sql)
            .bind(id)
            .bind(step)
            .bind(from as i64 + 1)
            .bind(chars as i64)
            .fetch_optional(pool)
            .await)
    }

    /// One step's report, points and boundaries.
    pub async fn step(&self, id: i64, step: i64) -> Result<Option<StoredStep>, sqlx::Error> {
        let row: Option<(String, String, String)> = on_pool!(self, |pool| sqlx::query_as(
            "SELECT report, points, boundaries FROM steps WHERE job_id = $1 AND step = $2",
        )
        .bind(id)
        .bind(step)
        .fetch_optional(pool)
        .await?);
        row.map(|(report, points, boundaries)| {
            StoredStep::from_text(report, points, boundaries)
                .map_err(|e| sqlx::Error::Decode(Box::new(e)))
        })
        .transpose()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A directory of a test's own, removed when it drops.
    struct ScratchDir(std::path::PathBuf);

    impl ScratchDir {
        fn new(tag: &str) -> Self {
            let dir = std::env::temp_dir().join(format!("mpm-store-{tag}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            ScratchDir(dir)
        }
    }

    impl Drop for ScratchDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// A store in a directory of its own, removed with it.
    struct Scratch {
        store: Store,
        _dir: ScratchDir,
    }

    impl std::ops::Deref for Scratch {
        type Target = Store;
        fn deref(&self) -> &Store {
            &self.store
        }
    }

    async fn store(tag: &str) -> Scratch {
        let dir = ScratchDir::new(tag);
        let store = Store::open(dir.0.join("jobs.sqlite").to_str().unwrap())
            .await
            .unwrap();
        Scratch { store, _dir: dir }
    }

    /// Whether a worker's claim finds no job.
    async fn nothing_to_claim(store: &Store) -> bool {
        store
            .claim("next", Duration::from_secs(30))
            .await
            .unwrap()
            .is_none()
    }

    fn new_job(case_json: &str) -> NewJob<'_> {
        NewJob {
            case_json,
            title: None,
            points: 1,
            load_steps: 10,
            idempotency_key: None,
        }
    }

    fn step_of(bytes: usize) -> StoredStep {
        let points = format!("{{\"x\": \"{}\"}}", "p".repeat(bytes));
        StoredStep::from_text("{}".into(), points, "[]".into()).unwrap()
    }

    /// A running job with one finished step, claimed by `owner` with `lease`.
    async fn running_job(store: &Store, owner: &str, lease: Duration) -> i64 {
        let id = match store.insert(&new_job("{}"), i64::MAX).await.unwrap() {
            Inserted::New(id) => id,
            other => panic!("{other:?}"),
        };
        let claimed = store.claim(owner, lease).await.unwrap().unwrap();
        assert_eq!(claimed.id, id);
        let step = StoredStep::from_text("{}".into(), "{}".into(), "[]".into()).unwrap();
        assert!(store.save_step(id, owner, 1, 3, &step, None).await.unwrap());
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
        assert!(nothing_to_claim(&store).await);

        for id in [orphan, requested] {
            let job = store.get(id).await.unwrap().unwrap();
            assert_eq!(job.status, JobStatus::Cancelled, "job {id}");
            assert_eq!(store.step_reports(id).await.unwrap().len(), 1, "job {id}");
        }
    }

    /// Retention deletes only jobs that ended before the cut-off, with their
    /// steps; running and queued jobs stay whatever their age.
    #[tokio::test]
    async fn pruning_deletes_only_jobs_that_ended_before_the_cut_off() {
        let store = store("prune").await;
        let ended = running_job(&store, "w", Duration::from_secs(30)).await;
        assert!(
            store
                .finish(ended, "w", JobStatus::Succeeded, 1.0, None)
                .await
                .unwrap()
        );
        let still_running = running_job(&store, "v", Duration::from_secs(30)).await;
        tokio::time::sleep(Duration::from_millis(20)).await;
        assert_eq!(store.prune(Duration::from_secs(3600)).await.unwrap(), 0);
        assert_eq!(store.prune(Duration::ZERO).await.unwrap(), 1);
        assert!(store.get(ended).await.unwrap().is_none());
        assert!(store.step_reports(ended).await.unwrap().is_empty());
        assert!(store.get(still_running).await.unwrap().is_some());
    }

    async fn checkpoints(store: &Store) -> i64 {
        on_pool!(store, |pool| sqlx::query_scalar(
            "SELECT COUNT(*) FROM checkpoints"
        )
        .fetch_one(pool)
        .await
        .unwrap())
    }

    /// A job with a checkpoint, put back in the queue by a shutdown, resumes
    /// from it when claimed; cancelled while queued, it leaves no checkpoint
    /// behind (they are 130 bytes a point).
    #[tokio::test]
    async fn a_requeued_job_resumes_and_a_cancelled_one_leaves_no_checkpoint() {
        let store = store("requeue").await;
        let id = running_job(&store, "w", Duration::from_secs(30)).await;
        let step = StoredStep::from_text("{}".into(), "{}".into(), "[]".into()).unwrap();
        let saved = store.save_step(id, "w", 2, 4, &step, Some(b"state")).await;
        assert!(saved.unwrap());
        store.save_step(id, "w", 3, 5, &step, None).await.unwrap();
        store.requeue(id, "w").await.unwrap();
        let queued = store.get(id).await.unwrap().unwrap();
        assert_eq!((queued.status, queued.steps_done), (JobStatus::Queued, 2));
        assert_eq!(
            queued.newton_iterations,
            3 + 4,
            "iterations up to the checkpoint"
        );
        assert_eq!(
            store.step_reports(id).await.unwrap().len(),
            2,
            "steps 1 and 2"
        );

        let claimed = store
            .claim("v", Duration::from_secs(30))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(claimed.checkpoint, Some((2, b"state".to_vec())));
        assert_eq!(store.get(id).await.unwrap().unwrap().resumed_from, Some(2));
        store.requeue(id, "v").await.unwrap();
        assert_eq!(store.cancel(id).await.unwrap(), CancelOutcome::Cancelled);
        assert_eq!(checkpoints(&store).await, 0);
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
        let Inserted::New(first) = store.insert(&job("{\"a\": 1}"), 10).await.unwrap() else {
            panic!("the first insert makes a job");
        };
        match store.insert(&job("{\"b\": 2}"), 10).await.unwrap() {
            Inserted::Earlier(earlier) => {
                assert_eq!(earlier.id, first);
                assert_eq!(earlier.case_json, "{\"a\": 1}");
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(store.list(None, 10, 0).await.unwrap().1, 1);
    }

    /// The database's disk filled while a job stored its steps (SQLite's
    /// page limit stands in for the disk here). Writes fail with a full
    /// disk, the store says so, and once space is freed every write
    /// succeeds again and everything acknowledged survives a reopening.
    /// Before the pool refused connections left inside a transaction, one
    /// sat in it with SQLite's write lock: the others' writes waited and
    /// failed ("database is locked"), and what ran on it was lost.
    #[tokio::test]
    async fn after_a_full_disk_no_acknowledged_write_is_lost() {
        let dir = ScratchDir::new("full");
        let path = dir.0.join("jobs.sqlite");
        let limited = SqliteConnectOptions::from_str("sqlite:")
            .unwrap()
            .filename(&path)
            .pragma("max_page_count", "80");
        let store = Store::open_sqlite(limited, 2).await.unwrap();
        let lease = Duration::from_secs(30);

        let ballast = running_job(&store, "b", lease).await;
        assert!(
            store
                .save_step(ballast, "b", 2, 1, &step_of(100_000), None)
                .await
                .unwrap()
        );
        assert!(
            store
                .finish(ballast, "b", JobStatus::Succeeded, 1.0, None)
                .await
                .unwrap()
        );

        let job = running_job(&store, "w", lease).await;
        let mut step = 2;
        let full = loop {
            match store
                .save_step(job, "w", step, 1, &step_of(20_000), Some(&[7; 3000]))
                .await
            {
                Ok(held) => assert!(held),
                Err(e) => break e,
            }
            step += 1;
            assert!(step < 100, "the page limit was never reached");
        };
        assert!(is_disk_full(&full), "{full}");
        assert!(store.storage_trouble().is_some());
        // What the service does while the disk is full: each fails or not,
        // and none may leave the store unable to write once space is back.
        for k in 0..4 {
            let _ = store
                .save_step(job, "w", step, 1, &step_of(20_000), Some(&[7; 3000]))
                .await;
            let _ = store.claim("x", lease).await;
            let _ = store.insert(&new_job(&"c".repeat(30_000 * k)), 100).await;
            let _ = store.renew(job, "w", lease).await;
            let _ = store.cancel(ballast).await;
        }

        // Space back: the ballast's pages go free, and the store's own
        // write (what /health makes) says so before any job writes.
        assert_eq!(store.delete(ballast).await.unwrap(), DeleteOutcome::Deleted);
        assert!(store.recheck_storage().await.is_none());
        assert!(
            store
                .save_step(job, "w", step, 1, &step_of(10), None)
                .await
                .unwrap()
        );
        assert!(store.storage_trouble().is_none(), "a stored step clears it");
        assert!(
            store
                .finish(job, "w", JobStatus::Succeeded, 1.0, None)
                .await
                .unwrap()
        );
        let Inserted::New(queued) = store.insert(&new_job("{}"), 100).await.unwrap() else {
            panic!("the queue takes a job")
        };
        on_pool!(store, |pool| pool.close().await);

        let reopened = Store::open(path.to_str().unwrap()).await.unwrap();
        assert!(
            reopened.get(ballast).await.unwrap().is_none(),
            "the delete stands"
        );
        let ended = reopened.get(job).await.unwrap().unwrap();
        assert_eq!(
            (ended.status, ended.steps_done),
            (JobStatus::Succeeded, step)
        );
        assert_eq!(
            reopened.get(queued).await.unwrap().unwrap().status,
            JobStatus::Queued
        );
    }

    /// A cancel asked for while a worker ran the job, which the worker had
    /// not yet seen when it was stopped (SIGTERM): the job ends cancelled,
    /// with its steps, and is never claimed again. Before, it went back to
    /// the queue and ran to success.
    #[tokio::test]
    async fn a_job_handed_back_after_a_cancel_request_ends_cancelled() {
        let store = store("cancel-requeue").await;
        let id = running_job(&store, "w", Duration::from_secs(30)).await;
        assert_eq!(store.cancel(id).await.unwrap(), CancelOutcome::Requested);
        assert_eq!(store.requeue(id, "w").await.unwrap(), Requeued::Cancelled);
        let job = store.get(id).await.unwrap().unwrap();
        assert_eq!(job.status, JobStatus::Cancelled);
        assert!(job.finished_at.is_some());
        assert_eq!(store.step_reports(id).await.unwrap().len(), 1);
        assert!(nothing_to_claim(&store).await);
    }

    /// Leases are judged by the database's clock: the expiry a claim
    /// stores is the database's time plus the lease, whatever the
    /// caller's clock says.
    #[tokio::test]
    async fn leases_run_on_the_database_clock() {
        let store = store("clock").await;
        let id = running_job(&store, "w", Duration::from_secs(30)).await;
        let expires: f64 = on_pool!(store, |pool| sqlx::query_scalar(
            "SELECT lease_expires_at FROM jobs WHERE id = $1"
        )
        .bind(id)
        .fetch_one(pool)
        .await
        .unwrap());
        let clock = store.clock().await.unwrap();
        assert!(
            (expires - clock - 30.0).abs() < 1.0,
            "{expires} against {clock}"
        );
        assert!(nothing_to_claim(&store).await);
    }

    /// Simultaneous submissions at the queue's limit: exactly the limit's
    /// number are queued (SQLite took 55 of 200 at a limit of 50).
    #[tokio::test]
    async fn the_queue_limit_holds_under_simultaneous_submissions() {
        let store = store("cap").await;
        let tries = (0..40).map(|_| {
            let store = store.store.clone();
            tokio::spawn(async move { store.insert(&new_job("{}"), 10).await })
        });
        let mut new = 0;
        for t in tries {
            match t.await.unwrap().unwrap() {
                Inserted::New(_) => new += 1,
                Inserted::QueueFull => {}
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(new, 10);
        assert_eq!(store.queued().await.unwrap(), 10);
    }

    /// A job whose runs each get further before their workers die keeps
    /// its attempts; one that makes no progress uses them up.
    #[tokio::test]
    async fn only_attempts_without_progress_count_against_the_limit() {
        let store = store("attempts").await;
        let id = running_job(&store, "w0", Duration::ZERO).await;
        let stalled = || async {
            on_pool!(store, |pool| sqlx::query_scalar::<_, i64>(
                "SELECT stalled_attempts FROM jobs WHERE id = $1"
            )
            .bind(id)
            .fetch_one(pool)
            .await
            .unwrap())
        };
        for k in 1..=4 {
            // This run stores a later checkpoint, then its worker dies.
            let owner = format!("w{}", k - 1);
            let step = StoredStep::from_text("{}".into(), "{}".into(), "[]".into()).unwrap();
            assert!(
                store
                    .save_step(id, &owner, k, 1, &step, Some(b"state"))
                    .await
                    .unwrap()
            );
            tokio::time::sleep(Duration::from_millis(5)).await;
            assert_eq!(store.fail_exhausted(2).await.unwrap(), 0);
            let claimed = store.claim(&format!("w{k}"), Duration::ZERO).await.unwrap();
            assert_eq!(claimed.map(|c| c.id), Some(id));
            assert_eq!(stalled().await, 1, "run {k} made progress");
        }
        // No progress: the next claim is a second stalled attempt, and the
        // limit of 2 is reached.
        tokio::time::sleep(Duration::from_millis(5)).await;
        assert!(store.claim("w5", Duration::ZERO).await.unwrap().is_some());
        assert_eq!(stalled().await, 2);
        tokio::time::sleep(Duration::from_millis(5)).await;
        assert_eq!(store.fail_exhausted(2).await.unwrap(), 1);
        assert_eq!(store.get(id).await.unwrap().unwrap().attempts, 6);
    }
}
