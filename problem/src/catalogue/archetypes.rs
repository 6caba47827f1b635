//! The archetypes of the catalogue, one function each: the periodic rotation (free–stick–free,
//! Sect. 6.1, QC eq. 64–65 or COT eq. 61–63 ratio objective eq. 60), reaching the ball (free),
//! and the free–stick problems (reorient, rotate at a reference velocity, rotate fast;
//! Sect. 4.1). Each returns a `Spec`: its phases, cost integrands, objective, point
//! functions (impact law eq. 40, Sect. 7 touch-down tolerances, continuity, periodicity,
//! horizons) and parameters.

use bf_codegen::Scene;
use bf_codegen::graph::Graph;
use bf_optim::ocp::{Objective, Param, PointFunction, Scheme, VarRef};

use super::guess::PhaseDef;
use super::{COT_MAX_PERIOD, Problem, ProblemSettings, max_phase_duration};
use crate::ProblemError;
use crate::node::{CostKind, PhaseMode, Physics};
use crate::points::{EndQuantity, continuity, end_point, impact};

/// Tolerance on h at the touch-down and the release, in ball radii (Sect. 7 work-arounds):
/// 0.1 mm on the paper's ball of 1 m. Relative, so that a finger drawn at another scale poses
/// the same problem (BENCHMARKS.md, "The plan for the plant in ball radii").
const TOL_H: f64 = 1e-4;
/// Share of the approach over which its clearance (`ProblemSettings::approach_clearance`) falls
/// to 0 before the impact: the approach may close the last of the gap only then. 1 % of the
/// human finger's 7.4 s approach is 74 ms, about the ramp of the hybrid controller's clearance
/// guard (50 ms); with 10 % its Newton plan still swept past the ball within a fraction of a
/// millimetre 0.16 s before its impact, where the controller's plant struck it
/// (docs/decisions/0040-touch-check-and-the-default-plan.md).
const APPROACH_CLEARANCE_RAMP: f64 = 0.01;

/// The shape of a problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Archetype {
    /// Free–stick–free, periodic.
    Periodic,
    /// One free phase from rest to touching the ball.
    Reach,
    /// Free then stick, from rest.
    FreeStick,
}

/// What an archetype function reads.
pub(crate) struct Context<'a> {
    pub(crate) problem: Problem,
    pub(crate) scene: &'a Scene,
    pub(crate) physics: &'a Physics,
    pub(crate) eps: f64,
    pub(crate) settings: &'a ProblemSettings,
    /// q⁰, the configuration of the default guess ([`super::guess::GuessConfigurations::free`]).
    pub(crate) q_guess: &'a [f64],
}

/// What an archetype function builds.
pub(crate) struct Spec {
    pub(crate) phases: Vec<PhaseDef>,
    pub(crate) cost: CostKind,
    pub(crate) objective: Objective,
    pub(crate) points: Vec<PointFunction>,
    pub(crate) params: Vec<Param>,
    pub(crate) cost_bounds: Vec<(f64, f64)>,
    /// Joint bounds of the states: the scene's joint limits (±∞ where it gives none).
    pub(crate) q_limits: Vec<(f64, f64)>,
}

impl Context<'_> {
    fn nq(&self) -> usize {
        self.physics.nq
    }

    fn nx(&self) -> usize {
        2 * self.physics.nq + 3
    }

    /// [`TOL_H`] in metres.
    fn tol_h(&self) -> f64 {
        TOL_H * self.physics.radius
    }

    fn q_limits(&self) -> Vec<(f64, f64)> {
        self.physics.q_limits.clone()
    }

    /// The state at rest in the default guess's configuration.
    fn x_rest(&self) -> Vec<f64> {
        let nq = self.nq();
        let mut x = vec![0.0; self.nx()];
        x[..nq].copy_from_slice(self.q_guess);
        x
    }
}

