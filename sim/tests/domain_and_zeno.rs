//! Step rejection at a mode's domain boundary and the Zeno fallback hook, on systems with
//! closed-form solutions.
//!
//! * The rotation x' = −y, y' = x stays on the unit circle; its vector field is declared defined
//!   only within |r − 1| ≤ 1e-4 (like the contact modes within the contact band). Explicit RK
//!   stages leave the circle by O(h²), so long trial steps must be rejected and retried shorter,
//!   and the run must still reach t_end on the circle with the exact phase. A system whose
//!   trajectory itself crosses the boundary must stop with the domain error instead of creeping
//!   towards it forever.
//! * A bouncing ball with restitution e < 1 has infinitely many impacts before
//!   t_∞ = t₁ (1 + e)/(1 − e) (from rest at height y₀, t₁ = √(2y₀/g)). Without a fallback the
//!   Zeno guard stops the run; with one that puts the ball to rest, the run continues to t_end
//!   from the accumulation point and the fallback is reported as a warning.

use bf_sim::toys::{BallMode, BouncingBall};
use bf_sim::{Guard, HybridSystem, SimError, SimSettings, Transition, simulate};

/// Unit-circle rotation whose field is defined only near the circle (band `band`), and only
/// for t ≤ `t_wall` (a boundary the trajectory itself crosses). With `at_projection` the band
/// is checked by the projection of each step end instead of by the vector field.
struct Band {
    band: f64,
    t_wall: f64,
    at_projection: bool,
}

impl Band {
    fn outside(&self, t: f64, r: f64) -> SimError {
        SimError::OutsideDomain {
            t,
            mode: "()".into(),
            msg: format!("|r - 1| = {:e}", (r - 1.0).abs()),
        }
    }
}

impl HybridSystem for Band {
    type Mode = ();
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _: (), t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        let r = libm::hypot(x[0], x[1]);
        if (!self.at_projection && (r - 1.0).abs() > self.band) || t > self.t_wall {
            return Err(self.outside(t, r));
        }
        dx[0] = -x[1];
        dx[1] = x[0];
        Ok(())
    }
    fn project(&self, _: (), t: f64, x: &mut [f64]) -> Result<Option<f64>, SimError> {
        let r = libm::hypot(x[0], x[1]);
        if self.at_projection && (r - 1.0).abs() > self.band {
            return Err(self.outside(t, r));
        }
        x[0] /= r;
        x[1] /= r;
        Ok(Some(r - 1.0))
    }
}

#[test]
fn trial_steps_leaving_the_domain_are_retried_shorter() {
    let set = SimSettings {
        rtol: 1e-3,
        atol: 1e-3,
        h_max: 0.5,
        ..SimSettings::default()
    };
    // Stages leave the circle by more than the step ends do: a tighter band for the end check.
    for (at_projection, band) in [(false, 1e-4), (true, 1e-6)] {
        let sys = Band {
            band,
            t_wall: f64::INFINITY,
            at_projection,
        };
        let out = simulate(&sys, set.clone(), (), 0.0, &[1.0, 0.0], 10.0).expect("no abort");
        assert!(
            out.stats.domain_rejections > 0,
            "loose tolerances must push the steps out of the band: {:?}",
            out.stats
        );
        // Every accepted step ended within the band (checked by the projection's drift).
        assert!(out.stats.max_drift <= band, "{:?}", out.stats);
        let x = out.trajectory.x.last().unwrap();
        // The projection keeps r = 1; the phase error is the integrator's (rtol 1e-3, 10 s).
        assert!((x[0] - libm::cos(10f64)).abs() < 2e-2 && (x[1] - libm::sin(10f64)).abs() < 2e-2);
    }
}

#[test]
fn running_into_the_domain_boundary_stops_with_the_domain_error() {
    let sys = Band {
        band: 1.0,
        t_wall: 2.0,
        at_projection: false,
    };
    let fail = simulate(&sys, SimSettings::default(), (), 0.0, &[1.0, 0.0], 5.0)
        .expect_err("the trajectory crosses t = 2");
    assert!(
        matches!(fail.error, SimError::OutsideDomain { .. }),
        "{}",
        fail.error
    );
    // It crept up to the wall, and stopped well before the step limit.
    assert!(fail.t <= 2.0 && fail.t > 2.0 - 1e-3, "{}", fail.t);
    assert!(fail.partial.stats.accepted_steps < 1000);
}

/// The bouncing ball, with a Zeno fallback that puts it to rest on the plane.
struct RestingBall(BouncingBall);

impl HybridSystem for RestingBall {
    type Mode = BallMode;
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn rhs(&self, m: BallMode, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        self.0.rhs(m, t, x, dx)
    }
    fn guards(&self, m: BallMode) -> Vec<Guard> {
        self.0.guards(m)
    }
    fn guard_values(&self, m: BallMode, t: f64, x: &[f64], o: &mut [f64]) -> Result<(), SimError> {
        self.0.guard_values(m, t, x, o)
    }
    fn reset(
        &self,
        m: BallMode,
        g: usize,
        t: f64,
        x: &mut [f64],
    ) -> Result<Transition<BallMode>, SimError> {
        self.0.reset(m, g, t, x)
    }
    fn zeno_fallback(
        &self,
        _mode: BallMode,
        _t: f64,
        x: &mut [f64],
        recent: &[(&'static str, BallMode)],
    ) -> Result<Option<(BallMode, String)>, SimError> {
        assert!(recent.iter().all(|&(_, m)| m == BallMode::Flight));
        x.fill(0.0);
        Ok(Some((BallMode::Resting, "ball put to rest".into())))
    }
}

#[test]
fn zeno_fallback_continues_from_the_accumulation_point_and_is_reported() {
    let (g, e) = (9.81, 0.8);
    let ball = BouncingBall {
        g,
        e,
        drag: 0.0,
        v_rest: None,
    };
    let t_inf = (2.0 / g).sqrt() * (1.0 + e) / (1.0 - e);
    let set = SimSettings::default();
    // Without a fallback: Zeno error (the documented default).
    let fail =
        simulate(&ball, set.clone(), BallMode::Flight, 0.0, &[1.0, 0.0], 10.0).expect_err("Zeno");
    assert!(matches!(fail.error, SimError::Zeno { .. }));
    // With it: the run reaches t_end at rest, with one warning near t_∞.
    let out = simulate(
        &RestingBall(ball),
        set.clone(),
        BallMode::Flight,
        0.0,
        &[1.0, 0.0],
        10.0,
    )
    .expect("the fallback ends the cascade");
    assert_eq!(out.t_final, 10.0);
    assert_eq!(out.mode_final, BallMode::Resting);
    assert_eq!(out.stats.zeno_fallbacks, 1);
    assert_eq!(out.warnings.len(), 1);
    let w = &out.warnings[0];
    assert_eq!(w.kind, "zeno_fallback");
    assert!(w.message.contains("ball put to rest"), "{}", w.message);
    assert!(
        (w.t - t_inf).abs() < 1e-2,
        "fallback at {} vs t_inf {t_inf}",
        w.t
    );
    assert!(out.events.len() > set.zeno_max_events);
}
