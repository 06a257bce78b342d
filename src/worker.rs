//! The worker pool: dedicated OS threads that claim jobs and run the solver,
//! off the async runtime. Each running job holds a lease that a small task
//! on the runtime renews; the solver reports every finished step, which the
//! worker stores at once, so a client can read step 1 while step 2 runs.
//! Every few steps ([`crate::config::checkpoint_interval`]) the solver's
//! state is stored with the step; a job claimed again (its worker died, or
//! was stopped) resumes from it.

use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use mpm::case::OutputSpec;
use mpm::case::solid::{SolidCase, SolidOutput};
use mpm::{
    Case, Checkpoint, CheckpointError, Observer, RunReport, Simulation, SolidCheckpoint,
    SolidStepState, StepReport, StepState,
};
use tokio::runtime::Handle;
use tokio::sync::Notify;

use crate::config::Config;
use crate::jobs::{Claimed, Failure, FailureKind, JobStatus, Requeued, Store};
use crate::step::StoredStep;

/// What the workers share.
struct Shared {
    store: Store,
    config: Arc<Config>,
    runtime: Handle,
    /// Woken when a job is submitted, so an idle worker starts at once.
    wake: Arc<Notify>,
    /// Set at shutdown: stop claiming, hand running jobs back to the queue.
    stopping: AtomicBool,
    /// Distinguishes this process's workers in lease_owner.
    process_tag: String,
    running: Arc<RunningJobs>,
}

/// The stop flags of the jobs this process is running, so a cancel request
/// reaches the solver at its next Newton iteration. (Jobs run by another
/// process see the request through their lease renewal.)
#[derive(Default)]
pub struct RunningJobs(Mutex<HashMap<i64, Arc<StopFlags>>>);

impl RunningJobs {
    /// Flags job `id` for cancellation if it runs here.
    pub fn cancel(&self, id: i64) {
        if let Some(flags) = self.jobs().get(&id) {
            flags.cancel_requested.store(true, Ordering::SeqCst);
        }
    }

    /// Fresh stop flags for job `id`, which starts running here.
    fn register(&self, id: i64) -> Arc<StopFlags> {
        let flags = Arc::new(StopFlags::default());
        self.jobs().insert(id, flags.clone());
        flags
    }

    /// Job `id` no longer runs here.
    fn remove(&self, id: i64) {
        self.jobs().remove(&id);
    }

    fn jobs(&self) -> std::sync::MutexGuard<'_, HashMap<i64, Arc<StopFlags>>> {
        self.0.lock().expect("not poisoned")
    }
}

pub struct WorkerPool {
    shared: Arc<Shared>,
    threads: Vec<JoinHandle<()>>,
}

impl WorkerPool {
    /// Starts `config.workers` threads. Must be called from within the tokio
    /// runtime whose handle the workers use for database access.
    pub fn start(
        store: Store,
        config: Arc<Config>,
        wake: Arc<Notify>,
        running: Arc<RunningJobs>,
    ) -> WorkerPool {
        let shared = Arc::new(Shared {
            store,
            runtime: Handle::current(),
            wake,
            stopping: AtomicBool::new(false),
            process_tag: format!(
                "pid{}-{:x}",
                std::process::id(),
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .unwrap_or_default()
                    .as_micros()
            ),
            config,
            running,
        });
        let threads = (0..shared.config.workers)
            .map(|i| {
                let shared = shared.clone();
                std::thread::Builder::new()
                    .name(format!("mpm-worker-{i}"))
                    .spawn(move || worker_loop(&shared, i))
                    .expect("spawn worker thread")
            })
            .collect();
        WorkerPool { shared, threads }
    }

    /// Stops claiming, makes running jobs stop at their next Newton iteration
    /// and go back to the queue, and waits for the threads.
    pub fn shutdown(self) {
        self.shared.stopping.store(true, Ordering::SeqCst);
        self.shared.wake.notify_waiters();
        for t in self.threads {
            let _ = t.join();
        }
    }
}

