//! Fairing as a background job: a `fair` of a network part's face runs on
//! the blocking pool on a snapshot of the face's mesh
//! ([`FairingInput`]), so the design's actor goes on serving drags and
//! edits of every client while it runs.
//!
//! * Progress goes straight from the job to the design's event channel
//!   ([`DesignEvent::FairingProgress`]): iteration 0 when it starts, then at
//!   most one per [`PROGRESS_INTERVAL`].
//! * Cancel (any editor, or the part's deletion, or the actor stopping)
//!   sets the job's flag; the kernel's progress callback reads it after
//!   every sweep, so the run stops within one sweep and restores its mesh.
//!   A cancelled job changes nothing, even when its result was already on
//!   its way.
//! * On completion the job hands its result back to the actor
//!   ([`super::actor::Request::FairingDone`]), which applies it as one
//!   undoable edit ([`NetworkEditDoc::SetFaired`]) — unless the face's mesh
//!   is no longer the one the job started from (a curve of the face moved,
//!   an undo, curves added or removed). Then the result is *discarded* with
//!   a message, not re-run: the result fits a mesh that is gone, a re-run
//!   would silently redo work the person may no longer want (they reshaped
//!   the face meanwhile) and, under a continuous drag, could chase the
//!   shape forever. When the face's mesh is bit for bit the one the job
//!   started from (another face, another part or nothing changed), the
//!   result is exactly the synchronous run's on the face as it is, and it
//!   is applied.
//! * One job per face; at most [`MAX_JOBS`] per design.

use super::actor::{DesignEvent, Request};
use super::command::Ack;
use super::error::{CommandError, ErrorKind};
use super::model::{DesignModel, Edit};
use super::network_engine::{FairingDoc, FairingInput, NetworkEditDoc};
use super::part::PartBody;
use crate::store::Role;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::{broadcast, mpsc, oneshot};
use vsculpt_kernel::fairing::{Control, FairingError, Progress};

/// The shortest time between two progress events of one job.
pub const PROGRESS_INTERVAL: Duration = Duration::from_millis(100);
/// Most fairing jobs running at once in one design.
pub const MAX_JOBS: usize = 16;

/// Whether `command` asks for a fairing (answered when its job ends).
pub fn is_fair(command: &super::command::Command) -> bool {
    matches!(
        command,
        super::command::Command::Edit(Edit::Network {
            edit: NetworkEditDoc::Fair(_),
            ..
        })
    )
}

/// The answer a job owes the client that asked for it.
type Reply = Option<oneshot::Sender<Result<Ack, CommandError>>>;

/// A job's progress (sent to every client).
#[derive(Clone, Debug, PartialEq)]
pub struct JobProgress {
    /// The network part.
    pub part: u64,
    /// The face.
    pub face: usize,
    /// The client that asked for it.
    pub client: u64,
    /// Sweeps done.
    pub iteration: usize,
    /// Sweeps at most.
    pub max_iterations: usize,
    /// The largest move of the last sweep (0 before the first).
    pub max_move: f64,
    /// The move below which the run has converged.
    pub threshold: f64,
    /// Estimated fraction done, in [0, 1].
    pub fraction: f64,
}

/// How a job ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobOutcome {
    /// Its result was applied (one undoable edit).
    Applied,
    /// Cancelled: nothing changed.
    Cancelled,
    /// The face changed while it ran: nothing changed.
    Discarded,
    /// The kernel (or the edit) refused: nothing changed.
    Failed,
}

/// A job's end (sent to every client).
#[derive(Clone, Debug, PartialEq)]
pub struct JobEnded {
    /// The network part.
    pub part: u64,
    /// The face.
    pub face: usize,
    /// The client that asked for it.
    pub client: u64,
    /// How it ended.
    pub outcome: JobOutcome,
    /// Sweeps run.
    pub iterations: usize,
    /// Whether it converged (applied runs only).
    pub converged: bool,
    /// Why, in words.
    pub message: String,
}

/// A finished run, on its way back to the actor.
pub struct JobDone {
    part: u64,
    face: usize,
    id: u64,
    result: Result<super::part::FairedFaceDoc, FairingError>,
}

