//! The search of `optimize` and the paper report ([`search`]), with the global search
//! ([`super::global`], `optimize --hops N`, [`VerifyPolicy::global`]) over the local optima of
//! the problems of Sect. 4 (eq. 60–66):
//!
//! 1. Sampling: the chains of a [`Strategy`] (for the periodic problems
//!    [`super::strategy::GLOBAL_STARTS`] seeded starts by default, with the global search;
//!    for `periodic-qc` each a continuation
//!    in the stick phase's lower bound, first ≥ [`STICK_CONTINUATION`], then relaxed to the
//!    problem's bound; with the global search on the COT problems every odd start a
//!    continuation in the period bound, `hold_the_period`), one point per distinct optimum
//!    (objectives within [`CLUSTER_RTOL`], [`representatives`]); with the global search on a
//!    coarse mesh ([`CoarseSampling`]), otherwise on the problem's mesh, each re-integrated
//!    ([`verify`]).
//! 2. Global search only: exploration on that mesh ([`Search::explore`]): the reshaping
//!    moves ([`super::reshape`]: the elbow flip, the mirror, phase-duration bounds then
//!    released) from the best distinct shapes not moved before (`same_shape`), monotonic
//!    basin hopping from the best distinct optima and polishing of the winner
//!    ([`DEFAULT_HOPS`]).
//! 3. Global search only: promotion ([`Search::promote_and_refine`]), the best optima that
//!    differ in shape re-solved on the problem's mesh from their coarse trajectories (twice:
//!    from a warm start's barrier parameter and from a close one, [`PROMOTE_MU_INIT`], the
//!    lower kept), each re-integrated (and, for a plan for the plant, executed in closed loop:
//!    [`VerifyPolicy::execution`]); while the next shape's coarse objective is below the best
//!    re-solved one, the next shapes too (the bound, [`PROMOTE_BOUND_ROUNDS`]); then refined
//!    as in step 4; once one verifies (for a plan, executed and robust), the next shapes
//!    while their coarse objective is below the best verified one (the bound against what
//!    verified), refined below it; while none verifies, the next shapes down the ranking
//!    ([`PROMOTE_ROUNDS`]), then the fallback ([`Search::fall_back_to_the_starts`]).
//! 4. hp refinement of the unverified optima that beat the best verified one (lowest objective
//!    first, one after the other until no candidate below the best verified objective is
//!    left, each only up to its first refinement not below the best verified before it,
//!    `refine_in_order`, which refines as many side by side as there are threads and
//!    returns what the one-after-the-other order gives), driven by their element-wise
//!    re-integration defects, until these are at most [`super::verify::VERIFIED_DEFECT`]
//!    ([`VerifyPolicy`], [`Search::refine_candidates`]); a candidate whose defects verify but
//!    whose path leaves the friction cone or penetrates the ball only while the refinements
//!    bring it closer to its allowance (`path_stalled`).
//! 5. Global search only: the winner's neighbourhood ([`Search::polish_the_winner`]): from the
//!    best verified (and robust) candidate, the reshaping moves and a few basin hops solved on
//!    the mesh it verified on ([`POLISH_HOPS`]); the results below it are verified and refined
//!    as in step 4 and join the candidates; while a round gives a new winner that is
//!    markedly lower, the next round starts from it ([`NEIGHBOURHOOD_ROUNDS`],
//!    [`NEIGHBOURHOOD_GAIN`]).
//! 6. The choice [`select`]: verified and robust first (a plan for the plant whose perturbed
//!    plants miss the robustness target comes after those that meet it, before the
//!    unverified), then the lowest objective, then the lowest index.
//!
//! Results are collected in index order and every choice depends on values only, so the
//! result is bitwise the same with any number of threads; a [`Shard`] runs every m-th start
//! and writes its distinct sampled optima, and `optimize merge` runs steps 2–6 on their union,
//! which is the unsharded run.

use std::sync::Mutex;
use std::time::Instant;

use bf_optim::ipm::{IterationInfo, Nlp};
use bf_optim::ocp::Scheme;
use bf_problem::solution::records::ExecutionCheck;
use bf_problem::{BuiltProblem, OcpSolution, Problem, ProblemSettings};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::build;
use super::error::PipelineError;
use super::global::{self, HopSettings, Landscape};
use super::refine::{self, RefineCriterion, RefineSettings};
use super::reshape::{MOVES, flip_elbow, mirror_first_joint, with_duration_bounds};
use super::solve::{INTERPOLATED_MU_INIT_MAX, better_solve, solve_recentred, solve_with_mu_max};
use super::strategy::{
    Chain, Progress, Shard, StageRecord, Strategy, StrategyReport, effective, failed_record,
    prepare_chains, record, run_chain,
};
use super::verify::{
    VERIFIED_DEFECT, execution_failure, is_robust, is_verified, passes, path_excess,
    robustness_miss, smoothing_failure, verify,
};

/// Relative objective difference within which two end points are one local optimum.
pub const CLUSTER_RTOL: f64 = 1e-6;

/// Relative difference of objectives and phase durations within which two end points have
/// the same shape (`same_shape`).
pub const SHAPE_RTOL: f64 = 0.02;

/// First stick-phase lower bound (s) of the stick continuation
/// ([`VerifyPolicy::stick_continuation`]).
pub const STICK_CONTINUATION: f64 = 0.1;

/// How a search verifies its candidates ([`search`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerifyPolicy {
    /// DOPRI5 relative tolerance of the re-integration ([`verify`]); 0 skips verification
    /// (and with it the refinement).
    pub rtol: f64,
    /// Tolerance on the element-wise re-integration defects (state units) of the first hp
    /// refinement of an unverified optimum ([`RefineCriterion::Reintegration`]); each further
    /// attempt divides it by 10.
    pub refine_tol: f64,
    /// hp refinements (each up to `refine_rounds` rounds) of one unverified optimum at most.
    pub refine_attempts: usize,
    /// Rounds of one refinement.
    pub refine_rounds: usize,
    /// Collocation points per phase at most ([`VERIFY_MAX_POINTS`] by default).
    pub max_points: usize,
    /// Distinct unverified optima (better than the best verified one) refined at most: they are
    /// refined one after the other, lowest objective first, until none below the best
    /// verified objective is left, so a spurious
    /// optimum that cannot be verified (e.g. a collapsed phase) does not hide the next one.
    /// Default 6: the budget costs refinements only when the better candidates fail, and with
    /// 3 the `periodic-cot` search of seed 8 ended unverified (its fifth candidate verifies;
    /// BENCHMARKS.md, 2026-11-26).
    pub clusters: usize,
    /// Continuation in the stick phase's lower bound (`periodic-qc` only): every chain first
    /// runs with the stick phase at least this long (s), then one warm-started stage relaxes
    /// the bound to the problem's ([`ProblemSettings::min_stick`]). With the short default
    /// bound most cold starts end in "taps" on it; from a stick phase of real duration the
    /// relaxation reaches better optima with an interior stick duration. `None`: no
    /// continuation.
    pub stick_continuation: Option<f64>,
    /// The global search's basin hopping and polishing after a multi-start
    /// ([`Search::explore`]; its seed is the multi-start's); `None` (the default): the best of
    /// the starts. [`VerifyPolicy::global`] sets it with the coarse sampling.
    pub hops: Option<HopSettings>,
    /// The multi-start's sampling on a coarse mesh, of which only the best distinct optima are
    /// re-solved on the problem's mesh ([`CoarseSampling`]); `None`: every start on the
    /// problem's mesh.
    pub coarse: Option<CoarseSampling>,
    /// The closed-loop execution of every candidate whose re-integration verifies
    /// ([`Execution`]; `optimize` sets it for the plans for the plant, decision record 0048);
    /// `None`: the re-integration alone decides.
    pub execution: Option<Execution>,
}

/// A closed-loop run of a candidate whose re-integration verified, supplied by the layer that
/// owns the controller (`paper::closed_loop`): its record joins the candidate's verification
/// ([`Verification::execution`](bf_problem::solution::records::Verification::execution)): a
/// plan that the nominal plant does not execute is not verified
/// ([`super::verify::execution_failure`]), one that misses the robustness target on a
/// perturbed plant is verified but ranked below every plan that meets it
/// ([`super::verify::robustness_miss`]), so a search chooses among the executed plans and
/// prefers robust ones. The function gets the candidate and its problem's scene (`None`: the
/// problem's compiled scene), since a candidate records no scene text until `optimize`
/// writes it. `None` from the function: no run was possible, and the re-integration decides
/// alone.
#[derive(Clone, Copy)]
pub struct Execution(pub fn(&OcpSolution, Option<&bf_codegen::Scene>) -> Option<ExecutionCheck>);

impl std::fmt::Debug for Execution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Execution(..)")
    }
}

impl PartialEq for Execution {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::fn_addr_eq(self.0, other.0)
    }
}

/// The sampling phase of the global search on a coarse mesh ([`VerifyPolicy::coarse`]): every
/// start of the multi-start is solved on `elements` Radau elements of `points` points per
/// phase in all, the basin hopping runs there ([`Search::explore`]), and only the `promote`
/// best optima that differ in shape are re-solved on the problem's own mesh, warm-started from
/// their coarse trajectories (interpolated; [`Search::promote_and_refine`]). A coarse start
/// costs about a fifth of one on the default mesh and ends at the same objective to about
/// 1e-4, and the good basins of `periodic-qc` are each reached by about one start in 250
/// (BENCHMARKS.md, "Global search on a coarse mesh"), so many cheap starts and hops find more
/// than a few expensive ones. Applies to multi-starts on Radau meshes of more points than the
/// coarse one and no explicit element layout.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoarseSampling {
    /// Radau elements per phase of the coarse mesh.
    pub elements: usize,
    /// Collocation points per phase of the coarse mesh.
    pub points: usize,
    /// Coarse optima that differ in shape (lowest objectives first) re-solved on the problem's
    /// mesh.
    pub promote: usize,
}

/// Promotion rounds at most ([`Search::promote_and_refine`]): while no re-solved candidate
/// verifies, the next [`CoarseSampling::promote`] shapes are re-solved, up to this many rounds
/// (24 shapes by default).
pub const PROMOTE_ROUNDS: usize = 3;

/// Promotion rounds at most in all ([`Search::promote_and_refine`]), those the bound asks for
/// included: while the next shape's coarse objective is below the best objective re-solved on
/// the problem's mesh, or, once a candidate has verified, below the best verified objective,
/// the next [`CoarseSampling::promote`] shapes are re-solved too.
pub const PROMOTE_BOUND_ROUNDS: usize = 8;

/// The default coarse sampling: 3 Radau elements of 4 points per phase (the default mesh has
/// 3 of 10), the 8 best optima that differ in shape re-solved on the problem's mesh.
pub const DEFAULT_COARSE: CoarseSampling = CoarseSampling {
    elements: 3,
    points: 12,
    promote: 8,
};

/// The basin hopping around the verified winner on its own mesh ([`Search::polish_the_winner`]):
/// every reshaping move from the winner, then four hops (two rounds of two, of the default
/// and of the wide size alternating as in [`DEFAULT_HOPS`]), then one polishing round (a
/// re-solve and a hop of e^±0.05). A solve on a refined mesh costs about ten coarse ones, so
/// the hops' budget is a sixteenth of [`DEFAULT_HOPS`]'s, all of it spent (the patience is
/// the budget).
pub const POLISH_HOPS: HopSettings = HopSettings {
    batch: 2,
    width: 1,
    budget: 4,
    confirmations: 1,
    patience: 4,
    scale: 0.3,
    wide: WIDE_HOPS,
    polish_scale: 0.05,
    polish_rounds: 1,
    seed: 0,
    reshape_width: 1,
    reshape_rounds: 1,
};

/// Rounds of the winner's neighbourhood at most ([`Search::polish_the_winner`]): while a
/// round's solves give a new verified winner at least [`NEIGHBOURHOOD_GAIN`] lower, the next
/// round starts from it (decision record 0057).
pub const NEIGHBOURHOOD_ROUNDS: usize = 2;

/// Relative objective gain of a round of the winner's neighbourhood below which no further
/// round runs ([`Search::polish_the_winner`]): a round that lowers the objective by less has
/// moved to a neighbour of the same family, whose neighbourhood the round just searched. On
/// `periodic-cot-human` every seed's first round gains 0.027 % and a second round found
/// nothing on any seed for 15–20 s each; on `periodic-cot` the first round of seed 7 gains
/// 0.21 % and its second round 3.3 % (decision record 0057).
pub const NEIGHBOURHOOD_GAIN: f64 = 1e-3;

/// Stage label prefix of the solves of [`Search::polish_the_winner`] (its later rounds: the
/// label and the round's number from 2).
pub const POLISH_LABEL: &str = "winner's neighbourhood";

/// Stage label of the re-solve of a coarse optimum on the problem's mesh ([`CoarseSampling`]).
pub const PROMOTE_LABEL: &str = "full mesh";

/// Stage label of the promotion's second solve, from the close barrier start
/// [`PROMOTE_MU_INIT`].
pub const PROMOTE_CLOSE_LABEL: &str = "full mesh, close start";

/// Whether a stage record is one of a promotion's solves ([`PROMOTE_LABEL`],
/// [`PROMOTE_CLOSE_LABEL`]).
pub fn is_promotion(stage: &str) -> bool {
    stage == PROMOTE_LABEL || stage == PROMOTE_CLOSE_LABEL
}

/// Largest initial barrier parameter μ₀ of a promotion's second solve, the close start
/// ([`super::solve::solve_with_mu_max`]); the first starts from a warm start's
/// [`super::solve::INTERPOLATED_MU_INIT_MAX`] = 1e-4, and the lower successful solution is
/// kept. From 1e-4 the re-centring of the interpolated start can carry the iterates out of a
/// narrow basin, as in a refinement round ([`super::refine::CLOSE_MU_FACTOR`]): of the 56
/// shapes that `periodic-cot` seed 1 promotes, 1 re-solved below 8e-4 from 1e-4 and 9 from
/// 1e-6; 21 ended more than three times above their coarse objective from 1e-4 (14 of them
/// with the period on its 10 s bound), 11 from 1e-6 (8); from 1e-6 they took half the
/// iterations (3 572 against 6 947). Neither start is the better one everywhere (on seed 4
/// the lowest plan comes from 1e-4 only), hence both (decision record 0059).
pub const PROMOTE_MU_INIT: f64 = 1e-6;