/// The impact impulse ι (eq. 40) as three parameters; a redundant finger's Newton plan adds
/// the plant's post-impact velocity q̇_N (`qd_newton1..N`) and impulse ι_N (`iota_newton1..3`)
/// ([`crate::points::impact`]).
fn iota_params(c: &Context<'_>) -> Vec<Param> {
    let param = |name: String| Param {
        name,
        lower: -1e3,
        upper: 1e3,
        guess: 0.0,
    };
    let mut params: Vec<Param> = (0..3).map(|i| param(format!("iota{}", i + 1))).collect();
    if c.settings.impact_law == crate::solution::PlannedImpact::Newton {
        params.extend(
            crate::points::newton_lifted_param_names(c.nq())
                .into_iter()
                .map(param),
        );
    }
    params
}

/// Free–stick–free periodic rotation with the QC or COT ratio objective (Sect. 6.1); with
/// [`ProblemSettings::replan`] its transient from a measured lift-off state
/// ([`periodic_from_lift_off`]).
pub(crate) fn periodic(c: &Context<'_>) -> Result<Spec, ProblemError> {
    if let Some(r) = &c.settings.replan {
        return periodic_from_lift_off(c, r);
    }
    let p = PeriodicParts::of(c)?;
    let mut points = apex(c, 0)?;
    points.extend(contact_sequence(c, 0)?);
    points.extend(stick_end(c)?);
    points.push(continuity(c.nx(), 1, 2, "stick -> free continuity"));
    points.push(continuity(c.nx(), 2, 0, "periodicity"));
    Ok(p.spec(c, |p| vec![p.approach, p.stick, p.release], points))
}

/// The transient period of a re-plan (module `replan` of the catalogue): the periodic
/// problem's phases in the order the plant meets them after a lift-off — release (free,
/// h ≥ −tol_h), approach (free, h ≥ 0, from the apex ḣ = 0 with h ≥ 0.3 r), stick — with
/// the release's first state fixed to the measured lift-off state and the stick phase's last
/// state fixed to the periodic optimum's lift-off state, so the plan ends on the periodic
/// orbit. The same objective (the ratio over the three phases, one period's worth) and the
/// same constraints as the periodic problem otherwise; the stick end's Δv = 0 row is left out,
/// as the fixed final state (where Δv = 0) implies it and the duplicate would make the
/// constraint Jacobian rank deficient. Started from the optimum's own lift-off state its
/// feasible set is the periodic problem's restricted to that lift-off state, which holds the
/// optimum: the re-plan is the optimum with its phases rotated.
pub(crate) fn periodic_from_lift_off(
    c: &Context<'_>,
    r: &super::replan::LiftOff,
) -> Result<Spec, ProblemError> {
    r.validate(c.nx())?;
    let p = PeriodicParts::of(c)?;
    let mut points = vec![fixed_state(
        0,
        false,
        &r.measured,
        super::replan::MEASURED_ROWS,
    )];
    points.extend(apex(c, 1)?);
    points.extend(contact_sequence(c, 1)?);
    points.push(fixed_state(
        2,
        true,
        &r.target,
        "ends on the periodic lift-off state",
    ));
    points.push(continuity(c.nx(), 0, 1, "release -> approach continuity"));
    Ok(p.spec(c, |p| vec![p.release, p.approach, p.stick], points))
}

/// The three phases of a periodic problem, which [`PeriodicParts::spec`] puts in order.
struct PeriodicPhases {
    approach: PhaseDef,
    stick: PhaseDef,
    release: PhaseDef,
}

/// What the periodic problem and its re-plan share: the three phases, the cost, the period
/// row and the cost bounds; [`PeriodicParts::spec`] makes a problem of them.
struct PeriodicParts {
    phases: PeriodicPhases,
    cost: CostKind,
    period_row: Option<PointFunction>,
    cost_bounds: Vec<(f64, f64)>,
}

