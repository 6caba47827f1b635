//! [`HybridController`]: the feedback law that executes an optimum in the hybrid model.
//!
//! **Timing by events.** The controller keeps a reference phase and the plant time it began.
//! The plant's impact (Free → Stick/Slip, the h = 0 guard of eq. 50) starts the next contact
//! phase of the reference, its lift-off (λ_n = 0, eq. 48) the next free phase, whatever the
//! clock says; a free phase that lasts longer than planned continues at the planned
//! pre-impact velocity ([`crate::reference`]), and an early plant switches to the contact law
//! at once.
//!
//! **Approach re-timed by the gap.** Over the last t_a of a free phase before a planned
//! impact (where the planned gap h*(s) falls at half the impact's rate or faster) the reference is indexed by the measured gap h
//! (eq. 4), not by the clock: σ solves h*(σ) = h, and the free law tracks q*(σ), q̇*(σ) with
//! the feed-forward q̈*(σ) σ̇, σ̇ = ḣ / ḣ*(σ). The planned velocity is then a field over the
//! path, so a late or early plant meets the planned impact state (q*(T), q̇*(T)) at h = 0
//! instead of chasing the clock (which leaves a velocity error of order δ ω_n / e for a delay
//! δ). On the controller's model the error dynamics follow: e = q*(σ) − q has no component
//! that changes h (h(q*(σ)) = h), so with e_v = q̇*(σ) − q̇, ė = P e_v (P projects along
//! q̇* onto the level set of h) and ė_v = −K_d e_v − K_p e: the velocity error along the path
//! decays as e^{−2ζω_n t}, the cross-path error as in the clock-timed law. A plant above the
//! window's top when its clock is past it (late) is re-timed on the tangent of h* there; one
//! that reaches the top up to a window's length early is re-timed from then on.
//!
//! **Free phases:** computed torque ([`ComputedTorque`], [`InverseDynamics`]):
//! τ = ID(q, q̇, q̈* + K_d (q̇* − q̇) + K_p (q* − q)) + μ_v q̇, with a clearance guard
//! ([`Clearance`]): away from the planned contacts the gap h (eq. 4) is kept above a floor
//! h_f that rises from 0 to h_c over t_r after a lift-off and falls back to 0 over t_c before
//! the planned impact; below the floor the torque J_cᵀ n β (a push along the normal at the
//! contact point, least in the M_f⁻¹ norm) raises ḧ to ω_n² (h_f − h) + 2 ω_n (ḣ_f − ḣ). A
//! lift-off leaves the ball at ḣ = 0 (λ_n falls to 0 with the velocity continuous), so the
//! floor's rate ḣ_f = h_c / t_r is what asks the finger to leave: without it a plant whose
//! links are heavier than the model falls back onto the ball within a microsecond, which the
//! timing by events takes for the next impact. The optima's
//! path constraint h ≥ 0 holds at their nodes only, and a plan that passes the ball within a
//! millimetre (the human finger's COT optimum, 86 ms after lift-off) would otherwise be
//! tracked into an unplanned impact, which starts the next contact phase a period early.
//!
//! **Contact phases (Stick, Slip):** hybrid force/velocity control through the contact force.
//! The force on the finger is commanded as λ_cmd = λ_n,cmd n + λ_∥,cmd:
//! * normal: λ_n,cmd = λ_n*(s) + k_f ∫(λ_n* − λ_n) dt, the integral of the *measured* force
//!   error (what [`bf_sim::Input::observe`] reports after each accepted step), updated
//!   semi-implicitly (ΔI = e Δt / (1 + k_f Δt), stable for any step Δt); after the planned end
//!   of the phase −`lift_off_share` · max λ_n*, so the finger lets go;
//! * tangential: the ball's equation (eq. 29b) I_b ω̇ = −ω × I_b ω − D ω − r_c × λ fixes the
//!   component of λ normal to r_c that gives ω̇_cmd = ω̇* + k_ω (ω* + δ + ω_r − ω):
//!   λ_∥ = (m × r_c)/‖r_c‖², m = −ω × I_b ω − D ω − I_b ω̇_cmd, then limited to
//!   ‖λ_∥‖ ≤ (1 − margin) μ_s λ_n,cmd (eq. 18–19 with a margin);
//! * the contact point: ω_r = k_r r_c × e / ‖r_c‖², e the tangential part of r_c* − r_c,
//!   rolls the ball so that the contact point returns to the planned one (‖e‖ decays at the
//!   rate k_r where the contact is at the fingertip, ṙ_c = ω × r_c). Sticking keeps the ball's
//!   spin about n (no contact force has a moment about it), so ω ⊥ r_c at lift-off as planned
//!   only if r_c is the planned one: a contact point displaced by the slip after an impact
//!   would otherwise stay displaced through the stick phase and send the ball off with the
//!   wrong ω (on the human finger's COT optimum 5 % of ‖ω̄*‖ in every period); the target
//!   is r_c* moved by the roll the outer loop's offset causes, (δ × r_c*) ∫w (below);
//! * the finger's acceleration keeps the contact: from d/dt Δv = ω̇ × r_c + ω × ṙ_c − J̇_c q̇ −
//!   J_c q̈ = −k_s Δv, J_c q̈ = ω̇ × r_c + ω × ṙ_c − J̇_c q̇ + k_s Δv with ω̇ the ball's response
//!   to λ_cmd; in Stick Δv = 0 and this is the sticking constraint (eq. 27–28), after a slip it
//!   drives the relative velocity back to zero (slip recovery); q̈ is the acceleration
//!   closest to the free law's command (computed torque on q*) that meets it (Gauss's least
//!   constraint, `LeastConstraint`), so a finger motion that does not move the contact point
//!   (J_c singular: joint 1's axis through it) follows q* instead of 1/σ_min(J_c);
//! * τ = M q̈ + C q̇ + g + μ_v q̇ − J_cᵀ λ_cmd (eq. 29a solved for τ). On the controller's own
//!   model in Stick, the plant's λ (eq. 33) under this τ is exactly λ_cmd.
//!
//! **Torque bounds** ([`HybridController::with_torque_bound`]): the commanded τ is saturated at
//! the actuators' bounds |τ_i| ≤ τ_max,i. Before that the law keeps its planned part and
//! scales the feedback: τ is affine in the commanded force and relative acceleration (in q̈
//! in free phases), so τ_ff + α (τ_cmd − τ_ff) with the largest α ∈ [0, 1] inside the bounds
//! keeps the correction's direction, τ_ff being the planned force λ* with Δv̇ = 0 (or
//! ID(q, q̇, q̈*)); clipping joint by joint would change the contact force in uncontrolled
//! ways. The normal-force integral is not updated at a
//! step where the law asks for more than the bounds (conditional integration: the integral
//! would otherwise wind up against an error only more torque could remove). The outer loop's
//! offset is bounded by itself (below).
//!
//! **Outer loop:** at the end of each period (when the reference wraps to its first phase) the
//! measured mean ω̄ of that period corrects one of two levers: the length of the next flights
//! where the period's flight is long enough to pace (below), otherwise the ω offset δ of the
//! contact phases.
//!
//! **The flight's pace** (flights planned 1 s or longer: the COT plans). Each flight (from a
//! lift-off to the next planned contact, planned length F) keeps the plan's clock over its
//! first and last 15 % (the lift-off with its clearance floor, the approach re-timed by the
//! gap) and runs the reference at the pace κ through the middle: the free law tracks q*(σ),
//! κ q̇*(σ) with the feed-forward κ² q̈*(σ) there, and the flight lasts F − (1 − 1/κ) 0.7 F.
//! In a flight the ball's spin only decays (eq. 29b with the solid sphere's I_b:
//! I_b ω̇ = −D ω), so a flight changes the period's mean by its length and never its
//! direction; where the spin dies out in the flight (I_b / D = 2 s against the 6–10 s flights
//! of the COT plans) the mean is ω_lo I_b / D over the period's length T, and 50 % more
//! damping takes a third of it. So the pace takes the whole error along ω̄*, a Newton step on
//! that model: it aims at the period T ← T (ω̄ · ω̂* / ‖ω̄*‖)^{γ_κ} (the plan's period less
//! what the middle saves, κ ∈ [1/3, 3]), and δ stays as it is. The direction of ω̄ is the
//! lift-off ω's, which the contact law tracks. A δ across ω̄* would ask the end of a stick
//! phase for tangential force while λ_n falls to zero for the lift-off: on the low
//! `periodic-cot` plans it broke the friction cone, the slip spun the ball about the vertical,
//! and δ wound up against an error of its own making, the mean spin drifting away period after
//! period (decision record 0056). A flight whose middle has not begun when its period ends
//! takes the new pace at once (a period that ends just after the lift-off), others from the
//! next lift-off on.
//!
//! **The ω offset** (periods without a flight to pace: the QC plans' flights of 0.1–0.5 s, or
//! a pace turned off): δ ← δ + (γ/ρ) P (ω̄* − ω̄), with ‖δ‖ ≤ 0.5 ‖ω*_lo‖ (anti-windup),
//! ω*_lo the planned ω at lift-off, P = 1 − r̂ r̂ᵀ with r̂ the direction of the contact point
//! r_c at the period's lift-off (every contact force's moment r_c × λ is normal to r_c, so no
//! contact phase changes the spin about r̂: integrated, that part of the error wound δ up
//! against the socket damping alone, and its leak into the tangential force saturated the
//! actuators), and ρ = ‖ω̄‖ / ‖ω_lo‖ the period's measured ratio of its mean ω to its lift-off
//! ω (the plan's ‖ω̄*‖ / ‖ω*_lo‖ for a period without lift-off; in [0.05, 1]): δ moves the ω
//! the contact phase leaves the ball with, and the flight's socket damping passes only the
//! share ρ of it on to the period's mean. δ ramps in with the weight w over the last
//! t_δ = 0.1 s of a contact phase (all of a shorter one), and the contact-point loop's target
//! moves with the roll it causes (above), so that loop does not undo it; the ramp keeps that
//! roll to ‖δ‖ t_δ / 2.
//!
//! **Friction measured:** in Slip the measured force gives the plant's μ_k = ‖λ_∥‖ / λ_n; the
//! controller predicts the kinetic friction with it and scales its μ_s (the friction cone of
//! the margin) by the ratio to the model's μ_k, so a plant with less friction than the model
//! is found out at its first slip.
//!
//! **Re-planning** ([`HybridController::with_replanner`], optional): at every lift-off the
//! [`Replanner`] gets the measured state and returns a new plan, which the controller tracks
//! from its first phase (a free phase starting at that state) on; the optimum's plans and
//! the outer loop's target ω̄* stay. The plan is made in zero simulated time (the plant waits
//! for it), so a run does not depend on the wall clock; what a re-plan costs in computing time
//! is the replanner's to measure against its budget. With plans that begin at the lift-off the
//! outer loop's periods run from lift-off to lift-off; the period that the first re-plan
//! interrupts restarts at that lift-off, uncorrected.
//!
//! The discrete state (plan, phase, its start, the force integral, δ, the ω integral, μ_k) is recorded
//! with its time at every observation, so τ at an earlier time (the per-sample report written
//! after the run) is recomputed with the state that held then.
//!
//! **Joints.** The controller is generic in the finger's joint count N ≥ 3: the contact law
//! commands a 3-D contact force through J_cᵀ λ and places the contact point's acceleration
//! through J_c q̈, which needs J_c (3 × N) of full row rank; with N > 3 the least constraint
//! leaves the motion in ker J_c to the free law. Fingers with fewer joints are refused.