fn worker_loop(shared: &Shared, index: usize) {
    let owner = format!("{}-w{index}", shared.process_tag);
    while !shared.stopping.load(Ordering::SeqCst) {
        let claimed = shared.runtime.block_on(async {
            shared
                .store
                .fail_exhausted(shared.config.max_attempts as i64)
                .await?;
            shared.store.claim(&owner, shared.config.lease).await
        });
        match claimed {
            Ok(Some(job)) => {
                if run_job(shared, &owner, job) == Ran::OutOfStorage {
                    // The database's disk is full: the job went back to the
                    // queue, to resume from its checkpoint once there is
                    // room; try again later rather than at once.
                    tracing::warn!(
                        seconds = STORAGE_RETRY.as_secs(),
                        "the database cannot store results; waiting before claiming again"
                    );
                    std::thread::sleep(STORAGE_RETRY);
                }
            }
            Ok(None) => {
                // Sleep until a submission wakes us or the poll interval
                // passes (expired leases need no wake-up).
                let poll = shared.config.poll_interval;
                let wake = shared.wake.clone();
                shared.runtime.block_on(async move {
                    let _ = tokio::time::timeout(poll, wake.notified()).await;
                });
            }
            Err(e) => {
                shared.store.note_failure(&e);
                tracing::error!(error = %e, "claiming a job failed");
                std::thread::sleep(shared.config.poll_interval);
            }
        }
    }
}

/// How long a worker waits before claiming again after a job's results
/// could not be stored for want of space.
const STORAGE_RETRY: Duration = Duration::from_secs(10);

/// How a run went, as far as the worker loop cares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ran {
    Done,
    /// Its results could not be stored for want of space or on an I/O
    /// error: it went back to the queue.
    OutOfStorage,
}

/// Why a run asked the solver to stop.
#[derive(Default)]
pub struct StopFlags {
    cancel_requested: AtomicBool,
    lease_lost: AtomicBool,
}

fn run_job(shared: &Shared, owner: &str, job: Claimed) -> Ran {
    let started = Instant::now();
    tracing::info!(job = job.id, attempt = job.attempts, "job started");
    let flags = shared.running.register(job.id);
    let renewal = shared.runtime.spawn(renew_lease(
        shared.store.clone(),
        job.id,
        owner.to_string(),
        shared.config.lease,
        flags.clone(),
    ));

    let mut observer = JobObserver {
        shared,
        owner,
        job: job.id,
        flags: &flags,
        deadline: started + shared.config.limits.job_time_limit,
        checkpoints: crate::config::CheckpointSchedule::with_wait(1, Duration::MAX),
        output: OutputSpec::default(),
        solid: None,
        timed_out: false,
        store_error: None,
        out_of_storage: false,
    };
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        if mpm::case::solid::is_solid(&job.case_json) {
            run_solid(shared, owner, &job, &mut observer)
        } else {
            run_plane(shared, owner, &job, &mut observer)
        }
    }));
    renewal.abort();
    shared.running.remove(job.id);
    let seconds = started.elapsed().as_secs_f64();
    let outcome = outcome.unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        tracing::error!(job = job.id, panic = %what, "solver panicked");
        Err(Failure::new(
            FailureKind::Internal,
            "the solver stopped on an internal error",
        ))
    });
    let out_of_storage = observer.out_of_storage;
    let end = match outcome {
        Ok(_) => End::Final(JobStatus::Succeeded, None),
        Err(f) if f.kind == FailureKind::Cancelled => stopped(shared, &observer, &flags, f),
        Err(f) => End::Final(JobStatus::Failed, Some(f)),
    };
    let store = &shared.store;
    // What the job's row says when this run is done with it.
    let result: Result<&str, sqlx::Error> = shared.runtime.block_on(async {
        match end {
            End::Final(status, failure) => {
                let error = failure.as_ref().map(Failure::json);
                let held = store
                    .finish(job.id, owner, status, seconds, error.as_deref())
                    .await?;
                Ok(if held { status.as_str() } else { "taken over" })
            }
            End::Requeue => Ok(match store.requeue(job.id, owner).await? {
                Requeued::Queued => JobStatus::Queued.as_str(),
                Requeued::Cancelled => JobStatus::Cancelled.as_str(),
                Requeued::NotHeld => "taken over",
            }),
            End::LeaseLost => Ok("taken over"),
        }
    });
    match result {
        Ok(status) => tracing::info!(job = job.id, status, seconds, "job ended"),
        Err(e) => {
            shared.store.note_failure(&e);
            tracing::error!(
                job = job.id,
                error = %e,
                seconds,
                "recording the job's end failed; its lease will expire and it will be retried"
            )
        }
    }
    if out_of_storage {
        Ran::OutOfStorage
    } else {
        Ran::Done
    }
}