/// The reshaping and basin hopping of the global search ([`VerifyPolicy::global`], `optimize
/// --hops N` with the budget N), on the coarse mesh of the sampling: 4 rounds of every
/// reshaping move from the 4 best distinct shapes not moved before ([`super::reshape::MOVES`];
/// 6 rounds took the default `periodic-qc` search to 29–33 s, decision record 0047), then
/// rounds of four hops (durations scaled by up to e^±0.3 each, and the period by up to
/// e^±0.3; every other round e^±0.8, [`WIDE_HOPS`]), at most 64, stopping once the best
/// optimum was reached three times and 24 hops in a row brought nothing better; then up to two
/// polishing rounds (a re-solve and three hops of e^±0.05).
/// A patience of 8 stopped `periodic-qc` seed 1 at J 0.1176, one hop short of the 0.0769
/// basin next to it (BENCHMARKS.md, "Global search on a coarse mesh"); a coarse hop costs about
/// 0.1 s.
pub const DEFAULT_HOPS: HopSettings = HopSettings {
    batch: 4,
    width: 4,
    budget: 64,
    confirmations: 3,
    patience: 24,
    scale: 0.3,
    wide: WIDE_HOPS,
    polish_scale: 0.05,
    polish_rounds: 2,
    seed: 0,
    reshape_width: 4,
    reshape_rounds: 4,
};

/// Size of the wide hops of every other round relative to the small ones
/// ([`HopSettings::wide`]): e^±0.8 against e^±0.3 on the durations, ±0.48 rad against ±0.18 rad
/// on the joints. Hops of e^±0.3 alone fell back into their origin's basin where the better
/// basin's free flight is split the other way: the default plan of `periodic-qc` reached its
/// best basin on 4 of seeds 0–9 with them, on 9 with the alternating rounds (decision record
/// 0043).
pub const WIDE_HOPS: f64 = 8.0 / 3.0;

/// Initial barrier parameter of a hop's re-solve ([`solve_recentred`]): large enough for the
/// iterates to leave the perturbed optimum's active set, small enough to stay in its region.
pub const HOP_MU: f64 = 1e-2;

/// Joint-angle offset of a hop of scale 1 (rad): a hop stays near its origin's basin, while
/// the starts sample each joint's whole revolution (`strategy::start_intervals`).
pub const HOP_JOINT: f64 = 0.6;

/// Iteration limit of a hop's re-solve: a solve from a perturbed optimum converges in tens
/// to a few hundred iterations or wanders.
pub const HOP_MAX_ITER: usize = 400;

/// hp refinements of one unverified optimum by default ([`VerifyPolicy::refine_attempts`],
/// `optimize --verify-refinements`): to element defects of 1e-4, 1e-5, …, 1e-8. A chain of
/// refinements does not converge monotonically (each re-solve on the refined mesh may move
/// within or out of the basin): the best candidate of seed 8 of the `periodic-cot` search
/// verifies at its fourth (defects 6.2e-2, 3.1e-1, 1.5e-2, 9.3e-8), where three sent the
/// search on to its fifth-best candidate, at a higher objective and more cost
/// (BENCHMARKS.md, "Five refinements per candidate (2026-11-26)"). Costs nothing where the
/// third verifies.
pub const VERIFY_REFINEMENTS: usize = 5;

/// Collocation points per phase that the refinements of an unverified optimum may reach by
/// default ([`VerifyPolicy::max_points`]): the bound on what one refinement chain may cost.
/// The `periodic-cot` optima have long free phases whose element-wise defects need many short
/// elements. When the limit was set, three of the default searches over seeds 0–19 stopped the
/// refinement of their best candidate at 400 points and reported a candidate 3–4× worse; with
/// 800 those candidates verified (BENCHMARKS.md, "A point limit of 800 (2026-11-26)"). Today's
/// winners verify on far fewer points than either limit (BENCHMARKS.md, "The proximal term in
/// the default searches; refinement sizes"); the larger one costs only where a chain needs it.
pub const VERIFY_MAX_POINTS: usize = 800;

impl VerifyPolicy {
    /// The policy of the global search (the default of `optimize` and the paper report for
    /// multi-starts; `--hops N` sets the budget, `--hops 0` leaves it out): `self` with the
    /// reshaping and basin hopping `hops` and the coarse sampling [`DEFAULT_COARSE`]. With it
    /// `periodic-qc` reaches J ≤ 0.08761 on every seed 0–9 (decision record 0029).
    pub fn global(self, hops: HopSettings) -> Self {
        VerifyPolicy {
            hops: Some(hops),
            coarse: Some(DEFAULT_COARSE),
            ..self
        }
    }
}

impl Default for VerifyPolicy {
    fn default() -> Self {
        VerifyPolicy {
            rtol: 1e-10,
            refine_tol: VERIFIED_DEFECT,
            refine_attempts: VERIFY_REFINEMENTS,
            refine_rounds: 4,
            max_points: VERIFY_MAX_POINTS,
            clusters: 6,
            stick_continuation: Some(STICK_CONTINUATION),
            hops: None,
            coarse: None,
            execution: None,
        }
    }
}

/// One end point of a search: the final solution of chain/start `index`.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Global chain/start index.
    pub index: usize,
    /// Its transcribed problem (`None` for a candidate read from a file).
    pub problem: Option<BuiltProblem>,
    /// The solution, with its [`OcpSolution::verification`] when verified.
    pub solution: OcpSolution,
}

/// The result of [`search`]: one candidate per distinct local optimum (verified, refined
/// where needed) and the record of every solve.
#[derive(Debug, Clone)]
pub struct Search {
    /// The strategy that ran.
    pub strategy: Strategy,
    /// The shard that ran.
    pub shard: Shard,
    /// One candidate per distinct optimum (its lowest-index start, or hop), in index order.
    pub candidates: Vec<Candidate>,
    /// The distinct optima of the sampling (re-solved on the problem's mesh, not refined), in
    /// index order: what a shard hands to `optimize merge`.
    pub sampled: Vec<Candidate>,
    /// Every stage of every chain/start, in index order.
    pub records: Vec<StageRecord>,
    /// The hp refinements of unverified optima (one record per refinement, its chain the
    /// start index), in index order; their iterations count in the solution's total, not in
    /// [`StrategyReport::iterations`].
    pub refinements: Vec<StageRecord>,
    /// Wall time (s).
    pub seconds: f64,
    /// Distinct sampled optima and hops that ended at the best optimum of the global search
    /// ([`Search::explore`]; `None` before it ran), or, where the choice comes from the
    /// winner's neighbourhood, that step's solves that ended in its shape
    /// ([`Search::polish_the_winner`]).
    pub basin_hits: Option<usize>,
}

/// Rank class of a solution: 0 verified and, where its plan was run on the perturbed
/// plants, robust ([`is_robust`]); 1 verified, but a perturbed plant missed the robustness
/// target ([`super::verify::robustness_miss`]); 2 successful but not verified; 3 failed.
fn class(sol: &OcpSolution) -> u8 {
    if !sol.status.is_success() || !sol.objective.is_finite() {
        FAILED
    } else if !is_verified(sol) {
        UNVERIFIED
    } else if is_robust(sol) {
        SETTLED
    } else {
        FLAGGED
    }
}

/// Rank class of a verified solution that meets every check, the robustness target included:
/// the search's goal, whose absence sends it on to further shapes and to the fallback.
const SETTLED: u8 = 0;

/// Rank class of a verified solution that missed the robustness target on a perturbed plant.
const FLAGGED: u8 = 1;

/// Rank class of a successful, unverified solution: the one that refinement may verify.
const UNVERIFIED: u8 = 2;

/// Rank class of a failed solve or a non-finite objective.
const FAILED: u8 = 3;

/// Whether the solve succeeded with a finite objective: the exploration ranks the problem's
/// own landscape on its mesh and leaves the verification to the refinement that follows it
/// ([`Search::refine_candidates`]).
fn solved(sol: &OcpSolution) -> bool {
    class(sol) <= UNVERIFIED
}

/// The order in which candidates are promoted and refined: lowest objective first, ties by
/// the lower index (values only, so shards merged order as the unsharded run does).
fn lowest_first(a: &Candidate, b: &Candidate) -> std::cmp::Ordering {
    a.solution
        .objective
        .total_cmp(&b.solution.objective)
        .then(a.index.cmp(&b.index))
}

/// Whether two end points are the same local optimum: objectives within [`CLUSTER_RTOL`]
/// and periods within 0.1 %.
pub(crate) fn same_optimum(a: &OcpSolution, b: &OcpSolution) -> bool {
    (a.objective - b.objective).abs() <= CLUSTER_RTOL * a.objective.abs().max(b.objective.abs())
        && (a.period - b.period).abs() <= 1e-3 * a.period.abs().max(b.period.abs())
}

/// The candidate a search returns (its position in `cands`, given as (start index,
/// solution)): the best class (verified and robust, verified, successful, failed: `class`),
/// in it the lowest objective, and among the end points within [`CLUSTER_RTOL`] of that
/// objective (one optimum, reached from several starts) the lowest start index. The rule
/// depends on the set only, not on its order, so shards merged give the unsharded choice.
pub fn select(cands: &[(usize, &OcpSolution)]) -> Option<usize> {
    let best_class = cands.iter().map(|(_, s)| class(s)).min()?;
    let in_class = || {
        cands
            .iter()
            .enumerate()
            .filter(|(_, (_, s))| class(s) == best_class)
    };
    let jmin = in_class()
        .map(|(_, (_, s))| s.objective)
        .filter(|j| j.is_finite())
        .fold(f64::INFINITY, f64::min);
    in_class()
        .filter(|(_, (_, s))| could_be_chosen(s.objective, jmin))
        .min_by_key(|(_, (k, _))| *k)
        .map(|(i, _)| i)
}

/// One candidate per distinct optimum: candidates sorted by (class, objective, index) are
/// grouped greedily (a group takes every following end point of its class within
/// `same_optimum` of its first); each group is represented by its lowest start index.
pub fn representatives(cands: Vec<Candidate>) -> Vec<Candidate> {
    let mut order: Vec<usize> = (0..cands.len()).collect();
    let key = |c: &Candidate| {
        let j = c.solution.objective;
        (
            class(&c.solution),
            if j.is_nan() { f64::INFINITY } else { j },
        )
    };
    order.sort_by(|&a, &b| {
        let (ka, kb) = (key(&cands[a]), key(&cands[b]));
        ka.0.cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then(cands[a].index.cmp(&cands[b].index))
    });
    let mut keep = vec![false; cands.len()];
    let mut i = 0;
    while i < order.len() {
        let first = &cands[order[i]];
        let mut j = i + 1;
        while j < order.len() {
            let c = &cands[order[j]];
            if class(&c.solution) != class(&first.solution)
                || !same_optimum(&first.solution, &c.solution)
            {
                break;
            }
            j += 1;
        }
        let rep = order[i..j]
            .iter()
            .copied()
            .min_by_key(|&o| cands[o].index)
            .unwrap_or(order[i]);
        keep[rep] = true;
        i = j;
    }
    cands
        .into_iter()
        .zip(keep)
        .filter_map(|(c, k)| k.then_some(c))
        .collect()
}

/// Re-integrates the candidate's solution ([`verify`]) at the policy's tolerance and stores
/// the result in it; a candidate that verifies is then executed in closed loop where the
/// policy asks for it ([`VerifyPolicy::execution`]), and its verdict includes the run. The
/// run is made only where the candidate could still be chosen over the verified and robust
/// objective `bound` ([`could_be_chosen`]; infinite: none yet): one above it is left
/// unexecuted, and so unverified ([`leave_unexecuted`]). The closed loop simulates the plan
/// for periods of the hybrid model on the nominal and every perturbed plant, seconds of CPU
/// where the re-integration takes a fraction of one, and the search's rules stop a
/// candidate above a verified plan whatever that run shows (decision record 0067).
fn attach_verification(c: &mut Candidate, policy: &VerifyPolicy, bound: f64) {
    let Some(p) = &c.problem else { return };
    let mut v = verify(p, &c.solution, policy.rtol).ok();
    if let (Some(v), Some(Execution(run))) = (v.as_mut(), policy.execution)
        && v.verified
    {
        if could_be_chosen(c.solution.objective, bound) {
            // The candidate records no scene text yet (`optimize` adds it to the file): the
            // problem's own scene (with `--param` values) is the one the plan was made on.
            v.execution = run(&c.solution, p.settings.scene.as_ref());
            v.verified = passes(v);
        } else {
            unexecuted(v);
        }
    }
    c.solution.verification = v;
}

/// The candidates' verifications made anew as the sampling makes them (`attach_verification`
/// before any plan is verified), in place of the ones they carry: a candidate read from a
/// file states a verdict that `optimize merge` does not take on trust. A candidate without
/// one (a coarse sampling's) stays without. In parallel, each candidate on its own.
pub fn verify_again(cands: &mut [Candidate], policy: &VerifyPolicy) {
    cands.par_iter_mut().for_each(|c| {
        if c.solution.verification.take().is_some() && policy.rtol > 0.0 {
            attach_verification(c, policy, f64::INFINITY);
        }
    });
}

/// Why the search left a plan unexecuted
/// ([`bf_problem::solution::records::Verification::not_executed`]).
pub const ABOVE_A_VERIFIED_PLAN: &str =
    "its objective lies above a verified and robust plan's, so it could not have been chosen";

/// Whether a plan of objective `j` could still be chosen over one of objective `bound` in
/// its rank class: [`select`]'s rule (objectives within [`CLUSTER_RTOL`] of the lowest are
/// one optimum, of which the lowest start index is chosen); always where `bound` is +∞,
/// never where it is −∞ (a refinement whose result the search drops, `refine_in_order`).
fn could_be_chosen(j: f64, bound: f64) -> bool {
    if bound.is_infinite() {
        return bound > 0.0;
    }
    j <= bound + CLUSTER_RTOL * bound.abs()
}

/// The verification of `c` as [`attach_verification`] would have left it with a bound that
/// rules the candidate out: a closed-loop run it made is dropped and the candidate is
/// unverified. A refinement chain run beside earlier ones executes a candidate that the
/// sequential order would not have (the earlier chains' results were not in yet,
/// `refine_in_order`); this undoes that run, so the result is the sequential one.
fn leave_unexecuted(c: &mut Candidate) {
    if let Some(v) = c.solution.verification.as_mut()
        && v.execution.is_some()
    {
        unexecuted(v);
    }
}

/// `v` without a closed-loop run, as the search leaves a plan that could not be chosen
/// ([`ABOVE_A_VERIFIED_PLAN`]): unverified.
fn unexecuted(v: &mut bf_problem::solution::records::Verification) {
    v.execution = None;
    v.not_executed = Some(ABOVE_A_VERIFIED_PLAN.to_string());
    v.verified = passes(v);
}

/// Whether `sol` was executed in closed loop and failed ([`super::verify::execution_failure`]):
/// a refinement changes the collocation's accuracy, not what the plan does, so it is not
/// refined.
fn execution_failed(sol: &OcpSolution) -> bool {
    sol.verification
        .as_ref()
        .is_some_and(|v| execution_failure(v).is_some())
}