use crate::error::ControlError;
use crate::law::{ComputedTorque, InverseDynamics};
use crate::reference::Reference;
use bf_model::{Kernels, Mat3, Mat3xN, MatN, MatNx3, Mode, Model, State, Vec3, VecN};
use bf_sim::{Input, Measurement, SimError};
use std::cell::RefCell;
use std::rc::Rc;

/// Gains of the contact law (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactGains {
    /// k_ω (1/s): rate at which ω follows its target ω* + δ + ω_r.
    pub omega_rate: f64,
    /// k_r (1/s): rate at which the contact point r_c is brought back to the planned r_c*
    /// through the ball's rolling (the ω_r of the module doc).
    pub contact_point_rate: f64,
    /// k_f (1/s): integral gain of the normal-force loop.
    pub force_integral: f64,
    /// k_s (1/s): rate at which a relative velocity Δv (slip) is driven to zero.
    pub slip_rate: f64,
    /// The commanded λ_n may rise up to this multiple of the phase's largest λ_n* to keep the
    /// tangential force ω needs inside the friction cone.
    pub force_boost: f64,
    /// a_s (m/s²): constant part of the deceleration of a slip's relative velocity.
    pub slip_decel: f64,
    /// Share of μ_s λ_n kept free: ‖λ_∥‖ ≤ (1 − margin) μ_s λ_n, in [0, 1).
    pub friction_margin: f64,
    /// After the planned end of a contact phase the commanded λ_n is minus this share of the
    /// phase's largest λ_n*, so the finger lifts off.
    pub lift_off_share: f64,
}

/// The clearance the free phases keep from the ball (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clearance {
    /// h_c (m): the gap kept away from the planned contacts; 0 turns the guard off.
    pub gap: f64,
    /// t_c (s): the floor falls from h_c to 0 over this time before a planned impact.
    pub ramp: f64,
    /// t_r (s): the floor rises from 0 to h_c over this time after a lift-off; 0 puts it at
    /// h_c at once.
    pub rise: f64,
}

/// All gains of the [`HybridController`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HybridGains {
    /// Free phases.
    pub free: ComputedTorque,
    /// Clearance from the ball in free phases.
    pub clearance: Clearance,
    /// t_a (s): the last t_a of a free phase before a planned impact (at most the part where
    /// the planned gap falls) is tracked as a function of the measured gap h, not of the
    /// clock (module doc); 0 turns the re-timing off.
    pub approach: f64,
    /// Contact phases.
    pub contact: ContactGains,
    /// γ of the outer loop's ω offset (share of the period's mean ω error corrected per
    /// period where the flight is not paced), in [0, 1].
    pub outer: f64,
    /// γ_κ of the flight's pace (module doc): share of the period's error along ω̄* that the
    /// pace corrects per period, in [0, 1]; 0 leaves every flight at the plan's pace (and
    /// the ω offset takes the error).
    pub pace: f64,
}

impl Default for HybridGains {
    /// The gains for the paper's ball of 1 m ([`HybridGains::for_ball`] scales them to
    /// another): ω_n = 20 rad/s, ζ = 1 (the free phases of the optima last 0.1–9 s, so errors decay in
    /// a fraction of a phase); clearance 5 mm, falling over 50 ms before an impact (the QC
    /// optimum is 13 mm from the ball 50 ms before its impact, so the guard leaves its
    /// approach alone) and rising over 20 ms after a lift-off (ḧ ≥ 2 ω_n h_c / t_r = 10 m/s²
    /// as the finger leaves; 4 m/s² did not lift a plant with 5 % heavier links off the
    /// `periodic-cot` plan of `tests/fixtures/fragile-cot-plan`);
    /// approach re-timed over its last 0.1 s (two time constants 1/(2ζω_n) of the velocity
    /// error along the path, so a plant that enters it late and fast is slowed to the plan);
    /// k_ω = 100/s (the contact phases of the optima last 26 ms and more); k_r = 10/s (a
    /// tenth of k_ω, so the ω loop follows the contact-point loop); λ_n boost up to
    /// 3 × max λ_n*; k_f = 300/s (the loop must settle within a 26 ms stick phase);
    /// k_s = 100/s, a_s = 20 m/s²; a friction margin of 20 % (a plant with μ 20 % below the
    /// model still sticks); lift-off share 5 %; γ = 0.5; γ_κ = 1 (where the ball's spin dies
    /// out in the flight the mean is the spin's integral over the period's length, so the
    /// pace's step is Newton's; BENCHMARKS.md, "The flight's pace" and "The pace takes the
    /// whole error along the mean spin", measure the low `periodic-cot` plans with 50 % more
    /// socket damping).
    fn default() -> Self {
        HybridGains {
            free: ComputedTorque {
                omega_n: 20.0,
                zeta: 1.0,
            },
            clearance: Clearance {
                gap: 5e-3,
                ramp: 0.05,
                rise: 0.02,
            },
            approach: 0.1,
            contact: ContactGains {
                omega_rate: 100.0,
                contact_point_rate: 10.0,
                force_boost: 3.0,
                force_integral: 300.0,
                slip_rate: 100.0,
                slip_decel: 20.0,
                friction_margin: 0.2,
                lift_off_share: 0.05,
            },
            outer: 0.5,
            pace: 1.0,
        }
    }
}

impl HybridGains {
    /// The [`Default`] gains for a ball of radius `radius` (m): the two gains in metres, the
    /// clearance gap h_c and the slip deceleration a_s, scaled by r (the defaults are those of
    /// the paper's ball of 1 m); the rates, shares and times stay. A finger drawn at another
    /// scale with the same dynamics (lengths × s, masses × 1/s², gravity × s) keeps its joint
    /// motion and times, so these gains track it as the defaults track the paper's finger.
    pub fn for_ball(radius: f64) -> Self {
        let mut gains = HybridGains::default();
        gains.clearance.gap *= radius;
        gains.contact.slip_decel *= radius;
        gains
    }

    /// Checks every gain (finite, in range); the error names it.
    pub fn validate(&self) -> Result<(), ControlError> {
        ComputedTorque::new(self.free.omega_n, self.free.zeta)?;
        let c = &self.contact;
        for (name, value) in [
            ("omega_rate", c.omega_rate),
            ("contact_point_rate", c.contact_point_rate),
            ("force_integral", c.force_integral),
            ("slip_rate", c.slip_rate),
            ("slip_decel", c.slip_decel),
            ("force_boost", c.force_boost),
            ("lift_off_share", c.lift_off_share),
            ("clearance.gap", self.clearance.gap),
            ("clearance.ramp", self.clearance.ramp),
            ("clearance.rise", self.clearance.rise),
            ("approach", self.approach),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ControlError::Gain {
                    name,
                    value,
                    condition: "a finite non-negative value",
                });
            }
        }
        if !(0.0..1.0).contains(&c.friction_margin) {
            return Err(ControlError::Gain {
                name: "friction_margin",
                value: c.friction_margin,
                condition: "a value in [0, 1)",
            });
        }
        for (name, value) in [("outer", self.outer), ("pace", self.pace)] {
            if !(0.0..=1.0).contains(&value) {
                return Err(ControlError::Gain {
                    name,
                    value,
                    condition: "a value in [0, 1]",
                });
            }
        }
        Ok(())
    }
}