/// Runs a claimed plane-strain job, from its checkpoint if it has one.
fn run_plane(
    shared: &Shared,
    owner: &str,
    job: &Claimed,
    observer: &mut JobObserver<'_>,
) -> Result<RunReport, Failure> {
    // The case was validated on submission; a failure here means the
    // stored text was altered or the format changed under it.
    let case = Case::from_json(&job.case_json)
        .map_err(|e| Failure::new(FailureKind::InvalidCase, e.to_string()))?;
    let mut sim = Simulation::new(&case)
        .map_err(|e| Failure::new(FailureKind::InvalidCase, e.to_string()))?;
    observer.checkpoints =
        crate::config::CheckpointSchedule::new(shared.config.checkpoint_every, sim.points.len());
    observer.output = case.output.clone();
    if let Some((step, state)) = &job.checkpoint
        && !resume(
            job.id,
            *step,
            Checkpoint::from_bytes(state).and_then(|c| sim.restore(&c)),
        )
    {
        start_over(shared, owner, job, observer);
    }
    if sim.steps_done() == 0 {
        // Step 0, the undeformed state, so a viewer shows the start.
        let (report, state) = sim.initial_step();
        observer.step_finished(&report, &state);
    }
    sim.run(observer).map_err(|e| {
        let hint = crate::jobs::failure::units_hint(&case, &e);
        let mut failure = Failure::from(e);
        failure.message.push_str(&hint.unwrap_or_default());
        failure
    })
}

/// Runs a claimed 3D job (`analysis.type: "3d"`), from its checkpoint if
/// it has one, as [`run_plane`] does.
fn run_solid(
    shared: &Shared,
    owner: &str,
    job: &Claimed,
    observer: &mut JobObserver<'_>,
) -> Result<RunReport, Failure> {
    // Validated on submission, as a plane-strain case is.
    let case = SolidCase::from_json(&job.case_json)
        .map_err(|e| Failure::new(FailureKind::InvalidCase, e.to_string()))?;
    let mut sim = Simulation::from_solid_case(&case)
        .map_err(|e| Failure::new(FailureKind::InvalidCase, e.to_string()))?;
    observer.checkpoints =
        crate::config::CheckpointSchedule::new(shared.config.checkpoint_every, sim.points.len());
    observer.solid = Some(case.output.clone());
    if let Some((step, state)) = &job.checkpoint
        && !resume(
            job.id,
            *step,
            SolidCheckpoint::from_bytes(state).and_then(|c| sim.restore(&c)),
        )
    {
        start_over(shared, owner, job, observer);
    }
    if sim.steps_done() == 0 {
        // Step 0, the undeformed state, so a viewer shows the start.
        let (report, state) = sim.initial_step();
        observer.solid_step_finished(&report, &state);
    }
    sim.run(observer).map_err(Failure::from)
}

/// Makes the claimed job start over from step 1 (its checkpoint could not
/// be restored).
fn start_over(shared: &Shared, owner: &str, job: &Claimed, observer: &mut JobObserver<'_>) {
    let reset = shared
        .runtime
        .block_on(shared.store.start_over(job.id, owner));
    if let Err(e) = reset {
        observer.store_error = Some(e.to_string());
    }
}

/// Whether a claimed job's checkpoint was `restored`. One that does not
/// fit (a solver of another version wrote it) is logged, and the job starts
/// over from step 1.
fn resume(job: i64, step: i64, restored: Result<(), CheckpointError>) -> bool {
    match restored {
        Ok(()) => {
            tracing::info!(job, step, "resuming from the checkpoint");
            true
        }
        Err(e) => {
            tracing::warn!(job, step, error = %e, "the checkpoint cannot be resumed; starting over");
            false
        }
    }
}

/// How a run ends in the store.
enum End {
    /// A final status, with the failure of a failed job.
    Final(JobStatus, Option<Failure>),
    /// Back to the queue (shutdown): the attempt does not count.
    Requeue,
    /// Nothing to record: the lease was lost and another worker owns the job.
    LeaseLost,
}

