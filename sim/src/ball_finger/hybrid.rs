//! [`HybridSystem`] implementation of [`BallFinger`] (paper Sect. 2.6–3, Fig. 2–3).
//!
//! | mode | vector field | guards (region: valid while g > 0, all `Falling`) |
//! |---|---|---|
//! | Free | eq. 26 | `h` (eq. 50: contact when h crosses 0 or leaves the band h ≥ −tol) |
//! | Stick | eq. 29, λ from eq. 33 | `lambda_n` (λ_n < 0 → Free, eq. 48), `sigma` (σ ≤ 0 → Slip, eq. 19) |
//! | Slip | eq. 37, λ from eq. 38 | `lambda_n` (→ Free), `slip_speed` = ‖Δv‖ − ε (→ Stick, Sect. 3.1), `slip_reversal` = Δv·d₀ − ½‖Δv‖ (Δv turned > 60° within a step: it passed ‖Δv‖ ≈ 0, → Stick), `slip_stop` = Δv̂·Δv(x + h ẋ) (with a fixed step h only: the slip would stop within the step, → Stick; [`slip_stop`]) |
//! | Stick, Slip | | `alpha_tip` = α, `alpha_base` = α + ℓ (either direction): the kinks of sat(α), eq. 3 (see below) |
//!
//! Resets: Free → impact law of Sect. 2.5 (eq. 39–43, [`bf_model::ImpactLaw`]); the post-impact ‖Δv⁺‖
//! picks Stick or Slip (Fig. 3's "In-contact" state). Stick → Slip: velocity kick Δv⁺ =
//! `slip_kick` along λ_∥ (so the slip guard does not fire back). Slip → Stick: projection onto
//! Δv = 0 with the sticking impulse (eq. 40–41). Contact → Free: q back onto h = 0 and a tiny
//! normal impulse sets n·v_c⁺ = `lift_off_speed` (1e-8 m/s) so the h guard does not chatter at
//! λ_n = 0. An h crossing in Free while n·v_c > 0 (interpolation error at a graze) puts q back
//! on h = 0 and stays Free instead of applying an impact to a separating finger. When the
//! new mode is already invalid (e.g. λ_n < 0 right after a sticking impact) the simulator chains
//! the next transition at the same instant.
//!
//! # Non-smooth points of the contact geometry
//! The finger's last link is the segment from joint N to the fingertip p_e (Sect. 2.2); the
//! potential contact point p_c = p_e + sat(α) e_x3 (eq. 3) has two kinks, α = 0 (p_c reaches the
//! fingertip: the contact passes between the link's side and its end point) and α = −ℓ (p_c
//! reaches the link's base, joint N; ℓ = a_N). At both, h (eq. 4, the distance to a convex set,
//! C¹ away from it), n (eq. 11), J_c (eq. 7) and v_c (eq. 6) are continuous, so at h = 0 the
//! conditions h = 0 (eq. 8) and n·v_c = 0 (eq. 10) hold on both sides and no impulse is needed.
//! But d sat(α)/dt jumps between α̇ and 0, so ṙ_c and J̇_c q̇ in the bias of eq. 33 and in the
//! normal-constraint acceleration of eq. 36–38 jump: λ and the accelerations are discontinuous
//! there. Hence in Stick and Slip the guards `alpha_tip` and `alpha_base` locate the crossing on
//! the dense output (event kind `kink`) and the reset keeps state and mode: the contact
//! persists on the other part of the link (the end point or the side), and whether it persists
//! beyond that instant is decided by the new geometry's λ_n (eq. 48: λ_n < 0 lifts off at once,
//! e.g. when the tip's path curves away from the ball) and σ (eq. 19: Stick → Slip), which the
//! simulator checks right after the reset (chained transitions). Free motion needs no kink
//! events: its vector field does not involve the contact and its guard h is C¹. The only other
//! non-smooth point, |r_c| = 0 (n undefined), cannot occur near contact (|r_c| = r + h).
//! Besides, a trial step whose stage or end state leaves the contact band |h| ≤
//! `contact_tolerance`·r is rejected and retried shorter ([`SimError::OutsideDomain`]), so a
//! step cannot jump out of the contact modes' domain. So is a Slip stage where eq. 37 has no
//! unique normal force (Painlevé, k = nᵀ W (n + μ_k t̂) ≤ 0): a stage past the slip's stop has
//! Δv, and so t̂, reversed, which with a large μ_k alone makes k negative; a paradox on the
//! trajectory itself still ends the run.
//!
//! # Zeno fallback
//! More than `SimSettings::zeno_max_events` events within `zeno_window` (an accumulation of
//! events, e.g. the contact point chattering at a kink, or impact / lift-off or stick / slip
//! chatter) calls [`HybridSystem::zeno_fallback`], which ends the cascade for
//! `BallFingerSettings::zeno_hold_time` seconds and is reported as a `zeno_fallback` warning:
//! * only kink events: the kink guards are suspended (the mode continues; the error control
//!   shortens the steps across the kink);
//! * otherwise: the contact is made sticking (q projected onto h = 0, velocities onto Δv = 0 by
//!   the sticking impulse of eq. 40–41, which never adds energy) and held in Stick regardless of
//!   λ_n and σ (the lift-off and stick → slip guards are suspended; the sticking force does no
//!   work). When the hold ends the guards take over again.
//! # Energy warnings
//! Drift control (Sect. 3.1 "we also allow h(q) to drift"): after each accepted step in a
//! contact mode, q is projected back onto h(q) = 0 by Gauss–Newton along ∇h = J_cᵀ n, then the
//! velocities onto the mode's constraint (Stick: Δv = 0 via the sticking impulse; Slip:
//! n·v_c = 0 by the M_f-norm-minimal change of q̇). The reported drift is |h| before projection
//! (m).

