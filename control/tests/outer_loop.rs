//! The outer loop on the ball (module doc of `controller`): at the end of a period the
//! measured mean ω̄ moves the contact phases' ω offset, δ ← δ + (γ/ρ) P (ω̄* − ω̄).
//!
//! Every contact force acts at the contact point r_c, so its moment r_c × λ on the ball is
//! normal to r_c (eq. 29b): no contact phase changes the ball's spin about r_c, only the
//! socket damping does. P removes that component of the error; without it an error along
//! r_c (a heavier finger on the Newton-planned `periodic-qc` optimum with a torque margin)
//! wound δ up period after period, its leak into the tangential force saturated the
//! actuators, and the ω error grew to 11.6 % (BENCHMARKS.md, "Outer loop").
//!
//! The test drives the controller with measurements of one period (a free phase, an impact,
//! a stick phase, the lift-off) in which the ball spins with the planned mean plus an error
//! with a part along the lift-off contact point and a part normal to it, and checks δ
//! against the closed form: the normal part corrected with the gain γ (ρ = 1 for a constant
//! ω), nothing along r_c.

use bf_control::Reference;
use bf_control::reference::Samples;
use bf_model::{Mode, State, Vec3, VecN};
use bf_sim::{Input, Measurement};

mod common;

use common::TOUCHING;

/// A plan of a free phase of `free` s and a stick phase of `stick` s at the posture
/// [`TOUCHING`], the ball spinning at `omega_star` throughout (the mean ω̄* too).
fn constant_spin_plan(
    model: &bf_model::Model<bf_model::PaperKernels>,
    free: f64,
    stick: f64,
    omega_star: Vec3,
) -> Reference {
    let row = |v: [f64; 3]| vec![v.to_vec(); 4];
    let t = [0.0, free, free, free + stick];
    let phase = [0, 0, 1, 1];
    let (qs, zeros) = (row(TOUCHING), row([0.0; 3]));
    let w = [omega_star[0], omega_star[1], omega_star[2]];
    Reference::from_samples(
        model,
        &[false, true],
        &[free, stick],
        Samples {
            t: &t,
            phase: &phase,
            q: &qs,
            qd: &zeros,
            omega: &row(w),
            tau: &zeros,
            lambda: &zeros,
        },
        w,
    )
    .unwrap()
}

#[test]
fn the_outer_loop_corrects_the_error_the_contact_can_change_and_nothing_along_r_c() {
    let model = bf_model::fixtures::paper_scene().unwrap();
    let q = TOUCHING;
    let rest = State::new(VecN::from(q), VecN::zeros(), Vec3::zeros());
    let kin = model.evaluate(&rest).unwrap();
    assert!(kin.contact.h.abs() < 1e-12, "h = {}", kin.contact.h);
    let axis = kin.contact.r_c.normalize();

    // The plan: a free phase and a stick phase of 0.05 s each, the ball spinning at ω*
    // throughout (so the offset's bound 0.5 ‖ω*_lo‖ is 1 rad/s, far from what one period
    // asks for).
    let omega_star = Vec3::new(0.0, 0.0, 2.0);
    assert!(axis.dot(&omega_star).abs() < 1e-9, "ω* along r_c");
    let reference = constant_spin_plan(&model, 0.05, 0.05, omega_star);
    let (law, gains) = common::controller(&model, reference, q);

    // The measured ball: ω* plus 0.3 rad/s along r_c and 0.1 rad/s normal to both.
    let normal = axis.cross(&omega_star).normalize();
    let omega = omega_star + axis * 0.3 + normal * 0.1;
    let x: Vec<f64> = q
        .iter()
        .copied()
        .chain([0.0; 3])
        .chain(omega.iter().copied())
        .collect();
    let step = |t: f64, mode: Mode, from: Option<Mode>| {
        law.observe(&Measurement {
            t,
            mode,
            from,
            x: &x,
            lambda: None,
        })
    };
    step(0.0, Mode::Free, None);
    for k in 1..=5 {
        step(0.01 * k as f64, Mode::Free, None);
    }
    step(0.05, Mode::Stick, Some(Mode::Free));
    for k in 6..=10 {
        step(0.01 * k as f64, Mode::Stick, None);
    }
    assert_eq!(law.periods(), 0);
    step(0.1, Mode::Free, Some(Mode::Stick));
    assert_eq!(
        law.periods(),
        1,
        "the lift-off after the last phase ends the period"
    );

    // ρ = ‖ω̄‖ / ‖ω_lo‖ = 1 for a constant ω: δ = γ P (ω* − ω) = −γ 0.1 n̂.
    let delta = Vec3::from(law.omega_offset());
    let want = normal * (-gains.outer * 0.1);
    assert!(
        (delta - want).norm() < 1e-9,
        "δ = {delta}, expected {want} (r̂_c = {axis})"
    );
    assert!(
        delta.dot(&axis).abs() < 1e-12,
        "δ has {} rad/s along r_c, which no contact force can produce",
        delta.dot(&axis)
    );
}