/// Largest ‖δ‖ of the outer loop, as a share of the planned lift-off ‖ω*_lo‖.
const OFFSET_LIMIT: f64 = 0.5;

/// t_δ (s): the outer loop's offset ramps in over at most this last part of a contact phase.
const OFFSET_RAMP: f64 = 0.1;

/// Least ρ of the outer loop (module doc): its gain γ/ρ stays at most 20 γ.
const MIN_SENSITIVITY: f64 = 0.05;

/// Largest rate σ̇ of the re-timed approach's reference time (a plant closing the gap faster
/// than this multiple of the plan's rate gets the feed-forward of this multiple).
const MAX_RETIME_RATE: f64 = 3.0;

/// Share of a flight's planned length kept at the planned pace at each end (module doc, the
/// flight's pace): the lift-off with its clearance floor, and the approach re-timed by the gap.
const PACE_ENDS: f64 = 0.15;

/// Shortest planned flight (s) whose middle the outer loop may pace.
const PACE_MIN_FLIGHT: f64 = 1.0;

/// Bounds of the pace κ of a flight's middle (the reference advances κ seconds per second).
/// The upper bound also bounds how short a period the controller commands
/// ([`crate::metrics::MIN_PERIOD_RATIO`]).
pub(crate) const PACE_LIMITS: (f64, f64) = (1.0 / 3.0, 3.0);

/// The clock of one flight (module doc, the flight's pace): from the lift-off at plant time
/// `start`, the reference runs at the planned pace for `ends` s, at pace `kappa` through the
/// next `middle` s of the reference, and at the planned pace again to the impact.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Flight {
    start: f64,
    ends: f64,
    middle: f64,
    kappa: f64,
}

impl Flight {
    /// No flight: the reference's clock is the plant's.
    const NONE: Flight = Flight {
        start: f64::NAN,
        ends: 0.0,
        middle: 0.0,
        kappa: 1.0,
    };

    /// A flight from a lift-off at `start`, planned to last `length` s, paced at `kappa`.
    fn new(start: f64, length: f64, kappa: f64) -> Flight {
        if !(length.is_finite() && length >= PACE_MIN_FLIGHT) {
            return Flight {
                start,
                ..Flight::NONE
            };
        }
        let ends = PACE_ENDS * length;
        Flight {
            start,
            ends,
            middle: length - 2.0 * ends,
            kappa,
        }
    }

    /// The reference time at plant time `t` and its rate.
    fn reference_time(&self, t: f64) -> (f64, f64) {
        let u = t - self.start;
        if u.is_nan() || u <= self.ends || self.middle <= 0.0 {
            return (t, 1.0);
        }
        let paced = self.middle / self.kappa;
        if u <= self.ends + paced {
            (
                self.start + self.ends + self.kappa * (u - self.ends),
                self.kappa,
            )
        } else {
            (t + self.middle - paced, 1.0)
        }
    }

    /// The plant time at reference time `r` (the inverse of [`Flight::reference_time`]).
    fn plant_time(&self, r: f64) -> f64 {
        let u = r - self.start;
        if u.is_nan() || u <= self.ends || self.middle <= 0.0 {
            return r;
        }
        if u <= self.ends + self.middle {
            self.start + self.ends + (u - self.ends) / self.kappa
        } else {
            r - self.middle + self.middle / self.kappa
        }
    }
}

/// The re-timing keeps to where the plan closes the gap at least at this share of its impact
/// speed: σ = h*⁻¹(h) turns a gap error into a time error 1/|ḣ*| times larger, and the QC
/// optimum hovers 15 mm from the ball at 1 cm/s 80 ms before its impact (at 33 cm/s).
const RETIME_MIN_RATE: f64 = 0.5;

/// Share of the torque bounds a saturated command's feed-forward is scaled into
/// (`HybridController::fit_bounds`): strictly inside, so the feedback fitted on top of it is a
/// continuous function of the state.
const FIT_INNER: f64 = 0.95;

/// The re-timed end of a free phase before a planned impact (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Approach {
    /// σ_a: where the re-timing begins (s since the phase began).
    start: f64,
    /// h*(σ_a) (m).
    gap: f64,
    /// ḣ*(σ_a) (m/s), negative.
    rate: f64,
}

impl Approach {
    /// The approach window of `phase`, followed by a contact phase: its last `window` s,
    /// shortened to the samples from which on h* falls at least at [`RETIME_MIN_RATE`] times
    /// the planned impact's ḣ*; `None` when h* does not fall at the planned impact, the
    /// window is empty or the next phase is free.
    fn of<const N: usize>(reference: &Reference<N>, phase: usize, window: f64) -> Option<Approach> {
        let phases = &reference.phases;
        let ph = &phases[phase];
        if ph.contact || !phases[(phase + 1) % phases.len()].contact || window <= 0.0 {
            return None;
        }
        let last = ph.s.len() - 1;
        let closing = RETIME_MIN_RATE * ph.gap_rate[last];
        let falling = ph
            .gap_rate
            .iter()
            .rev()
            .take_while(|r| closing < 0.0 && **r <= closing)
            .count();
        if falling < 2 {
            return None;
        }
        let start = (ph.s[last] - window).max(ph.s[last + 1 - falling]);
        let (gap, rate) = ph.gap_at(start);
        (rate <= closing && gap > ph.gap[last]).then_some(Approach { start, gap, rate })
    }
}

/// The discrete state of the controller from time `t` on.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Discrete {
    t: f64,
    mode: Mode,
    phase: usize,
    start: f64,
    force_int: f64,
    omega_offset: [f64; 3],
    omega_int: [f64; 3],
    omega_last: [f64; 3],
    /// ‖ω‖ at the last lift-off (rad/s), 0 before the first.
    lift_off_omega: f64,
    /// Unit vector of the contact point r_c at the last lift-off (from the ball's centre),
    /// zero before the first: the direction of ω no contact force can change.
    lift_off_contact: [f64; 3],
    period_start: f64,
    periods: usize,
    slips: usize,
    /// μ_k measured in the last slip (|λ_∥| / λ_n); the model's μ_k before any slip.
    mu_k: f64,
    /// The plan in force (index into [`HybridController::plans`]).
    plan: usize,
    /// The pace κ the outer loop sets for the next flights (1: the plan's).
    pace: f64,
    /// The flight in progress, or the last one until the next lift-off.
    flight: Flight,
}

/// Makes a new plan at a lift-off of the plant (module doc, re-planning).
pub trait Replanner<const N: usize = 3>: std::fmt::Debug {
    /// The plan to track from the lift-off at plant time `t` in the measured state `x`
    /// (q, q̇, ω; 2N + 3 values) on, starting with a free phase at `x`; `None` keeps the current plan.
    /// Called once per lift-off, in time order; it must not depend on the wall clock (the
    /// plant waits for it in simulated time).
    fn replan(&mut self, t: f64, x: &[f64]) -> Option<Reference<N>>;
}

/// A phase switch of the controller: plant time, reference phase entered, and the mode
/// transition that caused it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseSwitch {
    /// Plant time (s).
    pub t: f64,
    /// The reference phase entered.
    pub phase: usize,
    /// The plant's mode before the event.
    pub from: Mode,
    /// The plant's mode after it.
    pub to: Mode,
}

/// The hybrid controller (module doc); a bf-sim [`Input`] for `N` joints.
#[derive(Debug)]
pub struct HybridController<K: Kernels<N>, const N: usize = 3> {
    model: Model<K, N>,
    id: InverseDynamics,
    gains: HybridGains,
    /// The optimum's mean ω̄* (rad/s), the outer loop's target.
    mean_omega: [f64; 3],
    /// The plans tracked, in the order they were made: the optimum first, then one per
    /// re-plan ([`Replanner`]); [`Discrete::plan`] says which is in force.
    plans: RefCell<Vec<Rc<Plan<N>>>>,
    /// Makes a new plan at each lift-off, if set.
    replanner: Option<RefCell<Box<dyn Replanner<N>>>>,
    /// The plan's ρ of the outer loop (module doc), until a period measures its own.
    sensitivity: f64,
    /// Largest ‖δ‖ (rad/s).
    offset_limit: f64,
    /// |τ_i| ≤ tau_max[i] (N m): the actuators' bounds, infinite unless set.
    tau_max: [f64; N],
    history: RefCell<Vec<Discrete>>,
    switches: RefCell<Vec<PhaseSwitch>>,
}