/// hp-refines an unverified candidate (Radau only) until it is verified or the policy's
/// attempts are spent: attempt a refines from the previous attempt's mesh, each round
/// splitting or raising the degree of the elements whose element-wise re-integration defect
/// exceeds `refine_tol`·10⁻ᵃ, and re-integrates. An attempt that could not refine its mesh
/// at all (point limit, non-finite defects) ends the attempts, and so does one whose defects
/// verify and whose path check stays stuck beyond its allowance ([`path_stalled`]), and so
/// does one whose defects fail after a point of the chain had them verified (the solve left
/// the optimum being verified, [`LeftOptimum`]), and so does `earlier` turning `None`
/// (checked before each attempt and at each interior-point iteration of its solves: another
/// candidate's result has made this one's moot, `refine_in_order`), and so does a refinement
/// whose objective is not below `ceiling` or below the lowest objective verified by the
/// candidates refined before this one (`earlier`: a refined plan above a verified one no
/// longer competes with it; `ceiling` is infinite but in [`Search::polish_the_winner`], where
/// it is the winner's).
/// Returns every successful refinement with the records up to it ([`RefinedChain`]).
fn refine_until_verified(
    problem: Problem,
    settings: &ProblemSettings,
    start: Candidate,
    policy: &VerifyPolicy,
    ceiling: f64,
    earlier: &dyn Fn() -> Option<f64>,
) -> RefinedChain {
    let mut records = Vec::new();
    let mut steps: Vec<Step> = Vec::new();
    let mut tol = policy.refine_tol;
    let start_check = start.solution.verification.as_ref();
    let mut before = start_check.and_then(path_only_excess);
    let mut defects = DefectProgress::new(start_check.map(|v| v.max_defect));
    let mut leaving = LeftOptimum::default();
    leaving.step(start_check.is_some_and(|v| v.passes(VERIFIED_DEFECT)));
    // The lowest objective verified before this chain, or the ceiling; −∞ once the chain's
    // result is no longer wanted. Read anew each time: earlier chains finish meanwhile.
    let bound = || earlier().map_or(f64::NEG_INFINITY, |b| b.min(ceiling));
    for _ in 0..policy.refine_attempts {
        let cur = steps.last().map_or(&start, |s| &s.point);
        if is_verified(&cur.solution) || execution_failed(&cur.solution) || earlier().is_none() {
            break;
        }
        let Some(p) = cur.problem.as_ref() else { break };
        let Ok(mesh) = refine::current_mesh(p) else {
            break;
        };
        let t0 = Instant::now();
        let s = ProblemSettings {
            mesh: Some(mesh),
            ..settings.clone()
        };
        let opts = RefineSettings {
            tol,
            criterion: RefineCriterion::Reintegration { rtol: policy.rtol },
            max_rounds: policy.refine_rounds,
            max_points: policy.max_points,
            ceiling,
            ..RefineSettings::default()
        };
        // One significant digit: the tolerance is divided by 10 per attempt, which leaves
        // rounding digits (1.0000000000000002e-6) that say nothing.
        let label = format!("refine start {} to {tol:.0e}", cur.index);
        let iters0 = cur.solution.iterations;
        // A chain that `earlier` rules out is dropped whatever it returns (`refine_in_order`),
        // so its solve stops at its next iteration rather than at the end of its round: a
        // chain run beside an earlier one is ruled out when that one verifies below it.
        let mut wanted = |_: &IterationInfo| earlier().is_some();
        let refined = refine::refine_solution(
            problem,
            &s,
            cur.solution.clone(),
            &opts,
            Some(&mut wanted),
            None,
        );
        if earlier().is_none() {
            break;
        }
        match refined {
            Ok((b, sol)) => {
                let mut next = Candidate {
                    index: cur.index,
                    problem: Some(b),
                    solution: sol,
                };
                // Executed only while it could beat the best verified before it.
                attach_verification(&mut next, policy, bound());
                let v = next.solution.verification.as_ref();
                let defect = v.map_or(f64::NAN, |v| v.max_defect);
                let mut r = record(
                    cur.index,
                    refinement_label(&label, &next.solution),
                    &next.solution,
                    t0,
                );
                r.iterations = next.solution.iterations.saturating_sub(iters0);
                // The rounds' own link to the line that sums them, which the report follows
                // (and which a hop's result on this mesh carries as its origin's).
                if let Some(rep) = next.solution.refinement.as_mut() {
                    rep.stage = Some(r.stage.clone());
                }
                records.push(r);
                if !next.solution.status.is_success() {
                    break;
                }
                // A refinement that stopped after solving its starting mesh only, without
                // meeting its tolerance, was stopped by the point limit or by non-finite
                // defects: a tighter tolerance marks a superset of the elements and stops on the
                // same limit, so a further attempt would only solve the same mesh again. (One
                // whose refined mesh failed to solve also returns its starting mesh, but a
                // tighter tolerance refines differently and may succeed: that one goes on.)
                let stuck = next
                    .solution
                    .refinement
                    .as_ref()
                    .is_some_and(|r| !r.converged && r.history.len() == 1);
                // A candidate whose defects verify and whose only failure is a path check
                // (the `periodic-qc` 0.0769202 tap leaves the friction cone between its nodes)
                // is refined on only while refinements bring that check closer to its
                // allowance: the refined meshes of the tap kept min σ 24× outside the cone
                // through four refinements (BENCHMARKS.md, "Mirror move and refinement
                // progress").
                let now = v.and_then(path_only_excess);
                // A smoothing ε that misplaces the ball (decision record 0089) is not a mesh's
                // error: no refinement brings it closer.
                let coarse_smoothing = v.is_some_and(|v| {
                    v.passes(VERIFIED_DEFECT) && now.is_none() && smoothing_failure(v).is_some()
                });
                let no_progress = path_stalled(before, now) || coarse_smoothing;
                before = now;
                // A candidate whose defect does not fall is not brought to verify by finer
                // meshes either: a `periodic-cot` candidate kept a defect of 1.8e2 through five
                // refinements (BENCHMARKS.md, "Refinements whose defect does not fall").
                let fails = defect.is_nan() || defect > VERIFIED_DEFECT;
                let defect_stalled = fails && defects.stalled(defect);
                // A refined mesh is finer than the one before it everywhere, so on the same
                // trajectory its defects cannot fail where the coarser mesh's verified: the
                // solve has left the optimum the chain set out to verify, and refining on
                // verifies another one (on `periodic-cot` seed 7 a chain whose defects
                // verified at 1e-6, with its path 4.6x its allowance, jumped to a defect of
                // 2e-3 and an objective 2.8 times higher, and spent 11 s more on it).
                let left = leaving.step(v.is_some_and(|v| v.passes(VERIFIED_DEFECT)));
                // No longer wanted (its result is dropped): it stops as if above.
                let above = next.solution.objective >= bound();
                steps.push(Step {
                    point: next,
                    records: records.len(),
                    label,
                });
                if no_progress || defect_stalled || left || above {
                    break;
                }
                if stuck {
                    break;
                }
            }
            Err(e) => {
                records.push(failed_record(cur.index, label, &e, t0));
                break;
            }
        }
        tol *= 0.1;
    }
    RefinedChain {
        start,
        records,
        steps,
    }
}

/// The verification of a solution refined outside the search (`optimize --refine`), as the
/// search verifies its candidates: re-integrated and, for a plan the policy executes, run in
/// closed loop. One that does not verify goes on to the verification's hp refinements
/// (`refine_until_verified`, `policy.refine_attempts` of them): the error estimate of a mesh
/// refinement can meet its tolerance on a mesh whose element-wise re-integration does not (a
/// bang-bang torque whose polynomial overshoots its bound next to a switch, clamped in the
/// re-integration). `built` is the problem `sol` was solved on. Returns the chain's end where
/// it verifies, else `sol` with its verification (a refinement that does not verify is no
/// better a result than the one the user's tolerance made); the chain's stage records join
/// the strategy report's other verification refinements either way. The problem is `None`
/// only where the result carries none, which none started from a built problem does.
pub fn verify_refined(
    problem: Problem,
    settings: &ProblemSettings,
    built: BuiltProblem,
    sol: OcpSolution,
    policy: &VerifyPolicy,
) -> (Option<BuiltProblem>, OcpSolution) {
    let mut start = Candidate {
        index: 0,
        problem: Some(built),
        solution: sol,
    };
    attach_verification(&mut start, policy, f64::INFINITY);
    if is_verified(&start.solution) || start.solution.verification.is_none() {
        return (start.problem, start.solution);
    }
    let chain = refine_until_verified(problem, settings, start, policy, f64::INFINITY, &|| {
        Some(f64::INFINITY)
    });
    let RefinedChain {
        start,
        records,
        steps,
    } = chain;
    let Candidate {
        problem: built,
        solution: mut sol,
        ..
    } = match steps.into_iter().last() {
        Some(s) if is_verified(&s.point.solution) => s.point,
        _ => start,
    };
    if let Some(rep) = &mut sol.strategy {
        rep.refinements.extend(records);
    }
    (built, sol)
}

/// The stage label of a refinement's record: `label` (the attempt) with the refined point's
/// re-integration defect, its path checks where one is beyond its allowance, and what the
/// closed loop made of it: the search ranks a robustness miss below every robust plan, so a
/// low refined plan that loses says why here.
fn refinement_label(label: &str, sol: &OcpSolution) -> String {
    let v = sol.verification.as_ref();
    let defect = v.map_or(f64::NAN, |v| v.max_defect);
    let excess = v.map_or(f64::NAN, path_excess);
    let path = if excess > 1.0 {
        format!(", path {excess:.1}x its allowance")
    } else {
        String::new()
    };
    let closed_loop = match v {
        Some(v) if execution_failure(v).is_some() => ", execution failed",
        Some(v) if robustness_miss(v).is_some() => ", robustness missed",
        Some(v) if v.not_executed.is_some() => ", not executed: above a verified plan",
        _ => "",
    };
    format!("{label} (defect {defect:.1e}{path}{closed_loop})")
}

/// A successful refinement of a chain ([`RefinedChain`]): the refined point, the number of
/// the chain's records up to it, and its attempt's label ([`refinement_label`]).
#[derive(Debug, Clone)]
struct Step {
    point: Candidate,
    records: usize,
    label: String,
}

/// A candidate's refinement chain ([`refine_until_verified`]): the candidate it started
/// from, a record per attempt, and each successful refinement ([`Step`]), so that the chain
/// can be ended where a lower ceiling would have ended it ([`RefinedChain::cut`]). It ends
/// at its last successful refinement, or where it started.
#[derive(Debug, Clone)]
struct RefinedChain {
    start: Candidate,
    records: Vec<StageRecord>,
    steps: Vec<Step>,
}

impl RefinedChain {
    /// The position in `steps` after which the ceiling `c` ends the chain: its first
    /// refinement whose objective is not below `c`.
    fn cut_at(&self, c: f64) -> Option<usize> {
        self.steps
            .iter()
            .position(|s| s.point.solution.objective >= c)
    }

    /// The chain as it would have ended with the ceiling `c` (the refinements run the same
    /// up to there, so the chain is a prefix of this one), its end left unexecuted where it
    /// could not be chosen over `c` ([`attach_verification`] with that bound).
    fn cut(mut self, c: f64) -> Self {
        if let Some(i) = self.cut_at(c) {
            let n = self.steps[i].records;
            self.steps.truncate(i + 1);
            self.records.truncate(n);
            let step = &mut self.steps[i];
            if !could_be_chosen(step.point.solution.objective, c) {
                leave_unexecuted(&mut step.point);
                let label = refinement_label(&step.label, &step.point.solution);
                // The rounds keep naming their line (`RefineReport::stage`).
                if let Some(rep) = step.point.solution.refinement.as_mut() {
                    rep.stage = Some(label.clone());
                }
                self.records[n - 1].stage = label;
            }
        }
        self
    }

    /// Where the chain ended.
    fn end(self) -> Candidate {
        self.steps
            .into_iter()
            .last()
            .map_or(self.start, |s| s.point)
    }

    /// The objective at which the chain cut at `c` ends verified and robust, if it does
    /// (an end above `c` is left unexecuted by the cut, [`RefinedChain::cut`]).
    fn settled(&self, c: f64) -> Option<f64> {
        let end = match self.cut_at(c) {
            Some(i) => &self.steps[i].point,
            None => self.steps.last().map_or(&self.start, |s| &s.point),
        };
        let j = end.solution.objective;
        (class(&end.solution) == SETTLED && could_be_chosen(j, c)).then_some(j)
    }

    /// The highest objective of the chain, where it ends verified and robust uncut: under any
    /// ceiling above it the chain is not cut and ends settled at or below it
    /// (`refine_in_order`'s `peak`); `None` where the chain does not end settled.
    fn peak(&self) -> Option<f64> {
        let end = self.settled(f64::INFINITY)?;
        Some(
            self.steps
                .iter()
                .map(|s| s.point.solution.objective)
                .fold(end, f64::max),
        )
    }
}

/// Factor by which a refinement must lower the lowest re-integration defect of a candidate's
/// refinements so far to count as progress.
pub const DEFECT_PROGRESS: f64 = 0.5;

/// Refinements in a row without progress on the defect after which a candidate's refinements
/// stop.
pub const DEFECT_STALLS: usize = 2;

/// The defects of a candidate's refinements: progress is a defect below [`DEFECT_PROGRESS`]
/// times the lowest one so far (the candidate's own counts); [`DEFECT_STALLS`] refinements in
/// a row without it end the refinements. Defects that are not finite are no progress.
#[derive(Debug, Clone, Copy)]
struct DefectProgress {
    lowest: f64,
    stalls: usize,
}

impl DefectProgress {
    fn new(start: Option<f64>) -> Self {
        DefectProgress {
            lowest: start.filter(|d| d.is_finite()).unwrap_or(f64::INFINITY),
            stalls: 0,
        }
    }

    /// Records the defect of the next refinement; whether the refinements should stop.
    fn stalled(&mut self, defect: f64) -> bool {
        if defect.is_finite() && defect < DEFECT_PROGRESS * self.lowest {
            self.stalls = 0;
        } else {
            self.stalls += 1;
        }
        if defect.is_finite() {
            self.lowest = self.lowest.min(defect);
        }
        self.stalls >= DEFECT_STALLS
    }
}

/// Factor by which a refinement must shrink how far the path check of a candidate whose
/// defects already verify is beyond its allowance ([`path_excess`] − 1), for the next
/// refinement to be tried (`path_stalled`).
pub const PATH_PROGRESS: f64 = 0.5;