/// A plan whose flight is long enough to pace (2 s, at least `PACE_MIN_FLIGHT` = 1 s): the
/// flight's pace takes the whole error along ω̄* and δ none of the error, across ω̄* included.
/// In a flight the ball's spin only decays (eq. 29b, I_b ω̇ = −D ω for the solid sphere), so a
/// flight changes the period's mean by its length, never its direction; a δ across ω̄* asked
/// the end of a stick phase for tangential force while λ_n fell to zero, and on the low
/// `periodic-cot` plans the slip it caused drove the spin about the vertical away period after
/// period (decision record 0056).
///
/// Two periods of a free phase of 2 s and a stick phase of 0.05 s: the first (from the start,
/// so without a lift-off to pace from) at ω*, the second (from its lift-off, paced) at
/// 0.8 ω* plus 0.1 rad/s across it. Closed form of the pace: the period should become
/// T (ω̄ · ω̂* / ‖ω̄*‖)^γ_κ = 2.05 · 0.8 = 1.64 s, so the flight's middle (2 s less 15 % at
/// each end, 1.4 s) must take 1.4 − (2.05 − 1.64) = 0.99 s: κ = 1.4 / 0.99.
#[test]
fn a_paced_flight_corrects_the_mean_by_its_pace_and_leaves_delta_alone() {
    let model = bf_model::fixtures::paper_scene().unwrap();
    let q = TOUCHING;
    let rest = State::new(VecN::from(q), VecN::zeros(), Vec3::zeros());
    let axis = model.evaluate(&rest).unwrap().contact.r_c.normalize();
    let omega_star = Vec3::new(0.0, 0.0, 2.0);
    let reference = constant_spin_plan(&model, 2.0, 0.05, omega_star);
    let (law, gains) = common::controller(&model, reference, q);
    assert_eq!(gains.pace, 1.0, "the closed form below takes γ_κ = 1");

    let state = |omega: Vec3| -> Vec<f64> {
        q.iter()
            .copied()
            .chain([0.0; 3])
            .chain(omega.iter().copied())
            .collect()
    };
    let normal = axis.cross(&omega_star).normalize();
    let period = |t0: f64, omega: Vec3| {
        let x = state(omega);
        let step = |t: f64, mode: Mode, from: Option<Mode>| {
            law.observe(&Measurement {
                t,
                mode,
                from,
                x: &x,
                lambda: None,
            })
        };
        // The period's first sample: at the start, or right after the lift-off that ended
        // the last period (no time passes, so the mean is this period's ω alone).
        step(t0, Mode::Free, None);
        for k in 1..=20 {
            step(t0 + 0.1 * k as f64, Mode::Free, None);
        }
        step(t0 + 2.0, Mode::Stick, Some(Mode::Free));
        for k in 1..=5 {
            step(t0 + 2.0 + 0.01 * k as f64, Mode::Stick, None);
        }
        step(t0 + 2.05, Mode::Free, Some(Mode::Stick));
    };
    period(0.0, omega_star);
    assert_eq!(law.periods(), 1);
    assert_eq!(law.omega_offset(), [0.0; 3], "no error, no offset");
    assert_eq!(law.pace(), 1.0, "an unpaced first period leaves the pace");

    period(2.05, omega_star * 0.8 + normal * 0.1);
    assert_eq!(law.periods(), 2);
    assert_eq!(
        law.omega_offset(),
        [0.0; 3],
        "a paced flight leaves δ alone, also across ω̄*"
    );
    let want = 1.4 / (1.4 - (2.05 - 2.05 * 0.8));
    assert!(
        (law.pace() - want).abs() < 1e-9,
        "κ = {}, expected {want}",
        law.pace()
    );
}