impl<K: Kernels<N>, const N: usize> HybridController<K, N> {
    /// The controller on `model` (its own model of the plant: the optimum's scene) with the
    /// inverse dynamics `id` of the same scene, tracking `reference` from its first phase,
    /// which begins at plant time `t0` with the plant's initial state `x0` (q, q̇, ω).
    pub fn new(
        model: Model<K, N>,
        id: InverseDynamics,
        reference: Reference<N>,
        gains: HybridGains,
        t0: f64,
        x0: &[f64],
    ) -> Result<Self, ControlError> {
        gains.validate()?;
        if N < 3 {
            return Err(ControlError::Dimension {
                what: "finger joints (the contact law commands a 3-D force)",
                expected: 3,
                found: N,
            });
        }
        if id.nq() != N {
            return Err(ControlError::Dimension {
                what: "inverse dynamics joints",
                expected: N,
                found: id.nq(),
            });
        }
        if x0.len() != 2 * N + 3 || x0.iter().any(|v| !v.is_finite()) || !t0.is_finite() {
            return Err(ControlError::Dimension {
                what: "finite initial state (q, qd, omega)",
                expected: 2 * N + 3,
                found: x0.iter().filter(|v| v.is_finite()).count(),
            });
        }
        // ω*_lo: the largest planned ω at the end of a contact phase; without one, the mean.
        let mean = Vec3::from(reference.mean_omega).norm();
        let lift_off = reference
            .phases
            .iter()
            .filter(|p| p.contact)
            .map(|p| Vec3::from(p.omega[p.omega.len() - 1]).norm())
            .fold(0.0, f64::max);
        let lift_off = if lift_off > 0.0 { lift_off } else { mean };
        let sensitivity = if lift_off > 0.0 {
            (mean / lift_off).clamp(MIN_SENSITIVITY, 1.0)
        } else {
            1.0
        };
        let mode = if reference.phases[0].contact {
            Mode::Stick
        } else {
            Mode::Free
        };
        let omega = [x0[2 * N], x0[2 * N + 1], x0[2 * N + 2]];
        let d = Discrete {
            t: t0,
            mode,
            phase: 0,
            start: t0,
            force_int: 0.0,
            omega_offset: [0.0; 3],
            omega_int: [0.0; 3],
            omega_last: omega,
            lift_off_omega: 0.0,
            lift_off_contact: [0.0; 3],
            period_start: t0,
            periods: 0,
            slips: 0,
            mu_k: model.params().mu_k(),
            plan: 0,
            pace: 1.0,
            flight: Flight::NONE,
        };
        let mean_omega = reference.mean_omega;
        let plan = Plan::new(reference, gains.approach, t0);
        Ok(HybridController {
            model,
            id,
            gains,
            mean_omega,
            plans: RefCell::new(vec![Rc::new(plan)]),
            replanner: None,
            sensitivity,
            offset_limit: OFFSET_LIMIT * lift_off,
            tau_max: [f64::INFINITY; N],
            history: RefCell::new(vec![d]),
            switches: RefCell::new(Vec::new()),
        })
    }

    /// The controller with the actuators' torque bounds |τ_i| ≤ `bound[i]` (N m): the torque it
    /// commands is saturated there, and the force loop's integral is held while the law asks
    /// for more (anti-windup, module doc). Errors on a bound that is not positive (NaN
    /// included); infinity means no bound.
    pub fn with_torque_bound(mut self, bound: [f64; N]) -> Result<Self, ControlError> {
        if let Some(&b) = bound.iter().find(|b| b.is_nan() || **b <= 0.0) {
            return Err(ControlError::Gain {
                name: "tau_max",
                value: b,
                condition: "a positive torque bound (N m)",
            });
        }
        self.tau_max = bound;
        Ok(self)
    }

    /// The torque bounds (N m).
    pub fn torque_bound(&self) -> [f64; N] {
        self.tau_max
    }

    /// Whether the law at (`mode`, `t`, `x`) with the discrete state `d` asks for a torque
    /// beyond the bounds.
    fn saturates(&self, d: &Discrete, mode: Mode, t: f64, x: &State<N>) -> bool {
        let mut tau = [0.0; N];
        self.law(d, mode, t, x, &mut tau).is_ok()
            && tau.iter().zip(&self.tau_max).any(|(v, b)| v.abs() > *b)
    }

    /// The controller that re-plans at every lift-off of the plant with `replanner` (the
    /// module doc's re-planning).
    pub fn with_replanner(mut self, replanner: Box<dyn Replanner<N>>) -> Self {
        self.replanner = Some(RefCell::new(replanner));
        self
    }

    /// The reference the controller was made with (the optimum).
    pub fn reference(&self) -> Reference<N> {
        self.plans.borrow()[0].reference.clone()
    }

    /// The plans made at lift-offs so far (plant time from which each was tracked, and the
    /// plan), in time order; the optimum itself is not among them.
    pub fn replans(&self) -> Vec<(f64, Reference<N>)> {
        self.plans.borrow()[1..]
            .iter()
            .map(|p| (p.t, p.reference.clone()))
            .collect()
    }

    fn plan(&self, k: usize) -> Rc<Plan<N>> {
        let plans = self.plans.borrow();
        Rc::clone(&plans[k.min(plans.len() - 1)])
    }

    /// The phase switches so far, in time order.
    pub fn switches(&self) -> Vec<PhaseSwitch> {
        self.switches.borrow().clone()
    }

    /// Periods completed so far (the reference wrapped to its first phase).
    pub fn periods(&self) -> usize {
        self.last().periods
    }

    /// Stick → Slip transitions seen so far.
    pub fn slips(&self) -> usize {
        self.last().slips
    }

    /// The outer loop's current ω offset δ (rad/s).
    pub fn omega_offset(&self) -> [f64; 3] {
        self.last().omega_offset
    }

    /// The pace κ the outer loop has set for the next flights (1: the plan's; module doc,
    /// the flight's pace).
    pub fn pace(&self) -> f64 {
        self.last().pace
    }

    fn last(&self) -> Discrete {
        let h = self.history.borrow();
        h[h.len() - 1]
    }

    /// The discrete state in force at time `t` in plant mode `mode`: the last one recorded at
    /// or before `t`; of several recorded at `t` itself (an event: pre- and post-transition),
    /// the latest one with that mode.
    fn state_at(&self, t: f64, mode: Mode) -> Discrete {
        let h = self.history.borrow();
        let k = h.partition_point(|e| e.t <= t).max(1);
        let mut i = k - 1;
        while i > 0 && h[i].t == t && h[i].mode != mode && h[i - 1].t == t {
            i -= 1;
        }
        h[i]
    }

    /// The discrete state in force just before `t`: the last one recorded before `t`, none of
    /// those recorded at `t` itself ([`Input::tau_before`]); the first one for `t` at or before
    /// the start.
    fn state_before(&self, t: f64) -> Discrete {
        let h = self.history.borrow();
        h[h.partition_point(|e| e.t < t).saturating_sub(1)]
    }

    /// [`HybridController::law`] with the discrete state `d` at the plant's state
    /// `(q, q̇, ω)`, clamped to the torque bounds: the τ of both [`Input::tau_in_mode`] and
    /// [`Input::tau_before`].
    fn clamped_law(
        &self,
        d: &Discrete,
        mode: Mode,
        t: f64,
        (q, qd, omega): (&[f64], &[f64], &[f64]),
        out: &mut [f64],
    ) -> Result<(), SimError> {
        let len_err = |what, expected, found| SimError::DimensionMismatch {
            what,
            expected,
            found,
        };
        let q: [f64; N] = q.try_into().map_err(|_| len_err("q", N, q.len()))?;
        let qd: [f64; N] = qd.try_into().map_err(|_| len_err("qd", N, qd.len()))?;
        let w: [f64; 3] = omega
            .try_into()
            .map_err(|_| len_err("omega", 3, omega.len()))?;
        let found = out.len();
        let out: &mut [f64; N] = out
            .try_into()
            .map_err(|_| len_err("torque output", N, found))?;
        let x = State::new(q.into(), qd.into(), w.into());
        self.law(d, mode, t, &x, out).map_err(to_sim)?;
        for (v, b) in out.iter_mut().zip(&self.tau_max) {
            *v = v.clamp(-b, *b);
        }
        Ok(())
    }