use super::{BallFinger, Hold, state_of, write_velocities};
use crate::{Guard, HybridSystem, Input, Measurement, SimError, Transition};
use bf_model::dynamics::contact_matrices;
use bf_model::{Kernels, Mode, State, Vec3};

/// The `slip_reversal` guard fires when Δv turns by more than arccos(0.5) = 60° from its
/// direction at the start of the step: in continuous slip the direction of Δv changes slowly
/// unless ‖Δv‖ passes (close to) zero, which is the Slip → Stick condition of Sect. 3.1. It
/// catches the zero passage that the ‖Δv‖ ≤ ε guard misses when a step jumps over the ε-ball
/// (loose tolerances, fixed-step RK4).
const REVERSAL_COS: f64 = 0.5;

/// The `slip_stop` guard: the slip Δv′ one fixed step ahead (the state moved along its
/// derivative, x + h ẋ) along the slip's direction now, Δv̂·Δv′. It falls through zero where
/// the slip would stop within one step. A fixed-step explicit method cannot resolve that stop:
/// the friction force turns within its stages, and the iteration hovers at ‖Δv‖ ≈ a h / 2 (a
/// the slip's deceleration), in a numerical sliding mode that neither `slip_speed` (‖Δv‖ = ε)
/// nor `slip_reversal` ever sees; so with a fixed step the slip ends at most one step before
/// its true stop (the sticking impulse removes the ‖Δv‖ ≤ a h left), and the error falls with
/// h. Adaptive methods shorten their steps onto the stop and leave the guard constant.
fn slip_stop(dv: &Vec3, dv_ahead: &Vec3) -> f64 {
    let n = dv.norm();
    if n > 0.0 && n.is_finite() {
        dv_ahead.dot(dv) / n
    } else {
        0.0
    }
}

/// Value of a guard suspended by the Zeno fallback: constant and on the valid side, so it
/// neither fires nor masks; when the hold ends the true value takes over (a crossing there is an
/// ordinary event).
const HELD_GUARD: f64 = 1.0;

/// Guards of the contact modes besides their transitions: the kinks of sat(α) (eq. 3).
const KINK_GUARDS: [Guard; 2] = [Guard::either("alpha_tip"), Guard::either("alpha_base")];

impl<K: Kernels<N>, I: Input, const N: usize> BallFinger<K, I, N> {
    /// Values of the kink guards at contact geometry `c`: α (m; 0 where p_c reaches the
    /// fingertip p_e) and α + ℓ (m; 0 where p_c reaches the link's base, joint N).
    fn kink_values(&self, c: &bf_model::ContactGeometry<N>, t: f64, out: &mut [f64]) {
        let hold = self.hold.get();
        if hold.kinks && t < hold.until {
            out.fill(HELD_GUARD);
        } else {
            out[0] = c.alpha;
            out[1] = c.alpha + self.link_length;
        }
    }

    /// Whether the contact-mode transition guards are held by the Zeno fallback at `t`.
    fn contact_held(&self, t: f64) -> bool {
        let hold = self.hold.get();
        hold.contact && t < hold.until
    }