impl PeriodicParts {
    /// The problem of `points` (the period row appended) over the phases `order` takes from
    /// these parts: the ratio objective over one period, the impact impulse as parameters.
    fn spec(
        self,
        c: &Context<'_>,
        order: impl FnOnce(PeriodicPhases) -> Vec<PhaseDef>,
        mut points: Vec<PointFunction>,
    ) -> Spec {
        points.extend(self.period_row);
        Spec {
            phases: order(self.phases),
            cost: self.cost,
            objective: Objective::Ratio(0, 1),
            points,
            params: iota_params(c),
            cost_bounds: self.cost_bounds,
            q_limits: c.q_limits(),
        }
    }

    fn of(c: &Context<'_>) -> Result<PeriodicParts, ProblemError> {
        let settings = c.settings;
        let qc = c.problem == Problem::PeriodicQc;
        let margin = settings.hdot_margin;
        // Phase durations: ≤ 5 s for QC (its optimum has a short period); for COT only the
        // total period is bounded (≤ COT_MAX_PERIOD). `min_stick` is below it
        // (`check_settings`).
        let tmax = max_phase_duration(c.problem);
        let approach = PhaseDef {
            mode: PhaseMode::Free,
            h: Some((0.0, f64::INFINITY)),
            hdot: margin.map(|m| (f64::NEG_INFINITY, -m)),
            duration: (0.01, tmax),
            guess_duration: 1.0,
            clearance: Some((settings.approach_clearance, APPROACH_CLEARANCE_RAMP)),
        };
        let stick = PhaseDef {
            mode: PhaseMode::Stick,
            h: None,
            hdot: None,
            duration: (settings.min_stick, tmax),
            guess_duration: 1.0,
            clearance: None,
        };
        let release = PhaseDef {
            mode: PhaseMode::Free,
            h: Some((-c.tol_h(), f64::INFINITY)),
            hdot: margin.map(|m| (m, f64::INFINITY)),
            duration: (0.01, tmax),
            guess_duration: 1.0,
            clearance: None,
        };
        let cost = if qc {
            CostKind::Qc {
                w: settings.effort_scale,
                omega_ref: super::QC_OMEGA_REF,
            }
        } else {
            let s = std::f64::consts::FRAC_1_SQRT_2;
            CostKind::Cot {
                w: 10.0,
                omega_hat: [s, -s, 0.0],
            }
        };
        // COT bounds the period; for QC the duration bounds imply 0.03 ≤ T ≤ 15 s, and the
        // row is only added when `period_bounds` is given (a continuation gives it in every
        // stage, so all stages share one NLP layout for primal-dual warm starts). An inactive
        // row is not free: it changes the barrier path and with it the iterations.
        let (plo, phi) = if qc {
            (0.03, 3.0 * tmax)
        } else {
            (0.0, COT_MAX_PERIOD)
        };
        let (plo, phi) = match settings.period_bounds {
            Some((lo, hi)) => (lo.max(plo), hi.min(phi)),
            None => (plo, phi),
        };
        if !(plo <= phi && plo.is_finite() && phi.is_finite()) {
            return Err(ProblemError::PeriodBounds {
                lower: plo,
                upper: phi,
            });
        }
        let period_row = (!qc || settings.period_bounds.is_some()).then(|| {
            duration_sum(
                3,
                plo,
                phi,
                if qc {
                    "period bounds"
                } else {
                    "period <= 10 s"
                },
            )
        });
        // COT: the rotation measure must stay positive for the ratio to be meaningful.
        let cost_bounds = if qc {
            vec![]
        } else {
            vec![(f64::NEG_INFINITY, f64::INFINITY), (1e-3, f64::INFINITY)]
        };
        Ok(PeriodicParts {
            phases: PeriodicPhases {
                approach,
                stick,
                release,
            },
            cost,
            period_row,
            cost_bounds,
        })
    }
}