/// The path-check excess ([`path_excess`]) of a verification whose only failure is a path
/// check (completed, defects within [`VERIFIED_DEFECT`], excess above 1); `None` otherwise.
fn path_only_excess(v: &bf_problem::solution::records::Verification) -> Option<f64> {
    let e = path_excess(v);
    (v.passes(VERIFIED_DEFECT) && e > 1.0).then_some(e)
}

/// Whether a refinement chain has left the optimum it set out to verify: a point whose
/// defects fail ([`VERIFIED_DEFECT`]) after an earlier point of the chain had them verified
/// (whatever its path checks said). A refined mesh is finer than the one before it
/// everywhere, so on the same trajectory its defects cannot fail where the coarser mesh's
/// verified (decision record 0057).
#[derive(Debug, Clone, Copy, Default)]
struct LeftOptimum {
    verified_once: bool,
}

impl LeftOptimum {
    /// Records the next point of the chain (whether its re-integration completed with its
    /// defects within [`VERIFIED_DEFECT`]); whether the chain has left its optimum there.
    fn step(&mut self, verifies: bool) -> bool {
        let left = self.verified_once && !verifies;
        self.verified_once |= verifies;
        left
    }
}

/// Whether the refinements of a candidate are stuck on a path check: the previous point
/// (`before`) and the refined one (`now`) both fail on a path check only
/// ([`path_only_excess`]), and the refinement did not shrink the part of the excess beyond
/// the allowance by [`PATH_PROGRESS`]. The `periodic-qc` 0.0769202 tap stays at 24× its
/// cone allowance on every refined mesh; the `periodic-cot-human` direct solve goes from
/// 2.1× to 1.1× (penetration) and verifies at the next refinement.
fn path_stalled(before: Option<f64>, now: Option<f64>) -> bool {
    match (before, now) {
        (Some(b), Some(n)) => n - 1.0 > PATH_PROGRESS * (b - 1.0),
        _ => false,
    }
}

/// Fraction of the best verified objective below which a further candidate is still refined
/// (`refine_in_order`): every candidate below the best verified one may still win, since a
/// refinement may verify far from its candidate's objective, in either direction (on
/// `periodic-cot-human --impact-law stick` seed 2 the lowest candidate, J = 0.01149 on the
/// problem's mesh, verified at 0.01712, and the next, 0.01217, at 0.01583, the best known).
/// What bounds the cost is the ceiling: a chain stops at its first refinement that is not
/// below the best objective verified before it (`refine_until_verified`).
pub const REFINE_BELOW: f64 = 1.0;

/// The lowest objective of the verified (and robust) candidates of `cands`, infinite if none.
fn best_settled(cands: &[Candidate]) -> f64 {
    cands
        .iter()
        .filter(|c| class(&c.solution) == SETTLED)
        .map(|c| c.solution.objective)
        .fold(f64::INFINITY, f64::min)
}

/// The refinement of [`Search::refine_candidates`] on the unverified candidates of `cands`
/// below `ceiling` and below the best verified candidate already in `cands`, with each
/// refinement chain stopped once a refinement's objective is not below either, or below the
/// best verified by the chains before it (`refine_until_verified`); returns the refinements'
/// stage records.
fn refine_below(
    cands: &mut [Candidate],
    problem: Problem,
    settings: &ProblemSettings,
    policy: &VerifyPolicy,
    ceiling: f64,
) -> Vec<StageRecord> {
    if policy.rtol <= 0.0 {
        return Vec::new();
    }
    let ceiling = ceiling.min(best_settled(cands));
    let mut todo: Vec<usize> = (0..cands.len())
        .filter(|&i| {
            let s = &cands[i].solution;
            // A plan the controller did not execute stays what it is on a finer mesh.
            class(s) == UNVERIFIED && s.objective < ceiling && !execution_failed(s)
        })
        .collect();
    todo.sort_by(|&a, &b| lowest_first(&cands[a], &cands[b]));
    let refined = refine_in_order(
        &todo,
        policy.clusters,
        rayon::current_num_threads(),
        |&i| cands[i].solution.objective,
        |&i, earlier| {
            let c = cands[i].clone();
            refine_until_verified(problem, settings, c, policy, ceiling, earlier)
        },
        RefinedChain::settled,
        RefinedChain::cut,
        RefinedChain::peak,
    );
    let mut records = Vec::new();
    for (i, mut chain) in refined {
        records.append(&mut chain.records);
        cands[i] = chain.end();
    }
    records
}

/// Applies `refine` to the items of `order` (lowest `value` first), at most `max` of them,
/// until the next item's `value` is no lower than [`REFINE_BELOW`] times the lowest value
/// verified by the results before it; returns each item refined with its result. Each
/// result is taken as it would have ended with that lowest value as its ceiling (`cut`;
/// `verified(result, ceiling)`: the value at which the result so cut verifies, `None` if it
/// does not). A refinement may verify at a much higher objective than its candidate's (the
/// refined meshes' solves move between nearby basins: a `periodic-cot` candidate of J 1.1e-4
/// verified at 1.7e-3 while the third one verifies at 4.1e-4), so the first verified result
/// does not end the refinements while a lower candidate is left.
///
/// The rule is sequential, and so is the result: the items and results returned are those of
/// refining one item after the other, whatever `width`. Up to `width` items are refined at a
/// time (each refinement chain is sequential, so a second core would otherwise idle). A
/// worker takes the next item unless the results finished before it rule it out, and
/// `refine` gets an `earlier` check that returns the lowest value verified before its item,
/// or `None` once those results rule the item out (a chain checks it between refinements and
/// stops at a refinement not below it; a ruled-out chain's result is dropped). Both read only
/// the finished results at the front of the order (up to the first unfinished one), cut as
/// the sequential rule cuts them: further results can only lower that value. A result
/// finished behind an unfinished one bounds it too, through its `peak` (`Some(p)`: under
/// every ceiling above `p` the result is left as it is and verifies, at a value not above
/// `p`; `None`: it does not verify). Whatever the ceiling `c` the sequential rule hands that
/// result, the lowest value verified after it is at most `p`: above `p` the result verifies
/// at most there, and a ceiling not above `p` is itself that low. (A result that was told to
/// stop belongs to an item the sequential rule rules out, and then every later item is ruled
/// out as well.) So an item the sequential rule refines is never ruled out, and a chain never
/// stops before the sequential rule would stop it; the result is then cut where the
/// sequential rule ends it.
#[allow(clippy::too_many_arguments)]
fn refine_in_order<I: Copy + Sync, T: Send>(
    order: &[I],
    max: usize,
    width: usize,
    value: impl Fn(&I) -> f64 + Sync,
    refine: impl Fn(&I, &dyn Fn() -> Option<f64>) -> T + Sync,
    verified: impl Fn(&T, f64) -> Option<f64> + Sync,
    cut: impl Fn(T, f64) -> T,
    peak: impl Fn(&T) -> Option<f64> + Sync,
) -> Vec<(I, T)> {
    let n = order.len().min(max);
    // Finished results by position in `order`, and the next position to hand out.
    let state: Mutex<(Vec<Option<T>>, usize)> = Mutex::new(((0..n).map(|_| None).collect(), 0));
    // The sequential rule over the finished results at the front of the order, before
    // position k: the lowest value they verify (each cut at the lowest before it), and the
    // lowest peak of every result finished before k (at the front a peak adds nothing: the
    // front's value is at most it); `None` if they rule out k.
    let lowest_before = |done: &[Option<T>], k: usize| {
        let mut best = f64::INFINITY;
        // (A result before k that the rule itself rules out may still lower `best` here, but
        // values ascend, so k is ruled out by it either way.)
        for t in &done[..k] {
            let Some(t) = t else { break };
            if let Some(v) = verified(t, best) {
                best = best.min(v);
            }
        }
        // A long chain at the front would otherwise let the other workers refine item after
        // item that a result finished behind it already rules out (on `periodic-cot` seed 6
        // four chains and their closed-loop runs, while the front chain's ran for 13 s).
        let behind = done[..k]
            .iter()
            .flatten()
            .filter_map(&peak)
            .fold(f64::INFINITY, f64::min);
        let best = best.min(behind);
        (value(&order[k]) < REFINE_BELOW * best).then_some(best)
    };
    let lock = || state.lock().unwrap_or_else(|e| e.into_inner());
    let work = || {
        loop {
            let k = {
                let mut st = lock();
                let k = st.1;
                if k >= n || lowest_before(&st.0, k).is_none() {
                    // Values ascend: every later item is ruled out as well.
                    st.1 = n;
                    return;
                }
                st.1 += 1;
                k
            };
            let earlier = || lowest_before(&lock().0, k);
            let r = refine(&order[k], &earlier);
            lock().0[k] = Some(r);
        }
    };
    if width <= 1 || n <= 1 {
        work();
    } else {
        rayon::scope(|sc| {
            for _ in 0..width.min(n) {
                sc.spawn(|_| work());
            }
        });
    }
    // The sequential rule over the results, each cut at the lowest value verified before it:
    // the items up to the first that the results before it rule out.
    let done = state.into_inner().unwrap_or_else(|e| e.into_inner()).0;
    let mut best = f64::INFINITY;
    let mut out = Vec::new();
    for (k, t) in done.into_iter().enumerate() {
        if value(&order[k]) >= REFINE_BELOW * best {
            break;
        }
        let Some(t) = t else { break };
        let t = cut(t, best);
        if let Some(v) = verified(&t, f64::INFINITY) {
            best = best.min(v);
        }
        out.push((order[k], t));
    }
    out
}

/// A search for the best verified optimum: runs the chains of `strategy` in `shard`
/// (in parallel, results in index order), re-integrates every end point, keeps one
/// candidate per distinct optimum, and hp-refines the unverified optima that beat the best
/// verified one, lowest objective first, until none below the best verified objective is
/// left (`refine_until_verified`, at most `policy.clusters` of them). Every
/// decision depends on the computed values only, never on thread scheduling, so the result is
/// the same bit for bit with any number of threads. [`Search::best`] then picks by [`select`].
/// The starts of a global search ([`VerifyPolicy::hops`]) sample each joint's revolution,
/// those of a plain multi-start the neighbourhood of the default guess (decision record
/// 0054).
pub fn search(
    problem: Problem,
    settings: &ProblemSettings,
    strategy: Strategy,
    shard: Shard,
    policy: &VerifyPolicy,
    progress: Progress<'_>,
) -> Result<Search, PipelineError> {
    let revolution = policy.hops.is_some();
    search_sampling(
        problem, settings, strategy, shard, policy, progress, revolution,
    )
}

/// [`search`] with its starts drawn over each joint's revolution or not (`revolution`): the
/// global search's fallback to the starts ([`Search::fall_back_to_the_starts`]) runs without
/// hops but samples as the global search does.
fn search_sampling(
    problem: Problem,
    settings: &ProblemSettings,
    strategy: Strategy,
    shard: Shard,
    policy: &VerifyPolicy,
    progress: Progress<'_>,
    revolution: bool,
) -> Result<Search, PipelineError> {
    let t0 = Instant::now();
    let strategy = effective(settings, strategy);
    let coarse = coarse_mesh(settings, strategy, policy);
    let sampled_on = coarse.as_ref().map_or(settings, |(_, s)| s);
    let (target, mut chains) = prepare_chains(
        problem,
        sampled_on,
        strategy,
        policy.stick_continuation,
        revolution,
    )?;
    if policy.hops.is_some() && super::bounds::period_row(&target.ocp).is_some() {
        hold_the_period(&mut chains);
    }
    let land = OcpLandscape {
        problem,
        settings,
        policy,
        chains,
        verify_samples: coarse.is_none(),
        progress,
        records: Mutex::new(Vec::new()),
    };
    let ks: Vec<usize> = (0..land.chains.len())
        .filter(|&k| shard.contains(k))
        .collect();
    let cands: Vec<Candidate> = global::sample(&land, &ks)
        .into_iter()
        .filter_map(|(_, c)| c)
        .collect();
    let records = land.take_records();
    let mut cands = representatives(cands);
    cands.sort_by_key(|c| c.index);
    let mut found = Search {
        strategy,
        shard,
        sampled: cands.clone(),
        candidates: cands,
        records,
        refinements: Vec::new(),
        seconds: t0.elapsed().as_secs_f64(),
        basin_hits: None,
    };
    // Shards sample only; `optimize merge` explores from the union of their samples. A
    // shard still promotes and refines its own candidates for its own output set.
    if shard == Shard::WHOLE {
        found.explore(problem, settings, policy, progress);
    }
    found.promote_and_refine(
        problem,
        settings,
        policy,
        coarse.map(|(c, _)| c.promote),
        progress,
    );
    if shard == Shard::WHOLE {
        found.fall_back_to_the_starts(problem, settings, policy, progress)?;
        found.polish_the_winner(problem, settings, policy, progress);
    }
    found.seconds = t0.elapsed().as_secs_f64();
    Ok(found)
}

/// The period continuation of the global search's starts on a problem with a period row
/// ([`super::bounds::period_row`]: the COT problems): every odd start is first solved with
/// its period at most its start's (the sum of the start's durations, 0.15–4.8 s,
/// [`super::strategy::random_start`]), then released warm to the problem's period bounds (at
/// most [`HOP_MAX_ITER`] iterations). The COT ratio pulls a cold start to the period's 10 s
/// bound: on `periodic-cot-human` seeds 5 and 6 every start, reshaping move and hop ended
/// there, while the best optimum (8.46 s) is reached through short-period optima (2.6 s,
/// J 0.020 on the coarse mesh) that a start held short finds and keeps once released
/// (decision record 0037). Even starts keep the plain solve; chains that are not single
/// starts are left alone.
fn hold_the_period(chains: &mut [Chain]) {
    for (k, chain) in chains.iter_mut().enumerate() {
        let [(label, st)] = chain.as_mut_slice() else {
            continue;
        };
        let Some(start) = st.start.as_ref().filter(|_| k % 2 == 1) else {
            continue;
        };
        // A start whose period is outside the given bounds is not held (its held stage
        // would loosen the upper bound or be infeasible).
        let t: f64 = start.durations.iter().sum();
        let (lo, hi) = st.period_bounds.unwrap_or((0.0, f64::INFINITY));
        if !(t.is_finite() && t > lo && t < hi) {
            continue;
        }
        let released = ProblemSettings {
            start: None,
            max_iter: st.max_iter.min(HOP_MAX_ITER),
            ..st.clone()
        };
        st.period_bounds = Some((lo, t));
        label.push_str(&format!(", period <= {t:.3}"));
        chain.push((RELEASE_PERIOD_LABEL.to_string(), released));
    }
}

/// Stage label prefix of the starts of a global search's fallback
/// ([`Search::fall_back_to_the_starts`]).
pub const FALLBACK_LABEL: &str = "fallback";