/// A running job as the actor keeps it.
struct Job {
    id: u64,
    client: u64,
    input: Arc<FairingInput>,
    cancel: Arc<AtomicBool>,
    /// Its latest progress (written by the run after every sweep, read for
    /// a joiner's snapshot).
    progress: Arc<Mutex<JobProgress>>,
    /// Why it was cancelled, once it is.
    reason: Option<String>,
    reply: Reply,
}

/// A result the actor applies as an edit; hand it back with the edit's
/// outcome to [`FairingJobs::applied`].
pub struct Apply {
    /// The edit that applies the result.
    pub edit: Edit,
    part: u64,
    face: usize,
    client: u64,
    iterations: usize,
    converged: bool,
    reply: Reply,
}

/// The fairing jobs of one design, keyed by (part, face).
pub struct FairingJobs {
    jobs: BTreeMap<(u64, usize), Job>,
    next: u64,
    /// The actor's queue (weak: a job does not keep a stopped actor alive).
    actor: mpsc::WeakSender<Request>,
    events: broadcast::Sender<DesignEvent>,
}

fn send(reply: Reply, out: Result<Ack, CommandError>) {
    if let Some(r) = reply {
        let _ = r.send(out);
    }
}

fn conflict(msg: impl Into<String>) -> CommandError {
    CommandError::new(ErrorKind::Conflict, msg)
}

