//! When the pose graph is optimised, and on which thread.
//!
//! **When.** Every `optimize_every_n_nodes` nodes (or a thirtieth of the nodes so far, if
//! more) and `optimize_every_m` metres, if a closure or a fix came in since the last;
//! after a large correction (a loop closed after drift), so that the next searches look
//! where the robot now is; and once more at the end, to the default tolerance.
//!
//! **Beside local SLAM.** An optimisation during the run only steers the next searches
//! and places the next submaps, so it need not hold up the scans that follow it. As
//! Cartographer's global SLAM runs beside its local SLAM (Hess et al. 2016, §IV), the
//! graph is copied as it stands and the copy optimised on a thread of its own while the
//! next nodes are matched, inserted and searched: [`LAG_NODES`] nodes for a periodic
//! optimisation, one loop-closure batch (`loop_closure_batch_nodes`) after a large
//! correction, whose result the next batch's searches need. The result is taken at that
//! node, a fixed point of the trajectory, never when the thread happens to finish, so the
//! trajectory is the same to the bit on any number of threads (with one, the copy is
//! optimised where its result is taken). Nodes and submaps added in between were placed
//! through the old `global_from_local`, and move with the correction. The last
//! optimisation takes the one under way, then runs at once.
//!
//! The optimiser's thread runs at the lowest priority: it takes the time the matcher and
//! the searches leave idle. On the Intel bag on two cores the scans then wait 1.8 s for
//! 3.4 s of optimisation, but the matcher loses some of that to it: over nine alternated
//! runs the whole was 1.03× faster, within the noise (docs/BENCHMARKS.md). It pays where
//! the matcher leaves cores idle. The relation errors of the five benchmark logs moved by
//! at most 0.1 mm.

use super::mapper::Slam;
use super::pose_graph::{EdgeKind, Loss, OptimizeOptions, OptimizeReport, PoseGraph, PoseGraphError};
use crate::geometry::Pose2;
use std::thread::JoinHandle;
use std::time::Instant;

/// The nodes after which a periodic optimisation's result is taken: long enough for the
/// optimiser to finish beside the matching on the benchmark logs, short against the
/// optimisation period (90 nodes by default), so the searches' windows are never far
/// behind the estimate.
pub(super) const LAG_NODES: usize = 30;

/// A periodic optimisation waits for at least this share (1/`PERIOD_SHARE`) of the nodes so
/// far, not only `optimize_every_n_nodes`: its cost grows with the graph, so a fixed period
/// makes the optimisations of a long run cost the square of its length (on the simulator's
/// hour, 224 of them took 27 s). Spaced by a share of the graph, their total grows as
/// n log n. It changes nothing below 30 × 90 = 2,700 nodes (every log of the
/// generalisation bench); an optimisation after a large correction is not held back.
const PERIOD_SHARE: usize = 30;

/// The relative cost change at which an optimisation during the run stops (the last one
/// runs to [`OptimizeOptions`]' default, 10⁻⁶). Those only place the next searches' windows
/// and the next submaps: on the five SLAM-benchmark logs stopping there leaves the final
/// relation error unchanged to 0.1 mm and cuts the optimisation time by half (Intel) to
/// two thirds (MIT Killian, 519 large corrections each optimised at once).
const STEERING_TOLERANCE: f64 = 1e-3;

/// What one optimisation of a graph (one pass per loss) gave.
struct Outcome {
    graph: PoseGraph,
    results: Vec<Result<OptimizeReport, PoseGraphError>>,
    seconds: f64,
}

/// The losses of the closures, one pass each, and the options.
struct Job {
    graph: PoseGraph,
    losses: Vec<Loss>,
    opts: OptimizeOptions,
}

impl Job {
    fn run(mut self) -> Outcome {
        let t0 = Instant::now();
        let mut results = Vec::with_capacity(self.losses.len());
        for &loss in &self.losses {
            self.graph.set_loss_of(EdgeKind::LoopClosure, loss).expect("valid loss");
            results.push(self.graph.optimize(&self.opts));
        }
        Outcome { graph: self.graph, results, seconds: t0.elapsed().as_secs_f64() }
    }
}

enum Work {
    /// One thread: optimised where the result is taken.
    Later(Box<Job>),
    Running(JoinHandle<Outcome>),
}

/// An optimisation under way.
pub(super) struct Pending {
    work: Work,
    /// The node count at which its result is taken.
    take_at: usize,
    /// The last node in the copy.
    last_node: usize,
    /// The graph's node count at the copy: later ones move with the correction.
    graph_nodes: usize,
    /// `global_from_local` when the copy was taken.
    global_from_local: Pose2,
    /// The closures' loss after the last pass.
    loss: Loss,
}

/// Gives the calling thread the lowest CPU priority (nice 19), so that the optimiser runs
/// on what the matcher and the searches leave idle: on two cores they keep both busy
/// much of the time, and at equal priority the optimiser slowed them by as much as it
/// saved. On Linux the nice value belongs to the thread; elsewhere this does nothing.
fn lowest_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: `setpriority` with `who = 0` changes only the calling thread's nice value;
    // a failure (none is expected when lowering it) leaves the priority as it was.
    unsafe {
        libc::setpriority(libc::PRIO_PROCESS, 0, 19);
    }
}