/// Stage label of the release of a start held to a short period (`hold_the_period`).
pub const RELEASE_PERIOD_LABEL: &str = "release the period";

/// The coarse sampling of `policy` and the settings of its mesh, where it applies
/// ([`CoarseSampling`]: a multi-start on a Radau mesh of more points than the coarse one).
fn coarse_mesh(
    settings: &ProblemSettings,
    strategy: Strategy,
    policy: &VerifyPolicy,
) -> Option<(CoarseSampling, ProblemSettings)> {
    let c = policy.coarse?;
    let applies = matches!(strategy, Strategy::Multistart { .. })
        && matches!(settings.scheme, Scheme::Radau { .. })
        && settings.mesh.is_none()
        && c.points < settings.points;
    applies.then(|| {
        (
            c,
            ProblemSettings {
                points: c.points,
                scheme: Scheme::Radau {
                    elements: c.elements,
                },
                ..settings.clone()
            },
        )
    })
}

/// The optimal-control problem as a [`Landscape`] of the global search: a start is a chain of
/// the strategy ([`run_chain`]), a hop scales the phase durations of a local optimum's primal
/// point (each by e^(s·u), u uniform in [−1, 1], times a common factor for the period of the
/// same law) and re-solves it warm from μ = [`HOP_MU`] on the optimum's own mesh (the coarse
/// one of [`CoarseSampling`] by default); end points on the problem's mesh are
/// re-integrated. Points rank successful first, then by objective (better by more than
/// [`CLUSTER_RTOL`] relative): the verification and refinement come after the exploration
/// ([`Search::refine_candidates`]). Points are the same optimum by `same_optimum`.
struct OcpLandscape<'a> {
    problem: Problem,
    settings: &'a ProblemSettings,
    policy: &'a VerifyPolicy,
    chains: Vec<Chain>,
    /// Whether a start's end point is re-integrated (not on a coarse mesh, whose end points
    /// are re-solved on the problem's mesh first).
    verify_samples: bool,
    progress: Progress<'a>,
    /// Stage records of the solves (each start's or hop's pushed at once).
    records: Mutex<Vec<StageRecord>>,
}

impl OcpLandscape<'_> {
    /// The candidate of a hop's or a reshaping move's solve `res` (`label` in the records,
    /// timed from `t0`), re-integrated when the policy verifies; `None`, recorded, when the
    /// solve failed.
    fn candidate(
        &self,
        id: usize,
        label: String,
        t0: Instant,
        res: Result<(BuiltProblem, OcpSolution), PipelineError>,
    ) -> Option<Candidate> {
        let (b, sol) = match res {
            Ok(r) => r,
            Err(e) => {
                self.push(&self.records, vec![failed_record(id, label, &e, t0)]);
                return None;
            }
        };
        let mut c = Candidate {
            index: id,
            problem: Some(b),
            solution: sol,
        };
        self.push(&self.records, vec![record(id, label, &c.solution, t0)]);
        if self.policy.rtol > 0.0 && self.verify_samples {
            attach_verification(&mut c, self.policy, f64::INFINITY);
        }
        Some(c)
    }

    /// The records so far, sorted by chain (stable: a chain's stages keep their order, since
    /// each chain pushes its records at once), so they do not depend on the order in which
    /// the threads finished.
    fn take_records(&self) -> Vec<StageRecord> {
        let mut v = std::mem::take(&mut *self.records.lock().unwrap_or_else(|e| e.into_inner()));
        v.sort_by_key(|r| r.chain);
        v
    }

    fn push(&self, to: &Mutex<Vec<StageRecord>>, recs: Vec<StageRecord>) {
        if let Some(f) = self.progress {
            recs.iter().for_each(f);
        }
        to.lock().unwrap_or_else(|e| e.into_inner()).extend(recs);
    }

    /// The coarse end point `from` re-solved on the problem's mesh, warm-started from its
    /// trajectory interpolated onto that mesh, and re-integrated ([`CoarseSampling`]): solved
    /// from a warm start's barrier parameter and from a close one ([`PROMOTE_MU_INIT`]), the
    /// lower successful solution kept; executed in closed loop only where it could be chosen
    /// over the verified and robust objective `bound` ([`attach_verification`]).
    fn promote(&self, from: &Candidate, bound: f64) -> Option<Candidate> {
        let t0 = Instant::now();
        let b = match build(
            self.problem,
            &ProblemSettings {
                warm_start: Some(from.solution.clone()),
                start: None,
                ..self.settings.clone()
            },
        ) {
            Ok(b) => b,
            Err(e) => {
                let label = PROMOTE_LABEL.to_string();
                self.push(
                    &self.records,
                    vec![failed_record(from.index, label, &e, t0)],
                );
                return None;
            }
        };
        let starts = [
            (PROMOTE_LABEL.to_string(), INTERPOLATED_MU_INIT_MAX),
            (PROMOTE_CLOSE_LABEL.to_string(), PROMOTE_MU_INIT),
        ];
        let mut recs = Vec::new();
        let mut best: Option<OcpSolution> = None;
        for (label, mu_max) in starts {
            let t0 = Instant::now();
            match solve_with_mu_max(&b, mu_max, None) {
                Ok(sol) => {
                    recs.push(record(from.index, label, &sol, t0));
                    if best.as_ref().is_none_or(|kept| better_solve(&sol, kept)) {
                        best = Some(sol);
                    }
                }
                Err(e) => recs.push(failed_record(from.index, label, &e, t0)),
            }
        }
        self.push(&self.records, recs);
        let mut c = Candidate {
            index: from.index,
            problem: Some(b),
            solution: best?,
        };
        if self.policy.rtol > 0.0 {
            attach_verification(&mut c, self.policy, bound);
        }
        Some(c)
    }

    /// The primal-dual point of `from` with its phase durations scaled (module docs of
    /// [`global`]), clamped into the variable bounds of `p`; `None` if its layout is not `p`'s.
    fn perturbed(
        p: &BuiltProblem,
        from: &OcpSolution,
        seed: u64,
        scale: f64,
    ) -> Option<bf_optim::ipm::WarmStart> {
        let mut w = from.nlp_warm.clone()?;
        let n = Nlp::num_variables(&p.nlp);
        if w.x.len() != n || w.z_l.len() != n || w.z_u.len() != n {
            return None;
        }
        let (mut lo, mut up) = (vec![0.0; n], vec![0.0; n]);
        Nlp::variable_bounds(&p.nlp, &mut lo, &mut up);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let common = scale * rng.random_range(-1.0..1.0);
        for l in &p.nlp.phases {
            let f = libm::exp(common + scale * rng.random_range(-1.0..1.0));
            w.x[l.t] = (w.x[l.t] * f).clamp(lo[l.t], up[l.t]);
        }
        // One offset of the joint angles (the first states) over the whole period, so the
        // periodicity and the phase links stay as consistent as the optimum left them.
        let nq = p.guess.free.len();
        let dq: Vec<f64> = (0..nq)
            .map(|_| scale * HOP_JOINT * rng.random_range(-1.0..1.0))
            .collect();
        for l in &p.nlp.phases {
            for pt in 0..l.mesh.state_tau.len() {
                for (i, d) in dq.iter().enumerate().take(l.nx) {
                    let k = l.x(pt, i);
                    w.x[k] = (w.x[k] + d).clamp(lo[k], up[k]);
                }
            }
        }
        Some(w)
    }
}

impl Landscape for OcpLandscape<'_> {
    type Point = Candidate;

    fn sample(&self, k: usize) -> Option<Candidate> {
        let stages = self.chains.get(k)?.clone();
        let (recs, res) = run_chain(self.problem, k, stages, None, None);
        self.push(&self.records, recs);
        let (p, s) = res?;
        let mut c = Candidate {
            index: k,
            problem: Some(p),
            solution: s,
        };
        if self.policy.rtol > 0.0 && self.verify_samples {
            attach_verification(&mut c, self.policy, f64::INFINITY);
        }
        Some(c)
    }

    fn hop(&self, from: &Candidate, seed: u64, scale: f64, id: usize) -> Option<Candidate> {
        let t0 = Instant::now();
        let p = from.problem.as_ref()?;
        let label = if scale == 0.0 {
            format!("polish {}: re-solve from mu {HOP_MU:e}", from.index)
        } else {
            // The wide scale is a product (0.3 × 8/3): shown to six decimals, not as the
            // float's full expansion (0.7999999999999999).
            let shown = (scale * 1e6).round() / 1e6;
            format!("hop from {} (scale {shown})", from.index)
        };
        let settings = ProblemSettings {
            points: p.settings.points,
            scheme: p.settings.scheme,
            mesh: p.settings.mesh.clone(),
            max_iter: self.settings.max_iter.min(HOP_MAX_ITER),
            warm_start: None,
            start: None,
            ..self.settings.clone()
        };
        // Every other hop of `periodic-qc` goes through the stick continuation, as the starts
        // do: first with the stick phase bounded to the continuation's bound, then relaxed
        // (warm) to the problem's; a stick phase of real duration leads to other basins.
        let through = self.policy.stick_continuation.filter(|&s0| {
            self.problem == Problem::PeriodicQc && s0 > settings.min_stick && id % 2 == 1
        });
        let label = match through {
            Some(s0) => format!("{label}, stick >= {s0}, relaxed"),
            None => label,
        };
        let res = build(
            self.problem,
            &ProblemSettings {
                min_stick: through.unwrap_or(settings.min_stick),
                ..settings.clone()
            },
        )
        .and_then(|b| {
            let w = Self::perturbed(&b, &from.solution, seed, scale).ok_or(
                PipelineError::Internal("a hop's origin does not fit its own problem"),
            )?;
            let sol = solve_recentred(&b, &w, HOP_MU)?;
            if through.is_none() {
                return Ok((b, sol));
            }
            let relaxed = build(self.problem, &settings)?;
            let w = sol.nlp_warm.as_ref().ok_or(PipelineError::Internal(
                "a bounded hop's solution has no primal-dual point",
            ))?;
            let mut fin = super::solve::solve_warm(&relaxed, w, None)?;
            fin.iterations += sol.iterations;
            Ok((relaxed, fin))
        });
        self.candidate(
            id,
            label,
            t0,
            res.map(|r| on_the_mesh_of(r, &from.solution)),
        )
    }

    fn better(&self, a: &Candidate, b: &Candidate) -> bool {
        let (ca, cb) = (solved(&a.solution), solved(&b.solution));
        let (ja, jb) = (a.solution.objective, b.solution.objective);
        ca && (!cb || ja < jb - CLUSTER_RTOL * jb.abs())
    }

    fn same(&self, a: &Candidate, b: &Candidate) -> bool {
        solved(&a.solution) == solved(&b.solution) && same_optimum(&a.solution, &b.solution)
    }

    fn alike(&self, a: &Candidate, b: &Candidate) -> bool {
        solved(&a.solution) == solved(&b.solution) && same_shape(&a.solution, &b.solution)
    }

    fn reshapes(&self, from: &Candidate) -> usize {
        if solved(&from.solution) && from.problem.is_some() {
            MOVES.len()
        } else {
            0
        }
    }

    fn reshape(&self, from: &Candidate, kind: usize, id: usize) -> Option<Candidate> {
        let t0 = Instant::now();
        let p = from.problem.as_ref()?;
        let m = MOVES.get(kind)?;
        let within: Vec<(f64, f64)> = p.ocp.phases.iter().map(|ph| ph.duration_bounds).collect();
        let bounds = m.bounds(&from.solution.phase_durations, &within, &p.modes)?;
        let label = format!(
            "reshape {} from {}: {}{}",
            kind,
            from.index,
            m.describe(),
            if m.moves_posture() { "" } else { ", released" }
        );
        let max_iter = self.settings.max_iter.min(HOP_MAX_ITER);
        let res = (|| {
            let mut released = p.clone();
            released.settings.max_iter = max_iter;
            let fit = || PipelineError::Internal("a reshaped optimum does not fit its own problem");
            if m.moves_posture() {
                // The hop's seed is the reshaped point's global index: the same on every
                // thread count and shard.
                let mut w = Self::perturbed(&released, &from.solution, id as u64, m.hop_scale())
                    .ok_or_else(fit)?;
                let n = Nlp::num_variables(&released.nlp);
                let (mut lo, mut up) = (vec![0.0; n], vec![0.0; n]);
                Nlp::variable_bounds(&released.nlp, &mut lo, &mut up);
                let nq = released.guess.free.len();
                if m.mirrors() {
                    mirror_first_joint(&released, nq, &mut w.x, &lo, &up);
                } else {
                    flip_elbow(&released, nq, &mut w.x, &lo, &up);
                }
                let sol = solve_recentred(&released, &w, HOP_MU)?;
                return Ok((released, sol));
            }
            let held = with_duration_bounds(&released, &bounds)?;
            let w = Self::perturbed(&held, &from.solution, 0, 0.0).ok_or_else(fit)?;
            let sol = solve_recentred(&held, &w, HOP_MU)?;
            let w = sol.nlp_warm.as_ref().ok_or(PipelineError::Internal(
                "a reshaped solve's solution has no primal-dual point",
            ))?;
            let mut fin = super::solve::solve_warm(&released, w, None)?;
            fin.iterations += sol.iterations;
            Ok::<_, PipelineError>((released, fin))
        })();
        self.candidate(
            id,
            label,
            t0,
            res.map(|r| on_the_mesh_of(r, &from.solution)),
        )
    }
}

/// A hop's or a reshaping move's result `r`, solved on the mesh of its origin `from`, with
/// `from`'s refinement record: the record is where a solution keeps the refined mesh it was
/// solved on ([`super::solve::own_problem`] rebuilds it from there), as a re-solve at a
/// stored optimum keeps it ([`super::solve::resolve_at_own_point`]). Without it a result of
/// the winner's neighbourhood ([`Search::polish_the_winner`]) would be written as if solved on
/// the problem's mesh, and its file could not be solved again.
fn on_the_mesh_of(
    (b, mut sol): (BuiltProblem, OcpSolution),
    from: &OcpSolution,
) -> (BuiltProblem, OcpSolution) {
    sol.refinement.clone_from(&from.refinement);
    (b, sol)
}

/// What the global search's [`StrategyReport::basin_hits`] says, as `optimize` and `paper`
/// print it (`None` where no global search ran).
pub fn basin_line(report: &StrategyReport) -> Option<String> {
    report.basin_hits.map(|n| {
        format!(
            "basin: {n} of the distinct sampled optima and basin hops ended in the optimum's \
             basin (its shape: objective and every phase duration within {:.0} %)",
            100.0 * SHAPE_RTOL
        )
    })
}