/// The fraction done after `p`: the larger of the sweeps' fraction and how
/// far the largest move has come down, on a log scale, from the first
/// sweep's (`first`) toward the threshold.
pub fn fraction(p: &Progress, first: f64, max_iterations: usize) -> f64 {
    let by_sweeps = p.iteration as f64 / max_iterations.max(1) as f64;
    let by_moves = if first > p.threshold && p.max_move > 0.0 && p.threshold > 0.0 {
        (first / p.max_move).ln() / (first / p.threshold).ln()
    } else if p.max_move <= p.threshold {
        1.0
    } else {
        0.0
    };
    let f = by_sweeps.max(by_moves);
    if f.is_finite() {
        f.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

impl FairingJobs {
    /// No jobs; finished runs come back on `actor`, progress goes to
    /// `events`.
    pub fn new(actor: mpsc::WeakSender<Request>, events: broadcast::Sender<DesignEvent>) -> Self {
        Self {
            jobs: BTreeMap::new(),
            next: 1,
            actor,
            events,
        }
    }

    /// Whether any job is running.
    pub fn is_empty(&self) -> bool {
        self.jobs.is_empty()
    }

    /// The running jobs with their latest progress, by (part, face).
    pub fn running(&self) -> Vec<JobProgress> {
        self.jobs
            .values()
            .map(|j| match j.progress.lock() {
                Ok(p) => p.clone(),
                Err(poisoned) => poisoned.into_inner().clone(),
            })
            .collect()
    }

    /// Starts fairing `f` on network part `part` for `client` (of `role`;
    /// client 0 is the HTTP API's editor). A refusal is answered on `reply`
    /// at once and changes nothing; a started job answers when it ends.
    pub fn start(
        &mut self,
        model: &DesignModel,
        client: u64,
        role: Option<Role>,
        part: u64,
        f: &FairingDoc,
        reply: Reply,
    ) {
        match self.try_start(model, client, role, part, f) {
            Ok(job) => {
                let key = (part, f.face);
                let job = Job { reply, ..job };
                self.jobs.insert(key, job);
            }
            Err(e) => send(reply, Err(e)),
        }
    }

    fn try_start(
        &mut self,
        model: &DesignModel,
        client: u64,
        role: Option<Role>,
        part: u64,
        f: &FairingDoc,
    ) -> Result<Job, CommandError> {
        match (client, role) {
            (0, _) | (_, Some(Role::Editor)) => {}
            (_, Some(r)) => {
                return Err(CommandError::new(
                    ErrorKind::Forbidden,
                    format!("a {} may not do this", format!("{r:?}").to_lowercase()),
                ));
            }
            (_, None) => return Err(CommandError::new(ErrorKind::Forbidden, "not joined")),
        }
        let doc = model
            .doc()
            .part(part)
            .ok_or_else(|| CommandError::new(ErrorKind::UnknownPart, format!("no part {part}")))?;
        if !matches!(doc.body, PartBody::Network(_)) {
            return Err(CommandError::new(
                ErrorKind::Incompatible,
                format!("part {part} is a {}, not a network", doc.body.kind()),
            ));
        }
        if doc.locked {
            return Err(CommandError::new(
                ErrorKind::Locked,
                format!("part {} ({}) is locked: unlock it first", doc.id, doc.name),
            ));
        }
        let engine = model.network(part).ok_or_else(|| {
            CommandError::new(ErrorKind::UnknownPart, format!("no network part {part}"))
        })?;
        let input = Arc::new(engine.fairing_input(f)?);
        if let Some(j) = self.jobs.get(&(part, f.face)) {
            return Err(conflict(format!(
                "face {} of part {part} is already being faired (asked by client {}): wait for it or cancel it",
                f.face, j.client
            )));
        }
        if self.jobs.len() >= MAX_JOBS {
            return Err(conflict(format!(
                "{MAX_JOBS} fairing jobs are running in this design: wait for one to end or cancel one"
            )));
        }
        let id = self.next;
        self.next += 1;
        let cancel = Arc::new(AtomicBool::new(false));
        let max_iterations = f.max_iterations;
        let started = JobProgress {
            part,
            face: f.face,
            client,
            iteration: 0,
            max_iterations,
            max_move: 0.0,
            threshold: 0.0,
            fraction: 0.0,
        };
        let progress = Arc::new(Mutex::new(started.clone()));
        let _ = self
            .events
            .send(DesignEvent::FairingProgress(Box::new(started)));
        let (run_input, run_cancel) = (input.clone(), cancel.clone());
        let run_progress = progress.clone();
        let (events, actor) = (self.events.clone(), self.actor.clone());
        let face = f.face;
        tokio::task::spawn_blocking(move || {
            let mut last = Instant::now();
            let mut first = None;
            let result = run_input.run_kernel(|p| {
                if run_cancel.load(Ordering::SeqCst) {
                    return Control::Cancel;
                }
                let first = *first.get_or_insert(p.max_move);
                let now = JobProgress {
                    part,
                    face,
                    client,
                    iteration: p.iteration,
                    max_iterations,
                    max_move: p.max_move,
                    threshold: p.threshold,
                    fraction: fraction(p, first, max_iterations),
                };
                if let Ok(mut latest) = run_progress.lock() {
                    *latest = now.clone();
                }
                if last.elapsed() >= PROGRESS_INTERVAL {
                    last = Instant::now();
                    let _ = events.send(DesignEvent::FairingProgress(Box::new(now)));
                }
                Control::Continue
            });
            if let Some(tx) = actor.upgrade() {
                let _ = tx.blocking_send(Request::FairingDone(Box::new(JobDone {
                    part,
                    face,
                    id,
                    result,
                })));
            }
        });
        tracing::info!(part, face, client, "fairing job started");
        Ok(Job {
            id,
            client,
            input,
            cancel,
            progress,
            reason: None,
            reply: None,
        })
    }

    /// Cancels the job on `face` of `part` (asked by `client`); no job
    /// there is `out_of_range`.
    pub fn cancel(&mut self, part: u64, face: usize, client: u64) -> Result<Ack, CommandError> {
        let job = self.jobs.get_mut(&(part, face)).ok_or_else(|| {
            CommandError::new(
                ErrorKind::InvalidValue,
                format!("no fairing job on face {face} of part {part}"),
            )
        })?;
        if job.reason.is_none() {
            job.reason = Some(format!("cancelled by client {client}"));
        }
        job.cancel.store(true, Ordering::SeqCst);
        Ok(Ack::default())
    }

    /// Cancels the jobs of parts that are no longer network parts of
    /// `model` (deleted, or gone with an undo).
    pub fn cancel_orphans(&mut self, model: &DesignModel) {
        for ((part, _), job) in &mut self.jobs {
            if model.network(*part).is_none() && job.reason.is_none() {
                job.reason = Some(format!("part {part} was deleted"));
                job.cancel.store(true, Ordering::SeqCst);
            }
        }
    }

    fn ended(&self, e: JobEnded) {
        tracing::info!(part = e.part, face = e.face, outcome = ?e.outcome, "fairing job ended: {}", e.message);
        let _ = self.events.send(DesignEvent::FairingEnded(Box::new(e)));
    }

    /// A run came back: a cancelled, refused or stale one ends here (its
    /// requester hears why, everyone gets the end); a result still fitting
    /// its face comes back as the edit to apply.
    pub fn finish(&mut self, done: JobDone, model: &DesignModel) -> Option<Apply> {
        let key = (done.part, done.face);
        if self.jobs.get(&key).is_none_or(|j| j.id != done.id) {
            return None;
        }
        let job = self.jobs.remove(&key)?;
        let (part, face, client) = (done.part, done.face, job.client);
        let end = |outcome, iterations, message: String| JobEnded {
            part,
            face,
            client,
            outcome,
            iterations,
            converged: false,
            message,
        };
        if job.cancel.load(Ordering::SeqCst) {
            let why = job.reason.unwrap_or_else(|| "cancelled".into());
            let iterations = match &done.result {
                Ok(f) => f.iterations,
                Err(FairingError::Cancelled { iterations }) => *iterations,
                Err(_) => 0,
            };
            let message = format!("fairing of face {face} of part {part} {why}: nothing changed");
            self.ended(end(JobOutcome::Cancelled, iterations, message.clone()));
            send(job.reply, Err(conflict(message)));
            return None;
        }
        let faired = match done.result {
            Ok(f) => f,
            Err(e) => {
                let message = format!("fairing of face {face} of part {part} failed: {e}");
                self.ended(end(JobOutcome::Failed, 0, message.clone()));
                send(
                    job.reply,
                    Err(CommandError::new(ErrorKind::InvalidValue, message)),
                );
                return None;
            }
        };
        if !model
            .network(part)
            .is_some_and(|n| n.face_is_as(&job.input))
        {
            let message = format!(
                "face {face} of part {part} changed while it was faired (a curve of it moved, an undo, curves added or removed): the result fits a mesh that is gone and was discarded; fair it again"
            );
            self.ended(end(
                JobOutcome::Discarded,
                faired.iterations,
                message.clone(),
            ));
            send(job.reply, Err(conflict(message)));
            return None;
        }
        Some(Apply {
            part,
            face,
            client,
            iterations: faired.iterations,
            converged: faired.converged,
            edit: Edit::Network {
                part,
                edit: NetworkEditDoc::SetFaired(faired),
            },
            reply: job.reply,
        })
    }

    /// The edit of `apply` ran with `out`: everyone hears how the job
    /// ended, its requester gets `out`.
    pub fn applied(&self, apply: Apply, out: Result<Ack, CommandError>) {
        let (outcome, message) = match &out {
            Ok(_) => (
                JobOutcome::Applied,
                format!(
                    "face {} faired in {} sweeps ({})",
                    apply.face,
                    apply.iterations,
                    if apply.converged {
                        "converged"
                    } else {
                        "not converged"
                    }
                ),
            ),
            Err(e) => (
                JobOutcome::Failed,
                format!(
                    "the faired face {} of part {} could not be applied: {e}",
                    apply.face, apply.part
                ),
            ),
        };
        self.ended(JobEnded {
            part: apply.part,
            face: apply.face,
            client: apply.client,
            outcome,
            iterations: apply.iterations,
            converged: outcome == JobOutcome::Applied && apply.converged,
            message,
        });
        send(apply.reply, out);
    }
}

impl Drop for FairingJobs {
    /// A stopped (or failed) actor cancels its jobs.
    fn drop(&mut self) {
        for job in self.jobs.values() {
            job.cancel.store(true, Ordering::SeqCst);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(iteration: usize, max_move: f64) -> Progress {
        Progress {
            iteration,
            max_move,
            threshold: 1e-10,
        }
    }

    #[test]
    fn the_fraction_follows_sweeps_or_moves_whichever_is_further() {
        // Moves from 1e-2 to 1e-6: half-way to 1e-10 on a log scale.
        assert!((fraction(&p(10, 1e-6), 1e-2, 1000) - 0.5).abs() < 1e-12);
        // Sweeps further than moves.
        assert!((fraction(&p(800, 1e-3), 1e-2, 1000) - 0.8).abs() < 1e-12);
        // Converged: done.
        assert_eq!(fraction(&p(3, 1e-11), 1e-2, 1000), 1.0);
        // A move growing past the first's: never negative.
        assert_eq!(fraction(&p(1, 1.0), 1e-2, 1000), 0.001);
    }
}