    /// The drift control of [`HybridSystem::project`] (module doc), without the measurement.
    fn project_state(&self, mode: Mode, t: f64, x: &mut [f64]) -> Result<Option<f64>, SimError> {
        let err = Self::model_err(mode, t);
        if mode == Mode::Slip {
            // The slip_reversal guard of the next step compares Δv with its direction now.
            let s = state_of::<N>(x)?;
            let kin = self.model.evaluate(&s).map_err(&err)?;
            self.set_slip_ref(&kin.contact.delta_v);
        }
        if mode == Mode::Free || !self.settings.project {
            return Ok(None);
        }
        let mut s = state_of::<N>(x)?;
        let drift = self.project_position(&mut s)?;
        match mode {
            Mode::Stick => {
                let out = self.model.slip_to_stick_update(&s).map_err(&err)?;
                s.qd = out.qd;
                s.omega = out.omega;
            }
            Mode::Slip => {
                let kin = self.model.evaluate(&s).map_err(&err)?;
                let mats = contact_matrices(&kin, self.model.params()).map_err(&err)?;
                let n = kin.contact.n;
                let vn = n.dot(&kin.contact.v_c);
                if mats.n_w_n > 0.0 {
                    s.qd -= mats.minv_jct * n * (vn / mats.n_w_n);
                }
            }
            Mode::Free => {}
        }
        s.write_slice(x);
        if mode == Mode::Slip {
            let kin = self.model.evaluate(&s).map_err(&err)?;
            self.set_slip_ref(&kin.contact.delta_v);
        }
        Ok(drift)
    }