/// Whether two end points have the same shape: objectives within [`SHAPE_RTOL`] and every
/// phase duration within [`SHAPE_RTOL`] relative or 5 ms (the reshaping's origins differ
/// in shape, so that the moves are not spent on variants of one basin).
pub(crate) fn same_shape(a: &OcpSolution, b: &OcpSolution) -> bool {
    let close = |x: f64, y: f64, abs: f64| (x - y).abs() <= SHAPE_RTOL * x.abs().max(y.abs()) + abs;
    close(a.objective, b.objective, 0.0)
        && a.phase_durations.len() == b.phase_durations.len()
        && a.phase_durations
            .iter()
            .zip(&b.phase_durations)
            .all(|(x, y)| close(*x, *y, 5e-3))
}

impl Search {
    /// The promotion and refinement of a coarse sampling ([`CoarseSampling`]): the `promote`
    /// best candidates that differ in shape (`same_shape`; successful, lowest objective, then
    /// lowest index) re-solved on the problem's own mesh from their coarse trajectories, in
    /// parallel; while the next shape's coarse objective is below the lowest objective
    /// re-solved so far, the next `promote` shapes as well (the bound, decision record 0053:
    /// the coarse mesh under-prices the long free phases of the COT orbits up to 100-fold, so
    /// the lowest coarse shapes can all re-solve above a shape further down), for at most
    /// [`PROMOTE_BOUND_ROUNDS`] rounds in all; then the rounds not yet refined are refined
    /// ([`Search::refine_candidates`]). Once a candidate verifies, the bound holds against
    /// the best verified objective instead: while the next shape's coarse objective is below
    /// it, the next shapes are promoted and those below it refined (a re-solved candidate
    /// can refine far above its objective, so the first bound can stop too early). While
    /// none of the candidates verifies, the next `promote` shapes down the ranking the same
    /// way, refined at most [`PROMOTE_ROUNDS`] times (a plan for the plant whose best shapes
    /// the controller does not execute, decision record 0048). The re-solved candidates
    /// replace the coarse ones.
    /// `promote` = `None`: the candidates are on the problem's mesh already and are only
    /// refined.
    pub fn promote_and_refine(
        &mut self,
        problem: Problem,
        settings: &ProblemSettings,
        policy: &VerifyPolicy,
        promote: Option<usize>,
        progress: Progress<'_>,
    ) {
        let Some(promote) = promote.filter(|&n| n > 0) else {
            self.refine_candidates(problem, settings, policy);
            return;
        };
        let land = OcpLandscape {
            problem,
            settings,
            policy,
            chains: Vec::new(),
            verify_samples: true,
            progress,
            records: Mutex::new(Vec::new()),
        };
        let coarse = std::mem::take(&mut self.candidates);
        let mut order: Vec<&Candidate> = coarse.iter().filter(|c| solved(&c.solution)).collect();
        order.sort_by(|a, b| lowest_first(a, b));
        // One candidate per shape: coarse optima that differ only in the last digits of solves
        // that met the acceptable tolerances are one basin, which re-solves to one optimum on
        // the problem's mesh (decision record 0047).
        let mut shapes: Vec<&Candidate> = Vec::new();
        for c in order {
            if !shapes.iter().any(|s| same_shape(&s.solution, &c.solution)) {
                shapes.push(c);
            }
        }
        let mut kept: Vec<Candidate> = Vec::new();
        // Promoted and not yet refined.
        let mut pending: Vec<Candidate> = Vec::new();
        let mut refinements = 0;
        let mut batches = shapes.chunks(promote).take(PROMOTE_BOUND_ROUNDS).peekable();
        while let Some(batch) = batches.next() {
            let verified = best_settled(&kept);
            let mut done: Vec<Candidate> = batch
                .par_iter()
                .filter_map(|c| land.promote(c, verified))
                .collect();
            self.records.extend(land.take_records());
            pending.append(&mut done);
            // The bound: the coarse mesh prices a shape below its optimum on the problem's
            // mesh, so a shape whose coarse objective is not below the best re-solved one
            // cannot win; while the next shape's is, it is promoted before anything is
            // refined (decision record 0053).
            let best = kept
                .iter()
                .chain(&pending)
                .filter(|c| solved(&c.solution))
                .map(|c| c.solution.objective)
                .fold(f64::INFINITY, f64::min);
            if batches
                .peek()
                .is_some_and(|next| next[0].solution.objective < best)
            {
                continue;
            }
            pending = representatives(std::mem::take(&mut pending));
            pending.sort_by_key(|c| c.index);
            // Each refinement refines the rounds since the last one only (an earlier round's
            // were refined already), each below the best verified so far.
            let verified = best_settled(&kept);
            let records = refine_below(&mut pending, problem, settings, policy, verified);
            self.refinements.extend(records);
            kept.append(&mut pending);
            refinements += 1;
            if policy.rtol <= 0.0 {
                break;
            }
            // The bound again, against what verified: a shape whose coarse objective is below
            // the best verified objective may still win. The lowest re-solved objective of a
            // round can be a candidate that refines far above it (on `periodic-cot` seed 7 one
            // at 7.5e-4 refined to 1.7e-2 while the verified winner was 9.2e-4), so the first
            // bound stops the promotion too early once the refinements have spoken.
            let verified = best_settled(&kept);
            if verified.is_finite() {
                if batches
                    .peek()
                    .is_some_and(|next| next[0].solution.objective < verified)
                {
                    continue;
                }
                break;
            }
            if refinements >= PROMOTE_ROUNDS {
                break;
            }
        }
        kept = representatives(kept);
        kept.sort_by_key(|c| c.index);
        self.candidates = kept;
    }

    /// The strategy checkpoint of a global search ([`VerifyPolicy::hops`]) that ends without a
    /// verified candidate: the [`super::strategy::DEFAULT_STARTS`] starts of the same seed on
    /// the problem's own mesh (the search of `optimize --hops 0`, but with the global search's
    /// sampling of each joint's revolution), verified and refined the same way, whose
    /// candidates join this search's (their chains numbered after its own).
    /// The coarse ranking can place every shape of a family that does not verify above the
    /// ones that do: on the plans for the plant of `periodic-cot-human`, with the controller of
    /// decision record 0048, seeds 4 and 5 promoted 24 shapes of the lower plans that it did
    /// not execute, while the starts on the problem's mesh verified J = 0.0674642. Nothing
    /// happens when a candidate verifies, without verification (`rtol` 0), and for searches
    /// that are not global; `optimize merge` calls it as the unsharded run does.
    pub fn fall_back_to_the_starts(
        &mut self,
        problem: Problem,
        settings: &ProblemSettings,
        policy: &VerifyPolicy,
        progress: Progress<'_>,
    ) -> Result<(), PipelineError> {
        let Strategy::Multistart { seed, .. } = self.strategy else {
            return Ok(());
        };
        if policy.hops.is_none()
            || policy.rtol <= 0.0
            || self
                .candidates
                .iter()
                .any(|c| class(&c.solution) == SETTLED)
        {
            return Ok(());
        }
        let plain = VerifyPolicy {
            hops: None,
            coarse: None,
            ..*policy
        };
        let starts = Strategy::Multistart {
            starts: super::strategy::DEFAULT_STARTS,
            seed,
        };
        // The global search's sampling goes on: on the problem's mesh, without hops (on
        // `periodic-cot` seed 4 these starts verify J = 1.2e-3, near q⁰ 2.9e-2).
        let found = search_sampling(
            problem,
            settings,
            starts,
            Shard::WHOLE,
            &plain,
            progress,
            true,
        )?;
        let offset = self.next_index();
        let renumber = |mut r: StageRecord| {
            r.chain += offset;
            r.stage = format!("{FALLBACK_LABEL}: {}", r.stage);
            r
        };
        self.records.extend(found.records.into_iter().map(renumber));
        self.refinements
            .extend(found.refinements.into_iter().map(renumber));
        self.candidates
            .extend(found.candidates.into_iter().map(|mut c| {
                c.index += offset;
                // The rounds keep naming their line, relabelled as the records are.
                if let Some(stage) = c
                    .solution
                    .refinement
                    .as_mut()
                    .and_then(|r| r.stage.as_mut())
                {
                    *stage = format!("{FALLBACK_LABEL}: {stage}");
                }
                c
            }));
        self.candidates.sort_by_key(|c| c.index);
        Ok(())
    }

    /// The position in [`Search::candidates`] of the candidate [`select`] chooses.
    fn choice(&self) -> Option<usize> {
        let views: Vec<(usize, &OcpSolution)> = self
            .candidates
            .iter()
            .map(|c| (c.index, &c.solution))
            .collect();
        select(&views)
    }

    /// The first chain index after every record and candidate so far: where the stages of a
    /// later step of the search are numbered from.
    fn next_index(&self) -> usize {
        self.records
            .iter()
            .chain(&self.refinements)
            .map(|r| r.chain + 1)
            .chain(self.candidates.iter().map(|c| c.index + 1))
            .max()
            .unwrap_or(0)
    }

    /// The winner's neighbourhood on its own mesh ([`POLISH_HOPS`]): from the best verified and
    /// robust candidate, every reshaping move and a few basin hops solved on the mesh it
    /// verified on (its refined one), then a polishing round; the results below the winner's
    /// objective are verified, the unverified ones refined ([`Search::refine_candidates`]), and
    /// all join the candidates. The coarse exploration and the promotion end in the basins
    /// that the coarse shapes lead to, and a refinement may move a promoted shape into another
    /// basin: on `periodic-cot-human` a promoted J = 0.0457 shape refines to a verified
    /// 0.0509500 plan, whose neighbour on the 10 s period bound, J = 0.0448, no coarse shape
    /// of seeds 0, 1 and 6 led to (decision record 0052). While a round's verified results
    /// give a new winner [`NEIGHBOURHOOD_GAIN`] lower or more, the next round is the new
    /// winner's neighbourhood, up to [`NEIGHBOURHOOD_ROUNDS`] rounds: the plan a round
    /// reaches can have a lower family beside it that no move from the first winner reaches
    /// (on `periodic-cot` seed 7 the first round moves the 8.289e-4 plan to 8.271e-4, whose
    /// second round reaches 7.816e-4; decision records 0057 and 0058). Where the search's
    /// choice comes from here, [`Search::basin_hits`] counts the solves of its round that
    /// ended in its shape. Only for a global search that verifies; `optimize merge` calls it
    /// as the unsharded run does.
    pub fn polish_the_winner(
        &mut self,
        problem: Problem,
        settings: &ProblemSettings,
        policy: &VerifyPolicy,
        progress: Progress<'_>,
    ) {
        let Strategy::Multistart { seed, .. } = self.strategy else {
            return;
        };
        if policy.hops.is_none() || policy.rtol <= 0.0 {
            return;
        }
        for round in 0..NEIGHBOURHOOD_ROUNDS {
            match self.neighbourhood_round(problem, settings, policy, progress, seed, round) {
                Some((before, after)) if before - after > NEIGHBOURHOOD_GAIN * before.abs() => {}
                _ => break,
            }
        }
    }

    /// One round of [`Search::polish_the_winner`] (its `round`, from 0): the neighbourhood of
    /// the current winner; the objectives of the winner before and after it when the winner
    /// it leaves is one of this round's solves, `None` otherwise.
    fn neighbourhood_round(
        &mut self,
        problem: Problem,
        settings: &ProblemSettings,
        policy: &VerifyPolicy,
        progress: Progress<'_>,
        seed: u64,
        round: usize,
    ) -> Option<(f64, f64)> {
        let winner = self
            .candidates
            .iter()
            .filter(|c| class(&c.solution) == SETTLED && c.problem.is_some())
            .min_by(|a, b| lowest_first(a, b))
            .cloned()?;
        let land = OcpLandscape {
            problem,
            settings,
            policy,
            chains: Vec::new(),
            // Only the results below the winner are verified (below).
            verify_samples: false,
            progress,
            records: Mutex::new(Vec::new()),
        };
        let first = self.next_index();
        let e = global::exploit(
            &land,
            std::slice::from_ref(&winner),
            &HopSettings {
                // Each round's hops are drawn anew (a later round starts from another point).
                seed: seed.wrapping_add(round as u64),
                ..POLISH_HOPS
            },
            first,
        );
        let label = match round {
            0 => POLISH_LABEL.to_string(),
            r => format!("{POLISH_LABEL} {}", r + 1),
        };
        self.records
            .extend(land.take_records().into_iter().map(|mut r| {
                r.stage = format!("{label}: {}", r.stage);
                r
            }));
        let j = winner.solution.objective;
        let results: Vec<Candidate> = e.hops.into_iter().filter_map(|(_, _, p)| p).collect();
        // The neighbourhood looks for other basins: a point of the winner's own shape
        // (`same_shape`) is the winner again, to the last digits of its solve (the
        // `periodic-qc` plan's moves end 5e-6 below it), and is not verified.
        let mut lower: Vec<Candidate> = results
            .iter()
            .filter(|c| solved(&c.solution) && c.solution.objective < j - CLUSTER_RTOL * j.abs())
            .filter(|c| !same_shape(&c.solution, &winner.solution))
            .cloned()
            .collect();
        if lower.is_empty() {
            return None;
        }
        lower = representatives(lower);
        lower
            .par_iter_mut()
            .for_each(|c| attach_verification(c, policy, j));
        // Only the new candidates are refined, each only while it stays below the winner. The
        // first refinement of a point solved on an already refined mesh says where the point
        // settles: on `periodic-cot` seed 5 two points 1.5 % below the winner refined to 0.5 %
        // above it and stayed there through five more refinements (56 s of CPU).
        lower.sort_by_key(|c| c.index);
        let records = refine_below(&mut lower, problem, settings, policy, j);
        self.refinements.extend(records);
        let mut all = std::mem::take(&mut self.candidates);
        all.append(&mut lower);
        all = representatives(all);
        all.sort_by_key(|c| c.index);
        self.candidates = all;
        // A winner found here was reached by its own solve and by the others of the
        // neighbourhood that ended in its shape; the exploration's count was another basin's.
        let chosen = self.choice().map(|i| &self.candidates[i]);
        let w = chosen.filter(|w| w.index >= first)?;
        let others = results
            .iter()
            .filter(|c| c.index != w.index && solved(&c.solution))
            .filter(|c| same_shape(&c.solution, &w.solution))
            .count();
        self.basin_hits = Some(1 + others);
        Some((j, w.solution.objective))
    }

