//! [`Constants`]: the physical constants of a scene with a ball that are not on the robot's
//! expression graph, read once from a [`Scene`] by both the physics layer (bf-model) and the
//! optimal-control problem (bf-problem):
//!
//! - I_b, the ball inertia about its centre (eq. 25; default (2/5) m r² 1, which follows a
//!   runtime radius or mass), and the radius r (eq. 4);
//! - the Coulomb coefficients μ_s (stick cone, eq. 18–19) and μ_k (slip force, eq. 20);
//! - joint viscous friction μ_v (eq. 24) and ball–socket damping D (eq. 25);
//! - the joint limits q_min, q_max and torque limits τ_max that the problems use as bounds.
//!
//! Runtime parameters ([`Scene::runtime_parameters`]) may override the ball and friction values
//! of a compiled kernel set ([`Constants::with_runtime_parameters`]); the names are those of the
//! constant registry [`Scene::constants`].

use crate::Scene;

/// The ball, friction and limit constants of a scene with a `[ball]` (see the module docs).
/// Without a `[friction]` section the friction constants are 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Constants {
    /// Number of joints n.
    pub nq: usize,
    /// Ball inertia I_b about its centre (kg m², row-major), eq. 25.
    pub ib: [[f64; 3]; 3],
    /// Ball radius r (m).
    pub radius: f64,
    /// Ball mass m (kg).
    pub ball_mass: f64,
    /// Whether the scene gives I_b; otherwise it is the default (2/5) m r² 1 and follows the
    /// runtime parameters `ball.radius` and `ball.mass`.
    pub inertia_given: bool,
    /// Static Coulomb coefficient μ_s.
    pub mu_s: f64,
    /// Kinetic Coulomb coefficient μ_k.
    pub mu_k: f64,
    /// Joint viscous friction μ_v (N m s/rad).
    pub mu_v: f64,
    /// Ball–socket damping D (N m s).
    pub damping: f64,
    /// Joint limits (q_min, q_max) in radians; ±∞ where the scene gives none.
    pub q_limits: Vec<(f64, f64)>,
    /// Torque limits τ_max (N m); ∞ where the scene gives none.
    pub tau_max: Vec<f64>,
}

impl Constants {
    /// The constants of `scene`; `None` if it has no `[ball]`.
    pub fn of(scene: &Scene) -> Option<Constants> {
        let ball = scene.ball.as_ref()?;
        let (mu_s, mu_k, mu_v, damping) =
            scene.friction.as_ref().map_or((0.0, 0.0, 0.0, 0.0), |f| {
                (f.mu_s, f.mu_k, f.mu_v, f.socket_damping)
            });
        Some(Constants {
            nq: scene.links.len(),
            ib: ball.inertia_matrix(),
            radius: ball.radius,
            ball_mass: ball.mass,
            inertia_given: ball.inertia.is_some(),
            mu_s,
            mu_k,
            mu_v,
            damping,
            q_limits: scene
                .links
                .iter()
                .map(|l| {
                    (
                        l.q_min.unwrap_or(f64::NEG_INFINITY),
                        l.q_max.unwrap_or(f64::INFINITY),
                    )
                })
                .collect(),
            tau_max: scene
                .links
                .iter()
                .map(|l| l.tau_max.unwrap_or(f64::INFINITY))
                .collect(),
        })
    }

    /// These constants with the values of the runtime parameters `names` (registry names such
    /// as `"ball.radius"`, `"ball.inertia.xy"`, `"friction.mu_s"`) replaced by `values` (same
    /// order). Off-diagonal inertia entries set both symmetric entries; names of constants that
    /// are not held here (link geometry, link masses, ...) are ignored. A default inertia
    /// (none given by the scene or by `ball.inertia.*`) is that of the solid sphere of the
    /// runtime radius and mass, as a scene file with those values would have.
    pub fn with_runtime_parameters(mut self, names: &[&str], values: &[f64]) -> Constants {
        for (name, &v) in names.iter().zip(values) {
            let ib = &mut self.ib;
            if name.starts_with("ball.inertia.") {
                self.inertia_given = true;
            }
            match *name {
                "ball.radius" => self.radius = v,
                "ball.mass" => self.ball_mass = v,
                "ball.inertia.xx" => ib[0][0] = v,
                "ball.inertia.yy" => ib[1][1] = v,
                "ball.inertia.zz" => ib[2][2] = v,
                "ball.inertia.xy" => (ib[0][1], ib[1][0]) = (v, v),
                "ball.inertia.xz" => (ib[0][2], ib[2][0]) = (v, v),
                "ball.inertia.yz" => (ib[1][2], ib[2][1]) = (v, v),
                "friction.mu_s" => self.mu_s = v,
                "friction.mu_k" => self.mu_k = v,
                "friction.mu_v" => self.mu_v = v,
                "friction.socket_damping" => self.damping = v,
                _ => {}
            }
        }
        if !self.inertia_given {
            let j = 0.4 * self.ball_mass * self.radius * self.radius;
            self.ib = [[j, 0.0, 0.0], [0.0, j, 0.0], [0.0, 0.0, j]];
        }
        self
    }
}