/// The apex rows at the start of the approach phase `phase`: h ≥ 0.3 r and ḣ = 0.
fn apex(c: &Context<'_>, phase: usize) -> Result<Vec<PointFunction>, ProblemError> {
    Ok(vec![
        end_point(
            c.scene,
            c.eps,
            phase,
            false,
            EndQuantity::H(0.3 * c.physics.radius, f64::INFINITY),
            "h(0) >= 0.3 r",
        )?,
        // The period may start anywhere on the free arc with h ≥ 0.3 r: a continuum of
        // equivalent optima (a flat direction that stalls Newton's method). Starting at
        // the arc's apex (ḣ(0) = 0) picks one without changing the optimal value, since
        // the apex is where h is largest.
        end_point(
            c.scene,
            c.eps,
            phase,
            false,
            EndQuantity::HDot(0.0, 0.0),
            "apex start: hdot(0) = 0",
        )?,
    ])
}

/// From rest at q⁰ to touching the ball at rest, minimising time plus effort.
pub(crate) fn reach(c: &Context<'_>) -> Result<Spec, ProblemError> {
    let nq = c.nq();
    let phases = vec![PhaseDef {
        mode: PhaseMode::Free,
        h: Some((0.0, f64::INFINITY)),
        hdot: None,
        duration: (0.05, 10.0),
        guess_duration: 1.0,
        clearance: None,
    }];
    let points = vec![
        initial_state(&c.x_rest()),
        end_point(
            c.scene,
            c.eps,
            0,
            true,
            EndQuantity::H(0.0, c.tol_h()),
            "touch: 0 <= h(tf) <= 1e-4 r",
        )?,
        final_zero(0, &(nq..2 * nq).collect::<Vec<_>>(), "at rest at tf"),
    ];
    Ok(Spec {
        phases,
        cost: CostKind::TimeEffort { w: 1.0 },
        objective: Objective::Cost(0),
        points,
        params: vec![],
        cost_bounds: vec![],
        q_limits: c.q_limits(),
    })
}

/// Free approach, impact, stick: reorient the ball by 90° (`reorient`), track ω_ref over 3 s
/// (`rotate-ref`) or spin it as fast as possible over 2 s (`rotate-fast`).
pub(crate) fn free_stick(c: &Context<'_>) -> Result<Spec, ProblemError> {
    let phases = vec![
        PhaseDef {
            mode: PhaseMode::Free,
            h: Some((0.0, f64::INFINITY)),
            hdot: None,
            duration: (0.05, 5.0),
            guess_duration: 1.0,
            clearance: None,
        },
        // |h| ≤ tol_h at the stick nodes: Δv = 0 (or its rate) alone let h drift when the
        // contact point slides over the smoothed fingertip (sat, eq. 58–59), and the
        // fixed-horizon spinning problems exploited it (the finger ended inside the ball).
        PhaseDef {
            mode: PhaseMode::Stick,
            h: Some((-c.tol_h(), c.tol_h())),
            hdot: None,
            duration: (0.05, 5.0),
            guess_duration: 1.0,
            clearance: None,
        },
    ];
    let mut points = vec![initial_state(&c.x_rest())];
    points.extend(contact_sequence(c, 0)?);
    points.extend(stick_end(c)?);
    let z = [0.0, 0.0, 1.0];
    let (cost, cost_bounds) = match c.problem {
        Problem::Reorient => {
            let th = std::f64::consts::FRAC_PI_2;
            points.push(duration_sum(2, 0.1, 10.0, "total time <= 10 s"));
            (
                CostKind::Reorient { w: 0.1, axis: z },
                vec![(f64::NEG_INFINITY, f64::INFINITY), (th, th)],
            )
        }
        Problem::RotateRef => {
            points.push(duration_sum(2, 3.0, 3.0, "horizon = 3 s"));
            (
                CostKind::Track {
                    w: 0.1,
                    omega_ref: z,
                },
                vec![],
            )
        }
        _ => {
            points.push(duration_sum(2, 2.0, 2.0, "horizon = 2 s"));
            (CostKind::Spin { w: 0.01, axis: z }, vec![])
        }
    };
    Ok(Spec {
        phases,
        cost,
        objective: Objective::Cost(0),
        points,
        params: iota_params(c),
        cost_bounds,
        q_limits: c.q_limits(),
    })
}