    /// hp-refines the unverified candidates that beat the best verified one, lowest objective
    /// first, until none below the best verified objective is left (`refine_until_verified`,
    /// at most [`VerifyPolicy::clusters`] of them); nothing without verification (`rtol` 0). Runs
    /// after the exploration, so that the hops start from the problem's own mesh and only
    /// the winners are refined.
    pub fn refine_candidates(
        &mut self,
        problem: Problem,
        settings: &ProblemSettings,
        policy: &VerifyPolicy,
    ) {
        let records = refine_below(
            &mut self.candidates,
            problem,
            settings,
            policy,
            f64::INFINITY,
        );
        self.refinements.extend(records);
    }

    /// The global search's exploitation ([`global::exploit`], settings [`VerifyPolicy::hops`]
    /// seeded by the multi-start's seed): monotonic basin hopping from the best candidates,
    /// then polishing, on the candidates' own mesh. Runs only after a multi-start; hops are
    /// numbered on from its starts (their records' chain index), every distinct optimum a hop
    /// found joins the candidates, and [`Search::basin_hits`] counts the candidates and hops
    /// that ended in the best's basin (its shape: objective and phase durations within
    /// [`SHAPE_RTOL`]). Depends on the candidates' values only (not their order):
    /// shards merged explore as the unsharded run does.
    pub fn explore(
        &mut self,
        problem: Problem,
        settings: &ProblemSettings,
        policy: &VerifyPolicy,
        progress: Progress<'_>,
    ) {
        let (Some(hops), Strategy::Multistart { starts, seed }) = (policy.hops, self.strategy)
        else {
            return;
        };
        let land = OcpLandscape {
            problem,
            settings,
            policy,
            chains: Vec::new(),
            verify_samples: coarse_mesh(settings, self.strategy, policy).is_none(),
            progress,
            records: Mutex::new(Vec::new()),
        };
        self.candidates.sort_by_key(|c| c.index);
        let e = global::exploit(
            &land,
            &self.candidates,
            &HopSettings { seed, ..hops },
            starts,
        );
        self.records.extend(land.take_records());
        self.basin_hits = Some(e.hits);
        // Every distinct optimum the hops found is a candidate: the refinement that follows
        // takes them in objective order, so a winner that does not verify leaves the next.
        let found: Vec<Candidate> = e.hops.into_iter().filter_map(|(_, _, p)| p).collect();
        let mut all = std::mem::take(&mut self.candidates);
        all.extend(found);
        all = representatives(all);
        all.sort_by_key(|c| c.index);
        self.candidates = all;
    }

    /// The chosen candidate ([`select`]) with its [`OcpSolution::strategy`] record (every
    /// stage and the verification's refinements, total iterations and time; the rounds of the
    /// chosen candidate's last refinement are in [`OcpSolution::refinement`]); its problem is
    /// `None` only for candidates read from files. Errors when no chain produced a solution.
    pub fn best(mut self) -> Result<(Option<BuiltProblem>, OcpSolution), PipelineError> {
        let Some(i) = self.choice() else {
            let stages = self
                .records
                .iter()
                .map(|r| format!("{}: {}", r.chain, r.stage))
                .collect();
            return Err(PipelineError::AllChainsFailed {
                strategy: self.strategy,
                stages,
            });
        };
        let c = self.candidates.swap_remove(i);
        let mut sol = c.solution;
        let iterations = self.records.iter().map(|r| r.iterations).sum();
        sol.iterations = iterations + self.refinements.iter().map(|r| r.iterations).sum::<usize>();
        sol.solve_seconds = self.seconds;
        sol.strategy = Some(StrategyReport {
            strategy: self.strategy,
            records: self.records,
            chosen: sol.status.is_success().then_some(c.index),
            iterations,
            seconds: self.seconds,
            basin_hits: self.basin_hits,
            refinements: self.refinements,
        });
        Ok((c.problem, sol))
    }
}

#[cfg(test)]
mod tests {
    use super::{DefectProgress, LeftOptimum, VERIFIED_DEFECT, path_stalled, refine_in_order};

    /// The closed loop runs only on a plan that could be chosen (decision record 0067). The
    /// fixture is a human finger's plan, verified, executed and robust (J = 0.0505279).
    /// Above a verified plan 1 % lower it is re-integrated but not run: its defects pass, it
    /// is not verified, and its verdict says why. Within [`super::CLUSTER_RTOL`] of that plan
    /// it is the same optimum, which `select` may choose, and it is run (and robust). A
    /// refinement chain that ran it beside an earlier chain, before that chain's lower plan
    /// was in, reads once cut at that plan as the chain run after it: unexecuted, with the
    /// same record, and settling nothing.
    #[test]
    fn a_plan_that_could_not_be_chosen_is_not_run_in_closed_loop() {
        use std::time::Instant;

        use super::{
            CLUSTER_RTOL, Candidate, Execution, RefinedChain, Step, VerifyPolicy,
            attach_verification, refinement_label,
        };
        use crate::paper::closed_loop::execution_check;
        use crate::pipeline::solve::own_problem;
        use crate::pipeline::strategy::record;
        use crate::pipeline::verify::{is_robust, is_verified, verdict_failure};
        use crate::pipeline::{OcpSolution, SolutionIo};

        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let sol =
            OcpSolution::read_json(&root.join("tests/fixtures/human-plan-j0505279/solution.json"))
                .expect("the fixture reads");
        assert!(is_robust(&sol));
        let j = sol.objective;
        let policy = VerifyPolicy {
            rtol: sol.verification.as_ref().expect("verified").rtol,
            execution: Some(Execution(execution_check)),
            ..VerifyPolicy::default()
        };
        let (built, _) = own_problem(&sol).expect("the fixture's problem builds");
        let plan = Candidate {
            index: 0,
            problem: Some(built),
            solution: OcpSolution {
                verification: None,
                ..sol
            },
        };
        let lower = 0.99 * j;
        let mut above = plan.clone();
        attach_verification(&mut above, &policy, lower);
        let v = above.solution.verification.as_ref().expect("re-integrated");
        assert!(v.passes(VERIFIED_DEFECT), "defect {}", v.max_defect);
        assert!(v.execution.is_none() && v.not_executed.is_some());
        assert!(!v.verified && !is_verified(&above.solution));
        let why = verdict_failure(v).expect("a reason");
        assert!(why.contains("not run in closed loop"), "{why}");

        let same = j * (1.0 - 0.5 * CLUSTER_RTOL);
        let mut run = plan.clone();
        attach_verification(&mut run, &policy, same);
        let ran = run.solution.verification.as_ref().expect("re-integrated");
        assert!(ran.execution.is_some() && ran.not_executed.is_none());
        assert!(is_robust(&run.solution));

        let label = "refine start 0 to 1e-4".to_string();
        let chain = RefinedChain {
            start: plan,
            records: vec![record(
                0,
                refinement_label(&label, &run.solution),
                &run.solution,
                Instant::now(),
            )],
            steps: vec![Step {
                point: run.clone(),
                records: 1,
                label: label.clone(),
            }],
        };
        assert_eq!(chain.settled(same), Some(j));
        let kept = chain.clone().cut(same);
        assert!(is_robust(&kept.steps[0].point.solution));
        let cut = chain.cut(lower);
        assert_eq!(cut.settled(f64::INFINITY), None);
        assert_eq!(
            cut.records[0].stage,
            refinement_label(&label, &above.solution)
        );
        assert!(cut.records[0].stage.contains("not executed"));
        let end = cut.steps[0]
            .point
            .solution
            .verification
            .as_ref()
            .expect("kept");
        assert_eq!(
            (end.verified, &end.execution, &end.not_executed),
            (v.verified, &v.execution, &v.not_executed)
        );
    }

    /// The period continuation of the starts ([`super::hold_the_period`]) on the coarse mesh of
    /// the global search: start 9 of `periodic-cot-human` seed 5 solved plainly ends on the
    /// 10 s period bound (J ≈ 0.066, the region every start and move of that seed ended in
    /// before the continuation), held to its start's period and released it ends at a
    /// short-period optimum (≈ 2.5 s) of less than a third of that objective, off the bound:
    /// the region from which the reshaping reaches the best known optimum (J 0.0158
    /// verified). Even starts, and problems without a period row (`periodic-qc`), are not
    /// held.
    #[test]
    fn a_start_held_short_leaves_the_period_bound_that_a_plain_start_ends_on() {
        use bf_optim::ocp::Scheme;
        use bf_problem::{Problem, ProblemSettings};

        use crate::pipeline::strategy::{Strategy, prepare_chains, run_chain};

        let coarse = ProblemSettings {
            points: super::DEFAULT_COARSE.points,
            scheme: Scheme::Radau {
                elements: super::DEFAULT_COARSE.elements,
            },
            ..ProblemSettings::default()
        };
        let strategy = Strategy::Multistart {
            starts: 10,
            seed: 5,
        };
        let p = Problem::PeriodicCotHuman;
        let (target, plain) = prepare_chains(p, &coarse, strategy, None, true).expect("builds");
        let (_, tmax) =
            crate::pipeline::bounds::period_row(&target.ocp).expect("COT bounds its period");
        let mut held = plain.clone();
        super::hold_the_period(&mut held);
        for k in (0..10).step_by(2) {
            assert_eq!(held[k], plain[k]);
        }
        let start: f64 = plain[9][0].1.start.as_ref().unwrap().durations.iter().sum();
        assert_eq!(held[9].len(), 2);
        assert_eq!(held[9][0].1.period_bounds, Some((0.0, start)));
        assert_eq!(held[9][1].1.period_bounds, plain[9][0].1.period_bounds);
        // Under an upper period bound below the start's period nothing is held (the held
        // stage would loosen it).
        let mut tight = plain.clone();
        tight
            .iter_mut()
            .flatten()
            .for_each(|(_, st)| st.period_bounds = Some((0.0, 0.1)));
        let before = tight.clone();
        super::hold_the_period(&mut tight);
        assert_eq!(tight, before);

        let (_, a) = run_chain(p, 9, plain[9].clone(), None, None);
        let (recs, b) = run_chain(p, 9, held[9].clone(), None, None);
        let (a, b) = (a.expect("solves").1, b.expect("solves").1);
        assert!(a.status.is_success() && b.status.is_success());
        assert!(a.period > tmax * (1.0 - 1e-4), "plain: T {}", a.period);
        // The held stage ends on its bound, the release far below the problem's.
        assert!(recs[0].period <= start * (1.0 + 1e-6), "{:?}", recs[0]);
        assert!(b.period < 0.5 * tmax, "held: T {}", b.period);
        assert!(
            b.objective < a.objective / 3.0,
            "held J {} vs plain J {}",
            b.objective,
            a.objective
        );

        let qc = crate::pipeline::build(Problem::PeriodicQc, &coarse).expect("builds");
        assert_eq!(crate::pipeline::bounds::period_row(&qc.ocp), None);
    }

    /// Shards sample what the unsharded search samples, held starts included: the held
    /// chains keep their global start index, so the union of two shards' sampled optima and
    /// of their start records is the unsharded run's, bit for bit (`optimize merge` explores
    /// from that union). Four starts of `periodic-cot-human` (1 and 3 held), no reshaping,
    /// hops or verification, one optimum promoted.
    #[test]
    fn shards_sample_the_held_starts_as_the_unsharded_search_does() {
        use bf_problem::{Problem, ProblemSettings};

        use crate::pipeline::strategy::{Shard, Strategy};

        let policy = super::VerifyPolicy {
            rtol: 0.0,
            ..super::VerifyPolicy::default()
        }
        .global(super::HopSettings {
            budget: 0,
            polish_rounds: 0,
            reshape_width: 0,
            ..super::DEFAULT_HOPS
        });
        let policy = super::VerifyPolicy {
            coarse: Some(super::CoarseSampling {
                promote: 1,
                ..super::DEFAULT_COARSE
            }),
            ..policy
        };
        let strategy = Strategy::Multistart { starts: 4, seed: 5 };
        let run = |shard| {
            super::search(
                Problem::PeriodicCotHuman,
                &ProblemSettings::default(),
                strategy,
                shard,
                &policy,
                None,
            )
            .expect("searches")
        };
        let key = |s: &super::Search| {
            let mut v: Vec<(usize, u64, u64)> = s
                .sampled
                .iter()
                .map(|c| {
                    let o = &c.solution;
                    (c.index, o.objective.to_bits(), o.period.to_bits())
                })
                .collect();
            v.sort_unstable();
            v
        };
        let starts = |s: &super::Search| {
            let mut v: Vec<(usize, String, u64)> = s
                .records
                .iter()
                .filter(|r| !super::is_promotion(&r.stage))
                .map(|r| (r.chain, r.stage.clone(), r.objective.to_bits()))
                .collect();
            v.sort();
            v
        };
        let whole = run(Shard::WHOLE);
        let (a, b) = (
            run(Shard { index: 0, count: 2 }),
            run(Shard { index: 1, count: 2 }),
        );
        let mut union = key(&a);
        union.extend(key(&b));
        union.sort_unstable();
        assert_eq!(union, key(&whole));
        let mut recs = starts(&a);
        recs.extend(starts(&b));
        recs.sort();
        assert_eq!(recs, starts(&whole));
        // Starts 1 and 3 were held, then released.
        let released = recs
            .iter()
            .filter(|(_, st, _)| st == super::RELEASE_PERIOD_LABEL)
            .map(|(k, _, _)| *k)
            .collect::<Vec<_>>();
        assert_eq!(released, [1, 3]);
    }

    /// The refinements stop after two in a row that do not halve the lowest defect so far, on
    /// the measured sequences of `periodic-cot` seed 8 (BENCHMARKS.md, "Refinements whose
    /// defect does not fall"): a candidate stuck at 1.8e2 stops at its second refinement; one
    /// whose defect falls unevenly (0.14, 0.026, 0.037, 0.0015, 0.0010) is refined on.
    #[test]
    fn refinements_stop_when_the_defect_does_not_fall() {
        let stops = |start: f64, seq: &[f64]| {
            let mut p = DefectProgress::new(Some(start));
            seq.iter().position(|&d| p.stalled(d))
        };
        assert_eq!(stops(1.8e2, &[1.8e2, 1.8e2, 1.8e2, 1.8e2, 1.8e2]), Some(1));
        assert_eq!(
            stops(5.0e-1, &[1.4e-1, 2.6e-2, 3.7e-2, 1.5e-3, 1.0e-3]),
            None
        );
        // Non-finite defects are no progress, and a start without a defect counts as none.
        assert_eq!(stops(1.0, &[f64::NAN, f64::INFINITY]), Some(1));
        let mut p = DefectProgress::new(None);
        assert!(!p.stalled(1.0));
        assert!(!p.stalled(0.4));
    }

