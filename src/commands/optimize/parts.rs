//! Options that shape a part only some problems have (an impact, a stick phase, a periodic
//! approach, a ball at all, a search over starts, an arm's point-to-point motion). A problem
//! without the part refuses the option by name (exit status 2): accepted, it would be
//! recorded in `solution.json` as if it had shaped the plan. One table says what each option
//! shapes and one query what each problem has, so that a new option or problem is added in
//! one place.

use crate::cli::OptimizeArgs;
use crate::errors::bail_usage;
use anyhow::Result;
use bf_problem::Problem;
use bf_problem::arm::REACH_ARM;

/// A part of a problem that some options shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Part {
    /// A ball the finger acts on (every catalogue problem).
    Ball,
    /// An impact on the ball (every catalogue problem but `reach`).
    Impact,
    /// A stick phase, whose friction cone leaves a margin (as [`Part::Impact`]).
    StickPhase,
    /// A periodic approach to the ball (the periodic problems).
    PeriodicApproach,
    /// A stick phase of free duration (the periodic problems).
    FreeStick,
    /// A search over starts, hops and hp rounds (every catalogue problem).
    Search,
    /// An arm's point-to-point motion (`reach-arm`).
    ArmMotion,
}

/// The problem `optimize` poses: one of the catalogue (a finger and a ball) or `reach-arm`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Posed {
    /// A catalogue problem.
    Catalogue(Problem),
    /// `reach-arm`: an arm without a ball, one direct Radau solve.
    ReachArm,
}

impl Posed {
    /// Why this problem has no `part`, completing "--problem NAME …"; `None` when it has it.
    fn lacks(self, part: Part) -> Option<&'static str> {
        match self {
            Posed::ReachArm => match part {
                Part::ArmMotion => None,
                Part::Search => Some("is one direct Radau solve"),
                _ => Some("moves an arm without a ball"),
            },
            Posed::Catalogue(p) => match part {
                Part::Ball | Part::Search => None,
                Part::Impact if !p.has_impact() => Some("has no impact"),
                Part::StickPhase if !p.has_impact() => Some("has no stick phase"),
                Part::PeriodicApproach if !p.is_periodic() => Some("has no periodic approach"),
                Part::FreeStick if !p.is_periodic() => Some("has no stick phase of free duration"),
                Part::ArmMotion => {
                    Some("moves a finger on a ball (only --problem reach-arm takes it)")
                }
                _ => None,
            },
        }
    }

    fn name(self) -> &'static str {
        match self {
            Posed::Catalogue(p) => p.name(),
            Posed::ReachArm => REACH_ARM,
        }
    }
}

/// Every option that shapes a part only some problems have, whether it was given, and the
/// part. Given at its default value, an option is still given.
fn part_options(args: &OptimizeArgs) -> [(&'static str, bool, Part); 27] {
    [
        ("--impact-law", args.impact_law.is_some(), Part::Impact),
        ("--impulse-cone", args.impulse_cone, Part::Impact),
        (
            "--cone-margin",
            args.cone_margin.is_some(),
            Part::StickPhase,
        ),
        (
            "--approach-clearance",
            args.approach_clearance.is_some(),
            Part::PeriodicApproach,
        ),
        ("--min-stick", args.min_stick.is_some(), Part::FreeStick),
        ("--torque-margin", args.torque_margin.is_some(), Part::Ball),
        ("--epsilon", args.epsilon.is_some(), Part::Ball),
        ("--strategy", args.strategy.is_some(), Part::Search),
        ("--starts", args.starts.is_some(), Part::Search),
        ("--seed", args.seed.is_some(), Part::Search),
        ("--shard", args.shard.is_some(), Part::Search),
        ("--refine", args.refine.is_some(), Part::Search),
        (
            "--refine-rounds",
            args.refine_rounds.is_some(),
            Part::Search,
        ),
        ("--hops", args.hops.is_some(), Part::Search),
        ("--hop-scale", args.hop_scale.is_some(), Part::Search),
        ("--warm-start", args.warm_start.is_some(), Part::Search),
        (
            "--dual-regularization",
            args.dual_regularization.is_some(),
            Part::Search,
        ),
        (
            "--kkt-residual-ratio",
            args.kkt_residual_ratio,
            Part::Search,
        ),
        (
            "--curvature-extrapolation",
            args.curvature_extrapolation.is_some(),
            Part::Search,
        ),
        (
            "--extrapolate-every-barrier",
            args.extrapolate_every_barrier,
            Part::Search,
        ),
        (
            "--proximal-weight",
            args.proximal_weight.is_some(),
            Part::Search,
        ),
        ("--start", args.start.is_some(), Part::ArmMotion),
        ("--target", args.target.is_some(), Part::ArmMotion),
        (
            "--effort-weight",
            args.effort_weight.is_some(),
            Part::ArmMotion,
        ),
        (
            "--acceleration-weight",
            args.acceleration_weight.is_some(),
            Part::ArmMotion,
        ),
        ("--duration", args.duration.is_some(), Part::ArmMotion),
        ("--torque-hull", args.torque_hull.is_some(), Part::ArmMotion),
    ]
}

/// Refuse (exit status 2) the first given option that shapes a part `posed` lacks, naming the
/// option, the problem and what it lacks.
pub(super) fn refuse_missing_parts(args: &OptimizeArgs, posed: Posed) -> Result<()> {
    for (opt, given, part) in part_options(args) {
        if let Some(why) = posed.lacks(part).filter(|_| given) {
            bail_usage!("{opt}: --problem {} {why}", posed.name());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every part is had by some problem and lacked by another, so no option is refused
    /// everywhere or nowhere.
    #[test]
    fn every_part_is_had_by_some_problem_and_lacked_by_another() {
        let posed: Vec<Posed> = Problem::ALL
            .iter()
            .map(|&p| Posed::Catalogue(p))
            .chain([Posed::ReachArm])
            .collect();
        for part in [
            Part::Ball,
            Part::Impact,
            Part::StickPhase,
            Part::PeriodicApproach,
            Part::FreeStick,
            Part::Search,
            Part::ArmMotion,
        ] {
            let had = posed.iter().filter(|p| p.lacks(part).is_none()).count();
            assert!(had > 0 && had < posed.len(), "{part:?}: had by {had}");
        }
    }
}