    /// τ in `mode` at time `t` and state (q, q̇, ω) with the discrete state `d`.
    fn law(
        &self,
        d: &Discrete,
        mode: Mode,
        t: f64,
        x: &State<N>,
        out: &mut [f64; N],
    ) -> Result<(), ControlError> {
        let plan = self.plan(d.plan);
        let plan = &*plan;
        let (t_ref, pace) = plan.reference_time(d, t);
        let (phase, start) = plan.timed_phase(d.phase, d.start, t_ref);
        let ph = &plan.reference.phases[phase];
        let s = t_ref - start;
        if mode == Mode::Free || !ph.contact {
            let (sigma, rate) = if mode == Mode::Free {
                self.retime(plan, phase, s, x)?
            } else {
                (s, 1.0)
            };
            let r = ph.at(sigma);
            let qd_ref = r.qd.map(|v| v * pace);
            let qdd_ff = r.qdd.map(|v| v * rate * pace * pace);
            let mut qdd = [0.0; N];
            self.gains.free.acceleration(
                x.q.as_slice(),
                x.qd.as_slice(),
                &r.q,
                &qd_ref,
                &qdd_ff,
                &mut qdd,
            );
            self.inverse_dynamics(x, &qdd, out)?;
            if mode == Mode::Free {
                self.keep_clearance(plan, phase, sigma, x, &qdd, out)?;
            }
            if !self.within_bounds(out) {
                // The feed-forward ID(q, q̇, q̈*) plus as much feedback as the bounds allow.
                let mut base = [0.0; N];
                self.inverse_dynamics(x, &qdd_ff, &mut base)?;
                *out = self.fit_bounds(&base, out);
            }
            return Ok(());
        }
        let r = ph.at(s);
        let g = &self.gains.contact;
        let p = self.model.params();
        let kin = self.model.evaluate(x)?;
        let c = &kin.contact;
        let n = c.n;
        let planned_end = s > ph.duration;
        let mut lambda_n = if planned_end {
            -g.lift_off_share * plan.lambda_scale[phase]
        } else {
            Vec3::from(r.lambda).dot(&n) + g.force_integral * d.force_int
        };
        let omega = x.omega;
        let rc = c.r_c;
        // The contact point rolls with the ball, ṙ_c = ω × r_c at the fingertip: the ω_r with
        // ω_r × r_c = k_r e (e the tangential part of r_c* − r_c) makes |e| decay at the rate
        // k_r. Without it a contact point displaced by a slip stays displaced, and with it the
        // ω at lift-off (ω ⊥ r_c, as sticking keeps the spin about n) differs from the plan.
        // The outer loop's offset δ ramps in over the last t_δ of the phase (w from 0 to 1),
        // so the ball leaves with ω* + δ, and rolls the contact point by δ × r_c* ∫w more
        // than planned: that displaced point is the contact-point loop's target, or the loop
        // would undo δ within 1/k_r (it did on the human finger's COT optimum, whose stick
        // phase lasts 0.55 s); the ramp keeps that roll to |δ| t_δ / 2.
        let ramp = ph.duration.min(OFFSET_RAMP);
        let late = (s.clamp(0.0, ph.duration) - (ph.duration - ramp)).max(0.0);
        let (w, rolled) = if ramp > 0.0 {
            (late / ramp, 0.5 * late * late / ramp)
        } else {
            (1.0, 0.0)
        };
        let offset = Vec3::from(d.omega_offset);
        let rc_ref = Vec3::from(r.contact_point);
        let e = rc_ref + offset.cross(&rc_ref) * rolled - rc;
        let e = e - n * n.dot(&e);
        let omega_r = rc.cross(&e) * (g.contact_point_rate / rc.norm_squared());
        let target = Vec3::from(r.omega) + offset * w + omega_r;
        let omega_dot_cmd = Vec3::from(r.omega_dot) + (target - omega) * g.omega_rate;
        let ib: &Mat3 = p.ball_inertia();
        let f_b = omega.cross(&(ib * omega)) + omega * p.socket_damping();
        let m = -f_b - ib * omega_dot_cmd;
        let perp = m.cross(&rc) / rc.norm_squared();
        let mut lambda_t = perp - n * n.dot(&perp);
        // The friction measured in a slip scales the static coefficient the margin is taken
        // from (a plant with less friction than the model is found out at its first slip).
        let mu_s = if p.mu_k() > 0.0 {
            p.mu_s() * (d.mu_k / p.mu_k()).min(1.0)
        } else {
            p.mu_s()
        };
        let grip = (1.0 - g.friction_margin) * mu_s;
        if !planned_end {
            // Press harder when the tangential force ω needs exceeds the friction cone with
            // its margin, up to `force_boost` times the phase's largest planned force.
            let needed = lambda_t.norm() / grip;
            lambda_n = lambda_n.max(needed.min(g.force_boost * plan.lambda_scale[phase]));
        }
        let cap = grip * lambda_n.max(0.0);
        let lt = lambda_t.norm();
        if lt > cap {
            lambda_t *= if lt > 0.0 { cap / lt } else { 0.0 };
        }
        // In Slip the plant's friction is kinetic, λ = λ_n (n + μ_k t̂) (eq. 20, 37): the
        // tangential force is not the controller's to choose, so it is predicted, and the
        // finger's tangential acceleration instead drives Δv to zero.
        let slip_dir = match mode {
            Mode::Slip => {
                bf_model::dynamics::slip_direction(&kin, self.model.settings(), None).ok()
            }
            _ => None,
        };
        let lambda = match slip_dir {
            Some(t_hat) => (n + t_hat * d.mu_k) * lambda_n,
            None => n * lambda_n + lambda_t,
        };
        let dv = c.delta_v - n * n.dot(&c.delta_v);
        let dv_norm = dv.norm();
        // Δv̇ = −k_s Δv − a_s Δv/‖Δv‖: exponential plus a constant deceleration, so a slip
        // ends in finite time (the Slip → Stick guard ‖Δv‖ ≤ ε).
        // Only in Slip: in Stick Δv is zero up to rounding (the simulator projects onto it),
        // and Δv/‖Δv‖ of rounding noise would be a random unit vector.
        let mut dv_dot = Vec3::zeros();
        if slip_dir.is_some() && dv_norm > 0.0 {
            dv_dot = -dv * (g.slip_rate + g.slip_decel / dv_norm);
        }
        // The normal part keeps n·v_c = 0 (the derivative of eq. 36, as the slip law does).
        let normal = -(c.n_dot().dot(&c.v_c) + n.dot(&c.jc_dot_qd));
        // The finger's motion that leaves the contact point in place (ker J_c: joint 1's axis
        // through the contact point, a folded finger) is the free law's to choose: the least
        // constraint on the computed-torque command (module doc).
        let mut qdd_free = [0.0; N];
        self.gains.free.acceleration(
            x.q.as_slice(),
            x.qd.as_slice(),
            &r.q,
            &r.qd,
            &r.qdd,
            &mut qdd_free,
        );
        let qdd_free = VecN::<N>::from(qdd_free);
        let least =
            LeastConstraint::new(&kin.m_f, &c.j_c).ok_or(ControlError::SingularJacobian { t })?;
        // τ for the force λ on the finger and the relative acceleration Δv̇: affine in both.
        let torque = |lambda: Vec3, dv_dot: Vec3| -> Result<[f64; N], ControlError> {
            let omega_dot = p.ball_inertia_inv() * (-f_b - rc.cross(&lambda));
            let stick_acc = omega_dot.cross(&rc) + omega.cross(&c.rc_dot) - c.jc_dot_qd - dv_dot;
            let a_c = stick_acc - n * n.dot(&stick_acc) + n * normal;
            let qdd = Some(least.acceleration(&a_c, &qdd_free))
                .filter(|v| v.iter().all(|x| x.is_finite()))
                .ok_or(ControlError::SingularJacobian { t })?;
            let tau = kin.m_f * qdd + kin.cqd_g + x.qd * p.mu_v() - c.j_c.transpose() * lambda;
            Ok(tau.into())
        };
        let tau = torque(lambda, dv_dot)?;
        *out = if self.within_bounds(&tau) || planned_end {
            tau
        } else {
            // The planned force (the kinetic friction it implies in Slip) without the
            // feedback: the optimum keeps its torques inside the bounds, so the feedback is
            // scaled down to what the actuators give.
            let planned = Vec3::from(r.lambda);
            let planned = match slip_dir {
                Some(t_hat) => (n + t_hat * d.mu_k) * planned.dot(&n),
                None => planned,
            };
            self.fit_bounds(&torque(planned, Vec3::zeros())?, &tau)
        };
        Ok(())
    }

    /// The reference time σ and its rate σ̇ at time `s` of free phase `phase` for the plant
    /// state `x` (module doc): (s, 1) outside the approach window; in it the σ at which the
    /// plan's gap h*(σ) is the measured h (above the window's top, on the tangent of h* at
    /// σ_a, for a late plant), and σ̇ = ḣ / ḣ*(σ) in [0, [`MAX_RETIME_RATE`]].
    fn retime(
        &self,
        plan: &Plan<N>,
        phase: usize,
        s: f64,
        x: &State<N>,
    ) -> Result<(f64, f64), ControlError> {
        let Some(a) = plan.approach[phase] else {
            return Ok((s, 1.0));
        };
        let ph = &plan.reference.phases[phase];
        let window = ph.s[ph.s.len() - 1] - a.start;
        // An early plant is re-timed from one window's length before the window on.
        if s < a.start - window {
            return Ok((s, 1.0));
        }
        let c = self.model.evaluate(x)?.contact;
        if s < a.start && c.h > a.gap {
            return Ok((s, 1.0));
        }
        let (sigma, planned_rate) = if c.h >= a.gap {
            (
                (a.start + (c.h - a.gap) / a.rate).max(a.start - window),
                a.rate,
            )
        } else {
            let sigma = ph.time_of_gap(c.h, a.start);
            (sigma, ph.gap_at(sigma).1)
        };
        let rate = if planned_rate < 0.0 {
            (c.h_dot / planned_rate).clamp(0.0, MAX_RETIME_RATE)
        } else {
            1.0
        };
        Ok((sigma, rate))
    }

    /// τ = ID(q, q̇, q̈) + μ_v q̇ at the state `x` for the acceleration `qdd`: the generated
    /// kernel where the scene has one, else M(q) q̈ + (C q̇ + g)(q, q̇) + μ_v q̇ from the
    /// controller's model ([`InverseDynamics::from_model`]).
    fn inverse_dynamics(
        &self,
        x: &State<N>,
        qdd: &[f64; N],
        out: &mut [f64; N],
    ) -> Result<(), ControlError> {
        if self.id.is_compiled() {
            return self.id.torque(x.q.as_slice(), x.qd.as_slice(), qdd, out);
        }
        let kin = self.model.evaluate(x)?;
        let tau = kin.m_f * VecN::<N>::from(*qdd) + kin.cqd_g + x.qd * self.id.mu_v();
        *out = tau.into();
        Ok(())
    }

    /// Whether |τ_i| ≤ τ_max,i for every joint.
    fn within_bounds(&self, tau: &[f64; N]) -> bool {
        tau.iter().zip(&self.tau_max).all(|(v, b)| v.abs() <= *b)
    }

    /// [`fit_bounds`] with this controller's bounds.
    fn fit_bounds(&self, base: &[f64; N], full: &[f64; N]) -> [f64; N] {
        fit_bounds(&self.tau_max, base, full)
    }