    /// The Zeno fallback of [`HybridSystem::zeno_fallback`] (module doc), without the measurement.
    fn zeno_fallback_state(
        &self,
        mode: Mode,
        t: f64,
        x: &mut [f64],
        recent: &[(&'static str, Mode)],
    ) -> Result<Option<(Mode, String)>, SimError> {
        let is_kink = |g: &str| KINK_GUARDS.iter().any(|k| k.name == g);
        let kinks = recent.iter().any(|(g, _)| is_kink(g));
        let hold = self.settings.zeno_hold_time;
        let mut names: Vec<(&str, usize)> = Vec::new();
        for (g, _) in recent {
            match names.iter_mut().find(|(n, _)| n == g) {
                Some((_, c)) => *c += 1,
                None => names.push((g, 1)),
            }
        }
        let names: Vec<String> = names.iter().map(|(n, c)| format!("{n} {c}")).collect();
        let names = names.join(", ");
        if mode != Mode::Free && recent.iter().all(|(g, _)| is_kink(g)) {
            // This hold replaces a contact hold still running: that one ends here.
            if let Some(last) = self.contact_holds.borrow_mut().last_mut() {
                last.1 = last.1.min(t);
            }
            self.hold.set(Hold {
                until: t + hold,
                kinks: true,
                contact: false,
            });
            return Ok(Some((
                mode,
                format!(
                    "the contact point chatters across a kink of sat(alpha) (eq. 3; {names}): \
                     kink events suspended for {hold} s, steps across the kink are shortened \
                     by the error control"
                ),
            )));
        }
        // Chatter between contact and free motion or between stick and slip: hold a sticking
        // contact (Δv = 0 by the dissipative sticking projection, eq. 40–41).
        let mut s = state_of::<N>(x)?;
        let tol = self.model.settings().contact_tolerance * self.model.params().ball_radius();
        if self.gap(x)?.abs() > tol {
            return Ok(None);
        }
        self.project_position(&mut s)?;
        let out = self
            .model
            .slip_to_stick_update(&s)
            .map_err(SimError::system)?;
        s.qd = out.qd;
        s.omega = out.omega;
        s.write_slice(x);
        self.hold.set(Hold {
            until: t + hold,
            kinks,
            contact: true,
        });
        self.contact_holds.borrow_mut().push((t, t + hold));
        Ok(Some((
            Mode::Stick,
            format!(
                "mode chatter ({names}): sticking contact held for {hold} s regardless of \
                 lambda_n and sigma (eq. 48, 19)"
            ),
        )))
    }
}

impl<K: Kernels<N>, I: Input, const N: usize> HybridSystem for BallFinger<K, I, N> {
    type Mode = Mode;

    fn dim(&self) -> usize {
        State::<N>::DIM
    }

    fn rhs(&self, mode: Mode, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        let s = state_of::<N>(x)?;
        let tau = self.tau(mode, t, &s)?;
        let acc = self
            .model
            .accelerations(mode, &s, &tau)
            .map_err(Self::model_err(mode, t))?;
        acc.write_state_derivative(&s.qd, dx);
        Ok(())
    }

    fn guards(&self, mode: Mode) -> Vec<Guard> {
        let mut g = match mode {
            Mode::Free => return vec![Guard::falling("h")],
            Mode::Stick => vec![Guard::falling("lambda_n"), Guard::falling("sigma")],
            Mode::Slip => vec![
                Guard::falling("lambda_n"),
                Guard::falling("slip_speed"),
                Guard::falling("slip_reversal"),
                Guard::falling("slip_stop"),
            ],
        };
        g.extend(KINK_GUARDS);
        g
    }

    fn guard_values(&self, mode: Mode, t: f64, x: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        let s = state_of::<N>(x)?;
        let err = Self::model_err(mode, t);
        match mode {
            Mode::Free => {
                // Only the contact kernel is needed for h (no mass matrix).
                s.check_finite().map_err(SimError::system)?;
                let c = self.model.kernels().contact(
                    &s.q.into(),
                    &s.qd.into(),
                    &s.omega.into(),
                    self.model.contact_variant(),
                );
                out[0] = c.h;
            }
            Mode::Stick => {
                let tau = self.tau(Mode::Stick, t, &s)?;
                let kin = self.model.evaluate(&s).map_err(&err)?;
                let acc = bf_model::dynamics::stick(
                    &kin,
                    self.model.params(),
                    &tau,
                    self.model.settings(),
                )
                .map_err(&err)?;
                if self.contact_held(t) {
                    out[..2].fill(HELD_GUARD);
                } else {
                    out[0] = acc.force.lambda_n;
                    out[1] = acc.force.sigma;
                }
                self.kink_values(&kin.contact, t, &mut out[2..]);
            }
            Mode::Slip => {
                let tau = self.tau(Mode::Slip, t, &s)?;
                let kin = self.model.evaluate(&s).map_err(&err)?;
                let acc = bf_model::dynamics::slip(
                    &kin,
                    self.model.params(),
                    &tau,
                    self.model.settings(),
                    None,
                )
                .map_err(&err)?;
                let dv = kin.contact.delta_v;
                if self.contact_held(t) {
                    out[..4].fill(HELD_GUARD);
                } else {
                    out[0] = acc.force.lambda_n;
                    out[1] = dv.norm() - self.model.settings().slip_eps;
                    let d = Vec3::from(self.slip_ref.get());
                    out[2] = if d == Vec3::zeros() {
                        dv.norm()
                    } else {
                        dv.dot(&d) - REVERSAL_COS * dv.norm()
                    };
                    out[3] = match self.fixed_step.get() {
                        Some(h) => {
                            // x + h ẋ, without leaving the stack (this runs at every guard
                            // evaluation of a fixed-step slip).
                            let ahead = State::new(
                                s.q + s.qd * h,
                                s.qd + acc.qdd * h,
                                s.omega + acc.omega_dot * h,
                            );
                            let dv_ahead = self.model.evaluate(&ahead).map_err(&err)?;
                            slip_stop(&dv, &dv_ahead.contact.delta_v)
                        }
                        None => HELD_GUARD,
                    };
                }
                self.kink_values(&kin.contact, t, &mut out[4..]);
            }
        }
        Ok(())
    }

    fn reset(
        &self,
        mode: Mode,
        guard: usize,
        t: f64,
        x: &mut [f64],
    ) -> Result<Transition<Mode>, SimError> {
        let s = state_of::<N>(x)?;
        let name = self.guards(mode).get(guard).map_or("", |g| g.name);
        if KINK_GUARDS.iter().any(|g| g.name == name) {
            // The contact point passed a kink of sat(α): h, n, J_c and the velocities are
            // continuous there, so the contact persists in the same mode; the new geometry's
            // λ_n and σ are checked at once by the mode's guards (chained transition).
            return Ok(Transition::To(mode));
        }
        let next = match (mode, guard) {
            (Mode::Free, _) => {
                let kin = self.model.evaluate(&s).map_err(SimError::system)?;
                if kin.contact.normal_velocity() > self.model.settings().hdot_eps {
                    // h crossed zero on the interpolant while the finger separates (n·v_c > 0):
                    // a grazing touch seen through interpolation error, not an impact. Put q
                    // back on the surface and continue in Free; the guard then sees h rise.
                    let mut s = s;
                    self.project_position(&mut s)?;
                    x[..N].copy_from_slice(s.q.as_slice());
                    return Ok(Transition::To(Mode::Free));
                }
                let mut s = s;
                let tol =
                    self.model.settings().contact_tolerance * self.model.params().ball_radius();
                if kin.contact.h.abs() > tol {
                    // The located event state lies beyond the contact band (an interpolant far
                    // from the solution, e.g. a fixed step far too long): apply the impact law
                    // on the surface h = 0 instead of refusing it.
                    self.project_position(&mut s)?;
                    x[..N].copy_from_slice(s.q.as_slice());
                }
                let out = self
                    .model
                    .impact(&s, self.settings.impact_law)
                    .map_err(SimError::system)?;
                write_velocities(x, &out.qd, &out.omega);
                self.set_slip_ref(&out.delta_v);
                out.mode
            }
            (Mode::Stick | Mode::Slip, 0) => {
                // Leave the contact from the surface (the contact mode let h drift), so the
                // Free mode's h guard starts on its surface and sees the departure.
                let mut s = s;
                if self.settings.project {
                    self.project_position(&mut s)?;
                    x[..N].copy_from_slice(s.q.as_slice());
                }
                let sep = self.settings.lift_off_speed;
                if sep > 0.0 {
                    let kin = self.model.evaluate(&s).map_err(SimError::system)?;
                    let vn = kin.contact.normal_velocity();
                    if vn < sep {
                        let mats = contact_matrices(&kin, self.model.params())
                            .map_err(SimError::system)?;
                        if mats.n_w_n > 0.0 {
                            let qd =
                                s.qd + mats.minv_jct * kin.contact.n * ((sep - vn) / mats.n_w_n);
                            x[N..2 * N].copy_from_slice(qd.as_slice());
                        }
                    }
                }
                Mode::Free
            }
            (Mode::Stick, _) => {
                let tau = self.tau(Mode::Stick, t, &s)?;
                let acc = self.model.stick(&s, &tau).map_err(SimError::system)?;
                let out = self
                    .model
                    .stick_to_slip_update(&s, &acc.force)
                    .map_err(SimError::system)?;
                write_velocities(x, &out.qd, &out.omega);
                self.set_slip_ref(&out.delta_v);
                Mode::Slip
            }
            (Mode::Slip, _) => {
                let out = self
                    .model
                    .slip_to_stick_update(&s)
                    .map_err(SimError::system)?;
                write_velocities(x, &out.qd, &out.omega);
                Mode::Stick
            }
        };
        self.input.observe(&Measurement {
            t,
            mode: next,
            from: Some(mode),
            x,
            lambda: None,
        });
        Ok(Transition::To(next))
    }

    fn fixed_step(&self, h: Option<f64>) {
        self.fixed_step.set(h);
    }

    fn project(&self, mode: Mode, t: f64, x: &mut [f64]) -> Result<Option<f64>, SimError> {
        let drift = self.project_state(mode, t, x)?;
        let lambda = if self.input.wants_force() && mode != Mode::Free {
            // What a force sensor at the contact reads at the step's end: the mode's λ under
            // the input's own torques.
            let s = state_of::<N>(x)?;
            let tau = self.tau(mode, t, &s)?;
            let acc = self
                .model
                .accelerations(mode, &s, &tau)
                .map_err(Self::model_err(mode, t))?;
            Some(acc.force.lambda.into())
        } else {
            None
        };
        self.input.observe(&Measurement {
            t,
            mode,
            from: None,
            x,
            lambda,
        });
        Ok(drift)
    }

    fn zeno_fallback(
        &self,
        mode: Mode,
        t: f64,
        x: &mut [f64],
        recent: &[(&'static str, Mode)],
    ) -> Result<Option<(Mode, String)>, SimError> {
        let out = self.zeno_fallback_state(mode, t, x, recent)?;
        if let Some((next, _)) = &out {
            self.input.observe(&Measurement {
                t,
                mode: *next,
                from: Some(mode),
                x,
                lambda: None,
            });
        }
        Ok(out)
    }

    fn check_valid(&self, mode: Mode, t: f64, x: &[f64]) -> Result<(), SimError> {
        if mode == Mode::Free {
            return Ok(());
        }
        let h = self.gap(x)?;
        let tol = self.model.settings().contact_tolerance * self.model.params().ball_radius();
        if h.abs() > tol {
            // Outside the contact modes' domain: a trial step ending here is retried shorter.
            return Err(SimError::OutsideDomain {
                t,
                mode: format!("{mode:?}"),
                msg: format!("contact drift |h| = {:e} m exceeds {tol:e} m", h.abs()),
            });
        }
        Ok(())
    }
}