/// The point constraints of a free → stick switch at the end of phase `approach`: touch
/// (0 ≤ h(t_f) ≤ [`TOL_H`] r, Sect. 7) and the sticking impact law (eq. 40) with the impulse ι as
/// parameters. With Radau the callers add the stick constraint Δv = 0 at the end of the stick
/// phase, which the Radau points do not include (the re-plan fixes that state instead).
///
/// With Legendre–Gauss the stick phases impose d(Δv)/dt = 0 at the Gauss nodes
/// ([`crate::node::StickLevel::Acceleration`]) and the impact imposes Δv⁺ = 0 (eq. 40c) at the start, so
/// Δv = 0 at the quadrature end point holds up to the Gauss quadrature error (exactly when Δv
/// is linear in the state); imposing it again would make the constraint Jacobian (nearly) rank
/// deficient.
fn contact_sequence(c: &Context<'_>, approach: usize) -> Result<Vec<PointFunction>, ProblemError> {
    let (scene, eps, settings) = (c.scene, c.eps, c.settings);
    let lg = settings.scheme == Scheme::Lg;
    Ok(vec![
        end_point(
            scene,
            eps,
            approach,
            true,
            EndQuantity::H(0.0, c.tol_h()),
            "0 <= h1(tf) <= 1e-4 r",
        )?,
        impact(
            scene,
            c.physics,
            eps,
            approach,
            0,
            settings.impulse_cone,
            settings.impact_law == crate::solution::PlannedImpact::Newton,
            lg,
        )?,
    ])
}

/// Δv = 0 at the end of stick phase 1 (Radau only, see [`contact_sequence`]).
fn stick_end(c: &Context<'_>) -> Result<Option<PointFunction>, ProblemError> {
    if c.settings.scheme == Scheme::Lg {
        return Ok(None);
    }
    Ok(Some(end_point(
        c.scene,
        c.eps,
        1,
        true,
        EndQuantity::DeltaV,
        "stick end: delta v = 0",
    )?))
}

fn duration_sum(nphases: usize, lo: f64, hi: f64, name: &str) -> PointFunction {
    let mut g = Graph::new();
    let v: Vec<_> = (0..nphases as u32).map(|i| g.var(i)).collect();
    let s = g.sum(&v);
    PointFunction {
        name: name.into(),
        graph: g,
        vars: (0..nphases)
            .map(|i| (i as u32, VarRef::Duration(i)))
            .collect(),
        fixed: vec![],
        outputs: vec![s],
        bounds: vec![(lo, hi)],
        row_names: Vec::new(),
    }
}

/// Fixes x(0) of phase 0 to `x0`.
fn initial_state(x0: &[f64]) -> PointFunction {
    fixed_state(0, false, x0, "initial state")
}

/// Fixes the first (`fin` false) or last state of `phase` to `x`.
fn fixed_state(phase: usize, fin: bool, x: &[f64], name: &str) -> PointFunction {
    let mut g = Graph::new();
    let v: Vec<_> = (0..x.len() as u32).map(|i| g.var(i)).collect();
    PointFunction {
        name: name.into(),
        graph: g,
        vars: (0..x.len())
            .map(|i| {
                let r = if fin {
                    VarRef::Final { phase, i }
                } else {
                    VarRef::Initial { phase, i }
                };
                (i as u32, r)
            })
            .collect(),
        fixed: vec![],
        outputs: v,
        bounds: x.iter().map(|&v| (v, v)).collect(),
        row_names: Vec::new(),
    }
}

/// Fixes components `idx` of the final state of `phase` to 0.
fn final_zero(phase: usize, idx: &[usize], name: &str) -> PointFunction {
    let mut g = Graph::new();
    let v: Vec<_> = (0..idx.len() as u32).map(|i| g.var(i)).collect();
    PointFunction {
        name: name.into(),
        graph: g,
        vars: idx
            .iter()
            .enumerate()
            .map(|(k, &i)| (k as u32, VarRef::Final { phase, i }))
            .collect(),
        fixed: vec![],
        outputs: v,
        bounds: vec![(0.0, 0.0); idx.len()],
        row_names: Vec::new(),
    }
}