    /// The clearance guard of a free phase (module doc): below the floor h_f, adds J_cᵀ n β to
    /// the computed torque `tau` (for the commanded acceleration `qdd`) when the gap's
    /// acceleration ḧ would fall below ω_n² (h_f − h) + 2 ω_n (ḣ_f − ḣ), the critically damped
    /// return to the moving floor.
    fn keep_clearance(
        &self,
        plan: &Plan<N>,
        phase: usize,
        s: f64,
        x: &State<N>,
        qdd: &[f64; N],
        tau: &mut [f64; N],
    ) -> Result<(), ControlError> {
        let cl = &self.gains.clearance;
        // A plant off the ball in a contact phase of the reference is to make contact again.
        if cl.gap <= 0.0 || plan.reference.phases[phase].contact {
            return Ok(());
        }
        let (since, until) = plan.contact_margins(phase, s);
        let (floor, floor_rate) = clearance_floor(cl, since, until);
        if floor <= 0.0 {
            return Ok(());
        }
        let kin = self.model.evaluate(x)?;
        let c = &kin.contact;
        // Only below the floor: above it a condition on ḧ would also brake the planned
        // approach, whose gap closes at the impact speed.
        if c.h >= floor {
            return Ok(());
        }
        let n = c.n;
        let h_ddot =
            n.dot(&(c.j_c * VecN::<N>::from(*qdd) + c.jc_dot_qd)) + c.n_dot().dot(&c.rc_dot);
        let w = self.gains.free.omega_n;
        let wanted = w * w * (floor - c.h) + 2.0 * w * (floor_rate - c.h_dot);
        if h_ddot >= wanted {
            return Ok(());
        }
        // β = (wanted − ḧ) / (wᵀ M⁻¹ w), w = J_cᵀ n: the least torque (in the M⁻¹ norm, a
        // force along n at the contact point) that lifts ḧ to the wanted value.
        let dir = c.j_c.transpose() * n;
        let reach = kin
            .m_f
            .cholesky()
            .map(|m| dir.dot(&m.solve(&dir)))
            .filter(|r| r.is_finite() && *r > 0.0);
        if let Some(reach) = reach {
            let beta = (wanted - h_ddot) / reach;
            for i in 0..N {
                tau[i] += dir[i] * beta;
            }
        }
        Ok(())
    }

    /// [`Plan::timed_phase`] of `plan` applied to `d` at time `t`, ending the period when
    /// the reference wraps to its first phase.
    fn advance_timed(&self, plan: &Plan<N>, d: &mut Discrete, t: f64) {
        let (t_ref, _) = plan.reference_time(d, t);
        let (phase, start) = plan.timed_phase(d.phase, d.start, t_ref);
        if phase != d.phase {
            if phase < d.phase {
                self.end_period(d, d.flight.plant_time(start));
            }
            d.phase = phase;
            d.start = start;
        }
    }

    /// Moves `d` to the next reference phase whose contact flag is `contact`, starting at `t`;
    /// wrapping past the last phase ends a period (outer loop).
    fn advance(&self, plan: &Plan<N>, d: &mut Discrete, t: f64, contact: bool) {
        let np = plan.reference.phases.len();
        let mut next = d.phase;
        for _ in 0..np {
            next = (next + 1) % np;
            if next == 0 {
                self.end_period(d, t);
            }
            if plan.reference.phases[next].contact == contact {
                break;
            }
        }
        d.phase = next;
        d.start = t;
        d.force_int = 0.0;
    }

    /// At a lift-off at time `t` in state `x`: the plan made then (already made if this
    /// lift-off was observed before, e.g. again after a rejected step), or a new one from the
    /// replanner, tracked from its first phase on; without a replanner or a new plan, `d` is
    /// left as it is.
    fn replan(&self, d: &mut Discrete, t: f64, x: &[f64]) {
        let Some(replanner) = &self.replanner else {
            return;
        };
        if x.len() != 2 * N + 3 {
            return;
        }
        let made = {
            let plans = self.plans.borrow();
            (plans.len() > 1 && plans[plans.len() - 1].t == t).then(|| plans.len() - 1)
        };
        let k = match made {
            Some(k) => k,
            None => {
                let Some(reference) = replanner.borrow_mut().replan(t, x) else {
                    return;
                };
                let mut plans = self.plans.borrow_mut();
                plans.push(Rc::new(Plan::new(reference, self.gains.approach, t)));
                plans.len() - 1
            }
        };
        d.plan = k;
        d.phase = 0;
        d.start = t;
        d.force_int = 0.0;
        // The plan begins at this lift-off, so the outer loop's periods now run from lift-off
        // to lift-off. At the first re-plan the period in progress began where the plan
        // before began its period (its apex); measured on to the next lift-off it would hold
        // more than a period, and its mean a wrong error for the outer loop to correct
        // (0.85 % in the third period of the `periodic-qc` plan, where the optimum tracked
        // alone stays within 0.01 %). It restarts here, uncorrected; at later re-plans the
        // lift-off has just ended the period and this changes nothing.
        d.omega_int = [0.0; 3];
        d.period_start = t;
    }

    fn end_period(&self, d: &mut Discrete, t: f64) {
        let len = t - d.period_start;
        if len > 0.0 {
            let mean = d.omega_int.map(|v| v / len);
            let target = Vec3::from(self.mean_omega);
            let along = target.try_normalize(0.0);
            // The flight's pace, where this period's flight has a middle to pace, takes the
            // whole error along ω̄* and δ none of it. In a flight the ball's spin only decays
            // (eq. 29b with an isotropic I_b: I_b ω̇ = −D ω), so the flight changes the
            // period's mean by its length and never its direction; that direction is the
            // lift-off ω's, which the contact law tracks. A δ across ω̄* asks the end of a
            // stick phase for tangential force while λ_n falls to zero for the lift-off: on
            // the low `periodic-cot` plans it broke the cone and the slip spun the ball about
            // the vertical, so δ wound up against an error of its own making (docs/decisions
            // 0056). Where the spin dies out in the flight the mean is its integral over the
            // period's length, so the pace's step is Newton's.
            let ratio = along.map(|u| Vec3::from(mean).dot(&u) / target.norm());
            let pace_ratio = match ratio {
                Some(r) if self.gains.pace > 0.0 && d.flight.middle > 0.0 && r > 0.0 => Some(r),
                _ => None,
            };
            if let Some(ratio) = pace_ratio {
                // The period the pace should give, and the plant time its flight's middle
                // then takes: the plan's period less what the shorter middle saves.
                let wanted = len * libm::pow(ratio, self.gains.pace);
                let paced = d.flight.middle - (self.plan(d.plan).period() - wanted);
                let kappa = if paced > 0.0 {
                    d.flight.middle / paced
                } else {
                    PACE_LIMITS.1
                };
                d.pace = kappa.clamp(PACE_LIMITS.0, PACE_LIMITS.1);
                // A flight still in its first part (the period ended right after its
                // lift-off) is the next period's: it takes the new pace now.
                if t - d.flight.start <= d.flight.ends {
                    d.flight.kappa = d.pace;
                }
            } else {
                // Every contact force acts at r_c, so its moment r_c × λ is normal to r_c:
                // the spin about the contact point's direction is the socket damping's
                // alone. An error along it is left out of δ, which would otherwise wind up
                // against it (and through the contact point's motion leak into the
                // tangential force).
                let error = target - Vec3::from(mean);
                let axis = Vec3::from(d.lift_off_contact);
                let correction = error - axis * axis.dot(&error);
                // ρ measured in the period when it had a lift-off: a plant whose flight
                // differs from the plan (more socket damping) passes a different share of δ
                // to the mean.
                let measured = Vec3::from(mean).norm() / d.lift_off_omega;
                let sensitivity = if d.lift_off_omega > 0.0 && measured.is_finite() {
                    measured.clamp(MIN_SENSITIVITY, 1.0)
                } else {
                    self.sensitivity
                };
                for i in 0..3 {
                    d.omega_offset[i] += self.gains.outer / sensitivity * correction[i];
                }
            }
            // Anti-windup: a plant that cannot reach the optimum's ω must not drive the offset
            // (and with it the contact forces) without bound.
            let limit = self.offset_limit;
            let norm = Vec3::from(d.omega_offset).norm();
            if norm > limit {
                d.omega_offset = d.omega_offset.map(|v| v * limit / norm);
            }
        }
        d.omega_int = [0.0; 3];
        d.lift_off_omega = 0.0;
        d.lift_off_contact = [0.0; 3];
        d.period_start = t;
        d.periods += 1;
    }
}

/// A reference with what the law derives from it once: the largest λ_n* of each phase and
/// the re-timed approach of each phase.
#[derive(Debug)]
struct Plan<const N: usize> {
    /// Plant time from which on it is tracked (s).
    t: f64,
    reference: Reference<N>,
    /// max λ_n* of each phase (N): the scale of the lift-off command.
    lambda_scale: Vec<f64>,
    /// The re-timed approach of each phase, if it has one.
    approach: Vec<Option<Approach>>,
}

impl<const N: usize> Plan<N> {
    /// `reference` tracked from plant time `t`, its approach windows `window` s long at most.
    fn new(reference: Reference<N>, window: f64, t: f64) -> Plan<N> {
        let lambda_scale = reference
            .phases
            .iter()
            .map(|p| {
                p.lambda
                    .iter()
                    .map(|l| Vec3::from(*l).norm())
                    .fold(0.0, f64::max)
            })
            .collect();
        let approach = (0..reference.phases.len())
            .map(|p| Approach::of(&reference, p, window))
            .collect();
        Plan {
            t,
            reference,
            lambda_scale,
            approach,
        }
    }