    /// A refinement chain leaves its optimum where its defects fail after they had verified, on
    /// the measured chains: `periodic-cot` seed 7's start 58 (2.7e-1, 6.0e-5, 9.2e-7 with its
    /// path 4.6x its allowance, then 2.0e-3 at an objective 2.8 times higher) leaves at its
    /// fourth refinement; the best candidate of `periodic-cot` seed 8 (6.2e-2, 3.1e-1,
    /// 1.5e-2, 9.3e-8) never does, nor does a chain whose re-integration fails before its
    /// defects ever verify; the `periodic-qc` tap, whose defects verify from the start,
    /// leaves at the first refinement that fails or whose re-integration does not complete.
    #[test]
    fn a_refinement_that_leaves_its_optimum_ends_the_chain() {
        // Each point: its defect, or `None` where its re-integration did not complete.
        let leaves = |start: Option<f64>, seq: &[Option<f64>]| {
            let verifies = |d: Option<f64>| d.is_some_and(|d| d <= VERIFIED_DEFECT);
            let mut l = LeftOptimum::default();
            assert!(!l.step(verifies(start)), "a start has left nothing");
            seq.iter().position(|&d| l.step(verifies(d)))
        };
        let seed_7 = [2.7e-1, 6.0e-5, 9.2e-7, 2.0e-3, 3.9e-5].map(Some);
        assert_eq!(leaves(None, &seed_7), Some(3));
        let seed_8 = [6.2e-2, 3.1e-1, 1.5e-2, 9.3e-8].map(Some);
        assert_eq!(leaves(Some(1.2e-1), &seed_8), None);
        assert_eq!(leaves(Some(1.0), &[None, Some(1e-2), Some(1e-5)]), None);
        assert_eq!(leaves(Some(1e-6), &[Some(2e-6), Some(3e-4)]), Some(1));
        assert_eq!(leaves(Some(1e-6), &[None]), Some(0));
        // The tolerance itself verifies; NaN defects fail.
        assert_eq!(leaves(Some(1e-6), &[Some(VERIFIED_DEFECT)]), None);
        assert_eq!(leaves(Some(1e-6), &[Some(f64::NAN)]), Some(0));
    }

    /// The refinements stop on a path check that does not move towards its allowance and go
    /// on while it does, on the measured sequences of path excesses (× the allowance):
    /// the `periodic-qc` tap (24.1 on the problem's mesh and refined), the
    /// `periodic-cot-human` direct solve (60.9 with failing defects, 2.1, 1.1, then verified),
    /// and a `periodic-cot` candidate (7.7, 8.8).
    #[test]
    fn refinement_stops_on_a_stuck_path_check_only() {
        assert!(path_stalled(Some(24.1), Some(24.1)));
        assert!(path_stalled(Some(7.7), Some(8.8)));
        // Failing defects before: no verdict on the path yet.
        assert!(!path_stalled(None, Some(2.1)));
        // 2.1 → 1.1 shrinks the excess beyond the allowance from 1.1 to 0.1.
        assert!(!path_stalled(Some(2.1), Some(1.1)));
        // Verified, or failing on its defects again: nothing to stop.
        assert!(!path_stalled(Some(2.1), None));
        // The rule is about the part beyond the allowance: halving it is just enough.
        assert!(!path_stalled(Some(3.0), Some(2.0)));
        assert!(path_stalled(Some(3.0), Some(2.01)));
    }

    /// A verified result ends the refinements once the next candidate is no lower than
    /// [`REFINE_BELOW`](super::REFINE_BELOW) times the best verified value; a failed one passes
    /// on to the next; at most `max` are refined. (Single-step chains: no cut.)
    #[test]
    fn refinement_moves_on_while_a_lower_candidate_is_left() {
        // (candidate value, verified value of its refinement)
        let cands = [
            (1.0, None),
            (2.0, Some(9.0)),
            (3.0, Some(2.5)),
            (4.0, Some(4.0)),
        ];
        let run = |max: usize| {
            let calls = std::sync::Mutex::new(Vec::new());
            let out = refine_in_order(
                &[0usize, 1, 2, 3],
                max,
                1,
                |&i| cands[i].0,
                |&i, _| {
                    calls.lock().unwrap().push(i);
                    cands[i].1
                },
                |v, _| *v,
                |v, _| v,
                |v| *v,
            );
            (calls.into_inner().unwrap(), out)
        };
        // 0 fails, 1 verifies at 9 (3 is below it), 2 verifies at 2.5, and 4 is not below
        // 2.5: stop.
        let (calls, out) = run(10);
        assert_eq!(calls, [0, 1, 2]);
        assert_eq!(out, [(0, None), (1, Some(9.0)), (2, Some(2.5))]);
        let (calls, _) = run(2);
        assert_eq!(calls, [0, 1]);
        let (calls, out) = run(0);
        assert!(calls.is_empty() && out.is_empty());
    }

    /// A chain of refinement steps for the tests: (objective, verified) per step, run until
    /// its first step not below the ceiling that `earlier` gives (or to its end), as
    /// `refine_until_verified` runs; `None` from `earlier` stops it.
    fn run_steps(steps: &[(f64, bool)], earlier: &dyn Fn() -> Option<f64>) -> Vec<(f64, bool)> {
        let mut out = Vec::new();
        for &step in steps {
            let Some(c) = earlier() else { break };
            out.push(step);
            if step.0 >= c {
                break;
            }
        }
        out
    }

    /// The steps up to the first not below `c` (`RefinedChain::cut`).
    fn cut_steps(mut steps: Vec<(f64, bool)>, c: f64) -> Vec<(f64, bool)> {
        if let Some(i) = steps.iter().position(|s| s.0 >= c) {
            steps.truncate(i + 1);
        }
        steps
    }

    /// The value at which the steps cut at `c` end verified (`RefinedChain::settled`).
    fn settled_steps(steps: &[(f64, bool)], c: f64) -> Option<f64> {
        cut_steps(steps.to_vec(), c)
            .last()
            .and_then(|&(v, ok)| ok.then_some(v))
    }

    /// The highest step of steps that end verified uncut (`RefinedChain::peak`).
    fn peak_steps(steps: &[(f64, bool)]) -> Option<f64> {
        let end = settled_steps(steps, f64::INFINITY)?;
        Some(steps.iter().map(|s| s.0).fold(end, f64::max))
    }

    /// Refined several at a time, the items and results are those of one after the other,
    /// each chain stopped at its first step not below the best value verified before it,
    /// however the refinements' durations order their ends: random values, chains of
    /// verified and unverified steps and durations (later items often finish first), widths
    /// 1–4, against the sequential rule written out here.
    #[test]
    fn refinements_side_by_side_return_the_sequential_result() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _case in 0..60 {
            let n = rng.random_range(0..8usize);
            let mut values: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..10.0)).collect();
            values.sort_by(f64::total_cmp);
            let chains: Vec<Vec<(f64, bool)>> = (0..n)
                .map(|_| {
                    let len = rng.random_range(1..5usize);
                    let mut c: Vec<(f64, bool)> = (0..len)
                        .map(|_| (rng.random_range(0.0..20.0), false))
                        .collect();
                    // Only a chain's last step may verify (a verified step ends it).
                    if let Some(last) = c.last_mut() {
                        last.1 = rng.random_bool(0.6);
                    }
                    c
                })
                .collect();
            let micros: Vec<u64> = (0..n).map(|_| rng.random_range(0..3000)).collect();
            let max = rng.random_range(0..10usize);
            // The rule, sequentially.
            let mut expected = Vec::new();
            let mut best = f64::INFINITY;
            for k in 0..n.min(max) {
                if values[k] >= super::REFINE_BELOW * best {
                    break;
                }
                let ran = cut_steps(chains[k].clone(), best);
                if let Some(&(v, true)) = ran.last() {
                    best = best.min(v);
                }
                expected.push((k, ran));
            }
            let order: Vec<usize> = (0..n).collect();
            for width in 1..=4 {
                let out = refine_in_order(
                    &order,
                    max,
                    width,
                    |&k| values[k],
                    |&k, earlier| {
                        let mut ran = Vec::new();
                        for &step in &chains[k] {
                            std::thread::sleep(std::time::Duration::from_micros(micros[k]));
                            let Some(c) = earlier() else { break };
                            ran.push(step);
                            if step.0 >= c {
                                break;
                            }
                        }
                        ran
                    },
                    |s: &Vec<_>, c| settled_steps(s, c),
                    cut_steps,
                    |s: &Vec<_>| peak_steps(s),
                );
                assert_eq!(out, expected, "width {width}");
            }
        }
    }

    /// A chain that rises above a value verified before it stops there: item 0 verifies at
    /// 2; item 1 (value 1.5) refines to 1.8, 2.5 (not below 2: stop) and would go on to 1.0;
    /// item 2 (value 1.9) still refines, to a verified 1.7.
    #[test]
    fn a_chain_stops_above_the_best_verified_before_it() {
        let chains = [
            vec![(2.0, true)],
            vec![(1.8, false), (2.5, false), (1.0, true)],
            vec![(1.7, true)],
        ];
        for width in [1, 2] {
            let out = refine_in_order(
                &[0usize, 1, 2],
                3,
                width,
                |&k| [1.0, 1.5, 1.9][k],
                |&k, earlier| run_steps(&chains[k], earlier),
                |s: &Vec<_>, c| settled_steps(s, c),
                cut_steps,
                |s: &Vec<_>| peak_steps(s),
            );
            assert_eq!(
                out,
                [
                    (0, vec![(2.0, true)]),
                    (1, vec![(1.8, false), (2.5, false)]),
                    (2, vec![(1.7, true)]),
                ],
                "width {width}"
            );
        }
    }

    /// A refinement started beside an earlier one is told to stop once that one's verified
    /// result rules it out, and its result is not returned. On a pool of two threads of its
    /// own, item 0 finishes only after item 1 has started, so the two run side by side
    /// whatever else the machine runs.
    #[test]
    fn a_refinement_ruled_out_by_an_earlier_result_is_stopped() {
        use std::sync::atomic::{AtomicBool, Ordering};
        use std::time::{Duration, Instant};
        let (started, stopped) = (AtomicBool::new(false), AtomicBool::new(false));
        let pool = pool_of_two();
        // Item 0 (value 1) verifies at 1.5 once item 1 runs; item 1 (value 2, not below 1.5)
        // runs until it is no longer wanted. Each waits at most 10 s.
        let out = pool.install(|| {
            refine_in_order(
                &[0usize, 1],
                2,
                2,
                |&k| [1.0, 2.0][k],
                |&k, earlier| {
                    let t0 = Instant::now();
                    if k == 0 {
                        while !started.load(Ordering::SeqCst)
                            && t0.elapsed() < Duration::from_secs(10)
                        {
                            std::thread::sleep(Duration::from_millis(1));
                        }
                        return Some(1.5);
                    }
                    started.store(true, Ordering::SeqCst);
                    while t0.elapsed() < Duration::from_secs(10) {
                        if earlier().is_none() {
                            stopped.store(true, Ordering::SeqCst);
                            return Some(0.1);
                        }
                        std::thread::sleep(Duration::from_millis(1));
                    }
                    None
                },
                |v, _| *v,
                |v, _| v,
                |v| *v,
            )
        });
        assert_eq!(out, [(0, Some(1.5))]);
        assert!(started.load(Ordering::SeqCst) && stopped.load(Ordering::SeqCst));
    }

    /// A chain that `earlier` rules out while its refinement solves stops inside that solve
    /// and returns nothing: `earlier` allows the attempt and the solve's first iteration, then
    /// rules the chain out, and is asked once more after the stopped solve. The fixture is a
    /// `periodic-cot` plan whose first refinement, unstopped, takes about 25 times as long.
    #[test]
    fn a_chain_ruled_out_inside_its_solve_stops_there() {
        use std::cell::Cell;

        use super::{Candidate, VerifyPolicy, refine_until_verified};
        use crate::pipeline::refine::current_mesh;
        use crate::pipeline::solve::{own_problem, settings_of};
        use crate::pipeline::{OcpSolution, SolutionIo};
        use bf_problem::ProblemSettings;

        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let sol =
            OcpSolution::read_json(&root.join("tests/fixtures/rising-cot-plan/solution.json"))
                .expect("the fixture reads");
        let (problem, settings) = settings_of(&sol).expect("the fixture's settings");
        let (built, _) = own_problem(&sol).expect("the fixture's problem builds");
        let settings = ProblemSettings {
            mesh: Some(current_mesh(&built).expect("a Radau mesh")),
            ..settings
        };
        let start = Candidate {
            index: 0,
            problem: Some(built),
            solution: OcpSolution {
                verification: None,
                ..sol
            },
        };
        let calls = Cell::new(0usize);
        let earlier = || {
            calls.set(calls.get() + 1);
            (calls.get() <= 2).then_some(f64::INFINITY)
        };
        let policy = VerifyPolicy::default();
        let chain =
            refine_until_verified(problem, &settings, start, &policy, f64::INFINITY, &earlier);
        assert!(chain.steps.is_empty() && chain.records.is_empty());
        // Before the attempt, at the first and second iterations (the stop), and after.
        assert_eq!(calls.get(), 4);
    }

    /// A rayon pool of two threads of its own, so that two refinements run side by side
    /// whatever else the machine runs.
    fn pool_of_two() -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap()
    }

    /// A result finished behind a refinement still running rules out the items above its
    /// peak: item 0 (value 1) runs until well after item 1 (value 2) has verified at 2.5, and
    /// item 2 (value 3, not below 2.5) is never started, although nothing before it is
    /// settled while item 0 runs; the result is the sequential one (item 0 fails).
    #[test]
    fn a_result_behind_a_running_refinement_rules_out_the_items_above_it() {
        use std::sync::atomic::{AtomicBool, Ordering};
        use std::time::{Duration, Instant};
        let one_done = AtomicBool::new(false);
        let calls = std::sync::Mutex::new(Vec::new());
        let pool = pool_of_two();
        let out = pool.install(|| {
            refine_in_order(
                &[0usize, 1, 2],
                3,
                2,
                |&k| [1.0, 2.0, 3.0][k],
                |&k, _| {
                    calls.lock().unwrap().push(k);
                    match k {
                        0 => {
                            let t0 = Instant::now();
                            while !one_done.load(Ordering::SeqCst)
                                && t0.elapsed() < Duration::from_secs(10)
                            {
                                std::thread::sleep(Duration::from_millis(1));
                            }
                            // Time for the other worker to hand out item 2 if it would.
                            std::thread::sleep(Duration::from_millis(100));
                            None
                        }
                        1 => {
                            one_done.store(true, Ordering::SeqCst);
                            Some(2.5)
                        }
                        _ => Some(0.5),
                    }
                },
                |v, _| *v,
                |v, _| v,
                |v| *v,
            )
        });
        assert_eq!(out, [(0, None), (1, Some(2.5))]);
        let mut calls = calls.into_inner().unwrap();
        calls.sort_unstable();
        assert_eq!(calls, [0, 1]);
    }
}