impl Slam {
    /// After a node: takes the result under way when due, then optimises if due.
    pub(super) fn optimise_if_due(&mut self) {
        self.since_optimisation += 1;
        let news = self.loops.since_optimisation + self.fixes.since_optimisation;
        let travelled = self.nodes.last().map_or(0.0, |n| n.path_m) - self.optimised_at_m;
        let period = self.p.optimize_every_n_nodes.max(self.nodes.len() / PERIOD_SHARE);
        let due = self.since_optimisation >= period && travelled >= self.p.optimize_every_m;
        let lag = if self.loops.optimise_now {
            self.p.loop_closure_batch_nodes.max(1)
        } else if due && news > 0 {
            LAG_NODES
        } else {
            return;
        };
        self.take_optimisation();
        self.start_optimisation(lag, false);
    }

    /// Takes the result under way if its node has come.
    pub(super) fn take_optimisation_if_due(&mut self) {
        if self.pending.as_ref().is_some_and(|p| self.nodes.len() >= p.take_at) {
            self.take_optimisation();
        }
    }

    /// Optimises the whole graph once more, to the default tolerance, and takes the result.
    pub(super) fn optimise_last(&mut self) {
        self.take_optimisation();
        self.start_optimisation(0, true);
        self.take_optimisation();
    }

    /// Copies the graph and optimises the copy beside the next `lag` nodes (on one thread,
    /// or with no lag, where its result is taken).
    fn start_optimisation(&mut self, lag: usize, last: bool) {
        let job = self.job(last);
        let loss = *job.losses.last().expect("one pass at least");
        let work = if lag > 0 && crate::parallel::threads() > 1 {
            let spawned = std::thread::Builder::new().name("fusemap-optimiser".into()).spawn(move || {
                lowest_priority();
                job.run()
            });
            Work::Running(spawned.expect("a thread for the optimiser"))
        } else {
            Work::Later(Box::new(job))
        };
        self.report.optimisations_deferred += u64::from(lag > 0);
        self.pending = Some(Pending {
            work,
            take_at: self.nodes.len() + lag,
            last_node: self.nodes.len().saturating_sub(1),
            graph_nodes: self.graph.nodes().len(),
            global_from_local: self.global_from_local,
            loss,
        });
        self.restart_counters();
    }

    /// The optimisation of the graph as it stands.
    fn job(&mut self, last: bool) -> Job {
        // Fixes spread widely enough hold the graph in their frame: the first node is
        // then one more node, not the anchor.
        if let Some(first) = self.nodes.first().filter(|_| self.fixes.anchor_the_graph()) {
            self.graph.set_fixed(first.graph, false);
        }
        // The optimisations during the run only steer the next searches: they stop at a
        // coarser relative cost change; the last one runs to the default tolerance.
        let opts = OptimizeOptions {
            function_tolerance: if last { OptimizeOptions::default().function_tolerance } else { STEERING_TOLERANCE },
            ..OptimizeOptions::default()
        };
        // Huber first, from wherever the graph stands: closures pull with a bounded force,
        // so the right ones (the many that agree) bring the graph to them. Then dynamic
        // covariance scaling from there: a closure the rest of the graph disagrees with
        // stops pulling at all (Agarwal et al. 2013). Odometry and matches stay least
        // squares: they are the inliers everything is judged by. The DCS pass runs after a
        // large correction and at the end, not at every periodic optimisation: it costs as
        // much again (on the Intel bag half of all the optimisation time), and what a
        // wrong closure bends in between, with Huber's bounded pull, it takes back.
        let huber = Loss::Huber(self.p.loop_closure_huber);
        let dcs = (last || self.loops.optimise_now).then_some(Loss::Dcs(self.p.loop_closure_dcs));
        Job { graph: self.graph.take_copy(), losses: std::iter::once(huber).chain(dcs).collect(), opts }
    }

    fn restart_counters(&mut self) {
        self.since_optimisation = 0;
        self.optimised_at_m = self.nodes.last().map_or(0.0, |n| n.path_m);
        self.loops.since_optimisation = 0;
        self.loops.optimise_now = false;
        self.fixes.since_optimisation = 0;
    }

    /// Takes the optimisation under way, if any: its poses for the nodes it had, the
    /// correction for those added since.
    pub(super) fn take_optimisation(&mut self) {
        let Some(p) = self.pending.take() else { return };
        let t0 = Instant::now();
        let out = match p.work {
            Work::Later(job) => job.run(),
            Work::Running(handle) => handle.join().unwrap_or_else(|e| std::panic::resume_unwind(e)),
        };
        for r in out.results {
            match r {
                Ok(r) => {
                    self.report.optimisations += 1;
                    self.report.last_optimisation = Some(r);
                }
                Err(e) => self.report.optimisation_failures.push(e.to_string()),
            }
        }
        self.graph.adopt(out.graph);
        self.graph.set_loss_of(EdgeKind::LoopClosure, p.loss).expect("valid loss");
        if let Some(n) = self.nodes.get(p.last_node) {
            let now = self.graph.nodes()[n.graph].compose(n.local.inverse());
            let correction = now.compose(p.global_from_local.inverse());
            for i in p.graph_nodes..self.graph.nodes().len() {
                self.graph.set_node(i, correction.compose(self.graph.nodes()[i]));
            }
            self.global_from_local = now;
        }
        self.reindex();
        self.update_drift();
        self.report.optimisation_s += out.seconds;
        self.report.optimisation_wait_s += t0.elapsed().as_secs_f64();
    }
}