    /// The reference's clock at plant time `t` in the discrete state `d`, and its rate: the
    /// flight's paced clock ([`Flight`]) in a free phase, the plant's in a contact phase.
    fn reference_time(&self, d: &Discrete, t: f64) -> (f64, f64) {
        if self.reference.phases[d.phase].contact {
            (t, 1.0)
        } else {
            d.flight.reference_time(t)
        }
    }

    /// The planned period (s): the sum of the phase durations.
    fn period(&self) -> f64 {
        self.reference.phases.iter().map(|p| p.duration).sum()
    }

    /// Time since the last planned lift-off and until the next planned impact at time `s` of
    /// free phase `phase` (s), through the consecutive free phases around it; infinite for a
    /// reference without a contact phase.
    fn contact_margins(&self, phase: usize, s: f64) -> (f64, f64) {
        let phases = &self.reference.phases;
        let np = phases.len();
        let (mut since, mut until) = (s, phases[phase].duration - s);
        let mut back = phase;
        let mut ahead = phase;
        for _ in 1..np {
            back = (back + np - 1) % np;
            if phases[back].contact {
                break;
            }
            since += phases[back].duration;
        }
        for _ in 1..np {
            ahead = (ahead + 1) % np;
            if phases[ahead].contact {
                break;
            }
            until += phases[ahead].duration;
        }
        if !phases.iter().any(|p| p.contact) {
            return (f64::INFINITY, f64::INFINITY);
        }
        (since, until)
    }

    /// The free phase in force at time `t` when free phase `phase` began at `start`: two free
    /// phases in a row (the optimum's period may begin in the middle of the flight) are joined
    /// by time, as no event separates them. Other phases are returned as they are.
    fn timed_phase(&self, mut phase: usize, mut start: f64, t: f64) -> (usize, f64) {
        let phases = &self.reference.phases;
        for _ in 0..phases.len() {
            let next = (phase + 1) % phases.len();
            let ph = &phases[phase];
            if ph.contact || phases[next].contact || t - start <= ph.duration {
                break;
            }
            start += ph.duration;
            phase = next;
        }
        (phase, start)
    }
}

/// Relative damping ε of [`LeastConstraint`]: (W + ε tr(W)/3 · 1)⁻¹ caps the gain of a
/// contact-space error at 3/(ε tr W), as if W (J_c M⁻¹ J_cᵀ) had a condition number of at most
/// about 1/ε. Measured on the Newton-planned QC optimum (J 0.2273), whose stick phase passes
/// near a singular J_c: ε = 10⁻⁹ (the undamped law) commanded up to 1.7·10⁷ N m unbounded and
/// lost the ball bounded; 10⁻⁴ left 34 N m unbounded; 10⁻³ keeps it to 4.6 N m with the first
/// ten periods within 0.5 % (BENCHMARKS.md, "Newton-planned optima").
const CONTACT_DAMPING: f64 = 1e-3;

/// The finger acceleration of the contact law: the one closest to the free law's command q̈_f
/// in the kinetic-energy norm whose contact point accelerates by a_c (Gauss's least constraint),
/// q̈ = q̈_f + M⁻¹ J_cᵀ (W + δ² 1)⁻¹ (a_c − J_c q̈_f), W = J_c M⁻¹ J_cᵀ, with the damping
/// δ² = [`CONTACT_DAMPING`] tr(W)/3.
///
/// With a regular J_c and δ = 0 this is J_c⁻¹ a_c whatever q̈_f is, the sticking constraint
/// (eq. 27–28). Where J_c is singular (a finger motion that does not move the contact point:
/// joint 1's axis through it, or a folded finger) J_c⁻¹ a_c sends that motion to 1/σ_min(J_c),
/// and the term J̇_c q̇ of a_c feeds the motion's own velocity back through it: a Newton-planned
/// optimum that sticks there (decision 0033) had its joint-1 torque grow as e^{t/σ} to
/// 10¹⁰ N m. Here that motion follows the free law's tracking of q* instead, and the torque
/// it takes is M q̈_f on it, as in free motion.
#[derive(Debug, Clone, Copy)]
struct LeastConstraint<const N: usize> {
    /// M⁻¹ J_cᵀ.
    minv_jct: MatNx3<N>,
    /// J_c.
    j_c: Mat3xN<N>,
    /// (W + δ² 1)⁻¹.
    gain: Mat3,
}

impl<const N: usize> LeastConstraint<N> {
    /// `None` where M is not positive definite.
    fn new(m_f: &MatN<N>, j_c: &Mat3xN<N>) -> Option<Self> {
        let minv_jct = m_f.cholesky()?.solve(&j_c.transpose());
        let w = j_c * minv_jct;
        let delta2 = CONTACT_DAMPING * w.trace() / 3.0;
        let gain = (w + Mat3::identity() * delta2).cholesky()?.inverse();
        Some(LeastConstraint {
            minv_jct,
            j_c: *j_c,
            gain,
        })
    }

    /// q̈ for the contact acceleration `a_c` and the free law's command `qdd_free`.
    fn acceleration(&self, a_c: &Vec3, qdd_free: &VecN<N>) -> VecN<N> {
        qdd_free + self.minv_jct * (self.gain * (a_c - self.j_c * qdd_free))
    }
}

/// The clearance floor h_f and its rate ḣ_f (module doc) at `since` seconds after the last
/// contact and `until` seconds before the next planned one: rising linearly over t_r after a
/// lift-off, falling linearly over t_c before an impact (the nearer of the two decides), h_c
/// in between.
///
/// The rate is part of the guard's target because a lift-off leaves the ball with ḣ = 0: the
/// plan's own ḧ > 0 is all that separates the finger, and on a plant whose links are 5 %
/// heavier than the model that acceleration was negative, so the finger fell back onto the
/// ball within a microsecond and the controller took the touch for the next impact. A floor
/// that is only a position (ω_n² h_f, of order 10⁻⁵ m/s² there) does not see this; its rate
/// asks for ḧ ≥ 2 ω_n h_c / t_r at the lift-off. The rise is shorter than the fall because a
/// fast fall would hold the finger off a plan whose approach is within h_c of the ball for
/// longer than t_r.
fn clearance_floor(cl: &Clearance, since: f64, until: f64) -> (f64, f64) {
    if cl.ramp <= 0.0 && cl.rise <= 0.0 {
        return if since > 0.0 && until > 0.0 {
            (cl.gap, 0.0)
        } else {
            (0.0, 0.0)
        };
    }
    // Each ramp's progress in [0, 1]; a zero-length ramp is complete once its side is open.
    let progress = |elapsed: f64, length: f64| {
        if length > 0.0 {
            elapsed / length
        } else if elapsed > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    };
    let up = progress(since, cl.rise);
    let down = progress(until, cl.ramp);
    let (part, rate) = if up < down {
        (up, if up < 1.0 { cl.gap / cl.rise } else { 0.0 })
    } else {
        (down, if down < 1.0 { -cl.gap / cl.ramp } else { 0.0 })
    };
    if part <= 0.0 {
        (0.0, 0.0)
    } else if part >= 1.0 {
        (cl.gap, 0.0)
    } else {
        (cl.gap * part, rate)
    }
}

/// τ_0 + α (τ_1 − τ_0) with the largest α ∈ [0, 1] inside the bounds |τ_i| ≤ `tau_max[i]`:
/// the feed-forward `base`, scaled (direction kept) to within [`FIT_INNER`] of the bounds, plus
/// as much of the feedback in `full` as the actuators give.
///
/// The command must be continuous in the state, or a plant whose command sits on a bound slides
/// along it in nanosecond steps (a Filippov sliding mode the integrator cannot step over). With
/// the base strictly inside, α is continuous and equals 1 where `full` reaches the bounds, so the
/// command meets `full` there. A base on or beyond a bound made α jump between 0 and 1 wherever
/// the feedback in that joint changed sign.
fn fit_bounds<const N: usize>(tau_max: &[f64; N], base: &[f64; N], full: &[f64; N]) -> [f64; N] {
    let kappa = (0..N)
        .filter(|&i| base[i].abs() > 0.0)
        .map(|i| FIT_INNER * tau_max[i] / base[i].abs())
        .fold(1.0_f64, f64::min);
    let base: [f64; N] = std::array::from_fn(|i| kappa * base[i]);
    let mut alpha: f64 = 1.0;
    for i in 0..N {
        let (a, b, bound) = (base[i], full[i] - base[i], tau_max[i]);
        if b > 0.0 {
            alpha = alpha.min((bound - a) / b);
        } else if b < 0.0 {
            alpha = alpha.min((-bound - a) / b);
        }
    }
    if alpha >= 1.0 {
        return *full;
    }
    let alpha = alpha.max(0.0);
    std::array::from_fn(|i| base[i] + alpha * (full[i] - base[i]))
}

fn to_sim(e: ControlError) -> SimError {
    SimError::system(e)
}

impl<K: Kernels<N>, const N: usize> Input for HybridController<K, N> {
    fn dim(&self) -> usize {
        N
    }

    fn tau(&self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        // Without the ball's state the controller assumes free motion.
        self.tau_in_mode(Mode::Free, t, q, qd, &[0.0; 3], out)
    }

    fn tau_in_mode(
        &self,
        mode: Mode,
        t: f64,
        q: &[f64],
        qd: &[f64],
        omega: &[f64],
        out: &mut [f64],
    ) -> Result<(), SimError> {
        self.clamped_law(&self.state_at(t, mode), mode, t, (q, qd, omega), out)
    }