/// The end of a run that the solver stopped on request (`cancelled`): the
/// first reason to stop that holds, in order of precedence.
fn stopped(shared: &Shared, observer: &JobObserver<'_>, flags: &StopFlags, f: Failure) -> End {
    if observer.timed_out {
        let f = Failure::new(
            FailureKind::TimeLimit,
            format!(
                "the per-job wall-time limit of {} s was reached ({})",
                shared.config.limits.job_time_limit.as_secs(),
                f.message
            ),
        );
        End::Final(JobStatus::Failed, Some(f))
    } else if observer.out_of_storage {
        // Not the job's fault: back to the queue, to resume from its
        // checkpoint when the disk has room again.
        End::Requeue
    } else if let Some(e) = &observer.store_error {
        let f = Failure::new(
            FailureKind::Internal,
            format!("storing results failed: {e}"),
        );
        End::Final(JobStatus::Failed, Some(f))
    } else if flags.cancel_requested.load(Ordering::SeqCst) {
        End::Final(JobStatus::Cancelled, None)
    } else if shared.stopping.load(Ordering::SeqCst) {
        End::Requeue
    } else {
        End::LeaseLost
    }
}

/// Renews the lease every third of its length; notes a cancel request or a
/// lost lease for the solver to see at its next Newton iteration.
async fn renew_lease(
    store: Store,
    job: i64,
    owner: String,
    lease: Duration,
    flags: Arc<StopFlags>,
) {
    loop {
        tokio::time::sleep(lease / 3).await;
        match store.renew(job, &owner, lease).await {
            Ok(Some(cancel)) => {
                if cancel {
                    flags.cancel_requested.store(true, Ordering::SeqCst);
                }
            }
            Ok(None) => {
                flags.lease_lost.store(true, Ordering::SeqCst);
                return;
            }
            Err(e) => tracing::warn!(job, error = %e, "lease renewal failed; will retry"),
        }
    }
}

/// Stores each finished step and tells the solver when to stop.
struct JobObserver<'a> {
    shared: &'a Shared,
    owner: &'a str,
    job: i64,
    flags: &'a StopFlags,
    deadline: Instant,
    /// When to store the solver's state with a step.
    checkpoints: crate::config::CheckpointSchedule,
    /// Which steps store their points, and which columns.
    output: OutputSpec,
    /// A 3D run's: which steps store their points.
    solid: Option<SolidOutput>,
    timed_out: bool,
    store_error: Option<String>,
    /// The store error was the database's storage failing (a full disk).
    out_of_storage: bool,
}

impl JobObserver<'_> {
    /// Stores a finished step's document, with the solver's state when a
    /// checkpoint is due.
    fn save(&mut self, report: &StepReport, document: &StoredStep, checkpoint: Option<&[u8]>) {
        let saved = self.shared.runtime.block_on(self.shared.store.save_step(
            self.job,
            self.owner,
            report.step as i64,
            report.newton.iterations as i64,
            document,
            checkpoint,
        ));
        match saved {
            Ok(true) => {}
            Ok(false) => self.flags.lease_lost.store(true, Ordering::SeqCst),
            Err(e) => {
                self.out_of_storage = crate::jobs::store::is_storage_error(&e);
                self.store_error = Some(e.to_string());
            }
        }
    }
}

impl Observer for JobObserver<'_> {
    fn step_finished(&mut self, report: &StepReport, state: &StepState<'_>) {
        let document = StoredStep::new(report, state, &self.output, state.load_steps());
        let checkpoint = self
            .checkpoints
            .due(report.step)
            .then(|| state.checkpoint().to_bytes());
        self.save(report, &document, checkpoint.as_deref());
    }

    fn solid_step_finished(&mut self, report: &StepReport, state: &SolidStepState<'_>) {
        let Some(output) = &self.solid else {
            return;
        };
        let document = StoredStep::solid(report, state, output);
        let checkpoint = self
            .checkpoints
            .due(report.step)
            .then(|| state.checkpoint().to_bytes());
        self.save(report, &document, checkpoint.as_deref());
    }

    fn should_cancel(&mut self) -> bool {
        if Instant::now() > self.deadline {
            self.timed_out = true;
        }
        self.timed_out
            || self.store_error.is_some()
            || self.flags.cancel_requested.load(Ordering::SeqCst)
            || self.flags.lease_lost.load(Ordering::SeqCst)
            || self.shared.stopping.load(Ordering::SeqCst)
    }
}