    fn tau_before(
        &self,
        mode: Mode,
        t: f64,
        q: &[f64],
        qd: &[f64],
        omega: &[f64],
        out: &mut [f64],
    ) -> Result<(), SimError> {
        self.clamped_law(&self.state_before(t), mode, t, (q, qd, omega), out)
    }

    fn wants_force(&self) -> bool {
        true
    }

    fn observe(&self, m: &Measurement<'_>) {
        let mut h = self.history.borrow_mut();
        // A step whose end was measured and then rejected (its projected state failed the
        // validity check) is retried shorter: forget what was recorded after the retry's time.
        while h.len() > 1 && h[h.len() - 1].t > m.t {
            h.pop();
        }
        self.switches.borrow_mut().retain(|s| s.t <= m.t);
        self.plans.borrow_mut().retain(|p| p.t <= m.t);
        let mut d = h[h.len() - 1];
        let plan = self.plan(d.plan);
        let Some(omega) =
            m.x.get(2 * N..2 * N + 3)
                .and_then(|w| <[f64; 3]>::try_from(w).ok())
        else {
            return;
        };
        let dt = m.t - d.t;
        for i in 0..3 {
            d.omega_int[i] += 0.5 * (d.omega_last[i] + omega[i]) * dt;
        }
        d.omega_last = omega;
        self.advance_timed(&plan, &mut d, m.t);
        match m.from {
            None => {
                let ph = &plan.reference.phases[d.phase];
                if let (Some(lambda), true) = (m.lambda, m.mode != Mode::Free)
                    && let Some(s) = State::<N>::from_slice(m.x)
                    && let Ok(kin) = self.model.evaluate(&s)
                {
                    let n = kin.contact.n;
                    let lambda = Vec3::from(lambda);
                    let lambda_n = lambda.dot(&n);
                    if m.mode == Mode::Slip && lambda_n > 0.0 {
                        let mu = (lambda - n * lambda_n).norm() / lambda_n;
                        if mu.is_finite() && mu > 0.0 {
                            d.mu_k = mu;
                        }
                    }
                    let err = ph.lambda_n(m.t - d.start, &n) - lambda_n;
                    let kf = self.gains.contact.force_integral;
                    // Anti-windup: while the actuators saturate, the force error is theirs, not
                    // the integral's to correct.
                    if ph.contact
                        && err.is_finite()
                        && dt > 0.0
                        && m.t - d.start <= ph.duration
                        && !self.saturates(&d, m.mode, m.t, &s)
                    {
                        d.force_int += err * dt / (1.0 + kf * dt);
                    }
                }
            }
            Some(from) => {
                let was_contact = from != Mode::Free;
                let is_contact = m.mode != Mode::Free;
                if was_contact != is_contact {
                    if was_contact {
                        d.lift_off_omega = Vec3::from(omega).norm();
                        d.lift_off_contact = State::<N>::from_slice(m.x)
                            .and_then(|s| self.model.evaluate(&s).ok())
                            .and_then(|kin| kin.contact.r_c.try_normalize(0.0))
                            .map_or([0.0; 3], |u| [u[0], u[1], u[2]]);
                    }
                    let in_contact_phase = plan.reference.phases[d.phase].contact;
                    if in_contact_phase != is_contact {
                        self.advance(&plan, &mut d, m.t, is_contact);
                    }
                    if was_contact {
                        self.replan(&mut d, m.t, m.x);
                        let plan = self.plan(d.plan);
                        if !plan.reference.phases[d.phase].contact {
                            let length = plan.contact_margins(d.phase, 0.0).1;
                            d.flight = Flight::new(m.t, length, d.pace);
                        }
                    }
                    self.switches.borrow_mut().push(PhaseSwitch {
                        t: m.t,
                        phase: d.phase,
                        from,
                        to: m.mode,
                    });
                } else if from == Mode::Stick && m.mode == Mode::Slip {
                    d.slips += 1;
                }
            }
        }
        d.t = m.t;
        d.mode = m.mode;
        h.push(d);
    }
}

#[cfg(test)]
mod tests {
    use super::{Clearance, Flight, PACE_ENDS, clearance_floor, fit_bounds};

    const BOUND: [f64; 3] = [1.0, 2.0, 0.5];

    fn inside(tau: &[f64; 3]) -> bool {
        tau.iter()
            .zip(&BOUND)
            .all(|(v, b)| v.abs() <= b * (1.0 + 1e-12))
    }

    #[test]
    fn a_command_inside_the_bounds_is_kept_and_one_outside_is_brought_inside() {
        let base = [0.3, -0.5, 0.1];
        let full = [0.9, 1.5, -0.4];
        assert_eq!(fit_bounds(&BOUND, &base, &full), full);
        for full in [[3.0, 0.0, 0.0], [0.0, -5.0, 0.2], [-2.0, 4.0, -1.0]] {
            let out = fit_bounds(&BOUND, &base, &full);
            assert!(inside(&out), "{out:?}");
            // On the segment from the base to the full command, and on the boundary.
            let on_bound = out
                .iter()
                .zip(&BOUND)
                .any(|(v, b)| (v.abs() - b).abs() < 1e-12);
            assert!(on_bound, "{out:?}");
        }
    }

    /// The command is continuous where the full command crosses a bound, also when the
    /// feed-forward itself is on or beyond it (the case that jumped: α = 0 on one side of the
    /// crossing, α = 1 on the other).
    #[test]
    fn the_command_is_continuous_where_the_full_command_crosses_a_bound() {
        let jump = |base: &[f64; 3], a: f64, b: f64| {
            let below = fit_bounds(&BOUND, base, &[a, 2.5, 0.1]);
            let above = fit_bounds(&BOUND, base, &[b, 2.5, 0.1]);
            below
                .iter()
                .zip(&above)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        };
        for base in [[1.0, 0.5, 0.0], [1.3, -0.5, 0.2], [0.2, 0.1, 0.0]] {
            for eps in [1e-3, 1e-6, 1e-9] {
                // Across the bound, and where the feedback in the saturated joint changes sign.
                for (a, b) in [(1.0 - eps, 1.0 + eps), (base[0] - eps, base[0] + eps)] {
                    let d = jump(&base, a, b);
                    assert!(d < 50.0 * eps, "base {base:?}, eps {eps}: jump {d}");
                }
            }
        }
    }

    /// A flight's clock: the reference and the plant agree over the first and last 15 %, the
    /// middle runs κ times faster, the flight is (1 − 1/κ) of the middle shorter, and the two
    /// maps are inverse to each other; a flight shorter than 1 s keeps the plan's clock.
    #[test]
    fn a_paced_flight_keeps_its_ends_and_shortens_its_middle() {
        let (start, length, kappa) = (3.0, 10.0, 1.6);
        let f = Flight::new(start, length, kappa);
        let ends = PACE_ENDS * length;
        let middle = length - 2.0 * ends;
        let plant_length = length - middle * (1.0 - 1.0 / kappa);
        // The impact, planned at start + length, comes at start + plant_length.
        let (at_impact, rate) = f.reference_time(start + plant_length);
        assert!((at_impact - (start + length)).abs() < 1e-12);
        assert_eq!(rate, 1.0);
        for k in 0..=200 {
            let t = start + plant_length * f64::from(k) / 200.0;
            let (r, rate) = f.reference_time(t);
            let u = t - start;
            if u <= ends {
                assert_eq!((r, rate), (t, 1.0));
            } else if u < ends + middle / kappa {
                assert_eq!(rate, kappa);
            }
            assert!((f.plant_time(r) - t).abs() < 1e-12, "t = {t}");
        }
        // Before the lift-off's flight and without one, the clocks agree.
        assert_eq!(Flight::NONE.reference_time(7.0), (7.0, 1.0));
        assert_eq!(
            Flight::new(start, 0.9, kappa).reference_time(3.5),
            (3.5, 1.0)
        );
    }

    /// The clearance floor: 0 at a contact, rising at h_c / t_r after a lift-off, h_c away from
    /// the contacts, falling at h_c / t_c before an impact; the nearer contact decides.
    #[test]
    fn the_clearance_floor_rises_after_a_lift_off_and_falls_before_an_impact() {
        let cl = Clearance {
            gap: 5e-3,
            ramp: 0.05,
            rise: 0.02,
        };
        assert_eq!(clearance_floor(&cl, 0.0, 1.0), (0.0, 0.0));
        let (h, rate) = clearance_floor(&cl, 0.01, 1.0);
        assert!((h - 2.5e-3).abs() < 1e-15 && (rate - 0.25).abs() < 1e-12);
        assert_eq!(clearance_floor(&cl, 0.5, 1.0), (5e-3, 0.0));
        let (h, rate) = clearance_floor(&cl, 1.0, 0.025);
        assert!((h - 2.5e-3).abs() < 1e-15 && (rate + 0.1).abs() < 1e-12);
        assert_eq!(clearance_floor(&cl, 1.0, 0.0), (0.0, 0.0));
        // Without ramps the floor is h_c between the contacts and 0 at them.
        let flat = Clearance {
            ramp: 0.0,
            rise: 0.0,
            ..cl
        };
        assert_eq!(clearance_floor(&flat, 0.01, 0.01), (5e-3, 0.0));
        assert_eq!(clearance_floor(&flat, 0.0, 0.01), (0.0, 0.0));
    }
}
