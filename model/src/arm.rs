//! Free motion of a robot arm with any number of joints (no ball): the joint-space dynamics
//! M(q) q̈ = τ − C(q, q̇) q̇ − g(q) − μ_v q̇ (eq. 22–24, 26 without the ball) on the scene's
//! `mass_cqd_g` and `potential` kernels, compiled (the registry entry, when the scene is a
//! compiled one) or interpreted from the same graphs, for any NQ (slices, no fixed size).
//!
//! - [`ArmModel::from_scene`]: the model of a parsed scene and its [`KernelSource`].
//! - [`ArmModel::accelerations`]: q̈ by a Cholesky factorisation of M (an error if M is not
//!   positive definite or a value is not finite).
//! - [`ArmModel::energy`]: E = ½ q̇ᵀ M q̇ + U(q), whose rate is τ·q̇ − μ_v |q̇|² (the power
//!   balance the simulator's energy check integrates).

use bf_codegen::interp::Tape;
use bf_codegen::spec::Scene;
use bf_generated::{MassCqdGFn, PotentialFn};
use nalgebra::{DMatrix, DVector};

use crate::registry::{InterpretedTapes, KernelSource, compiled_match, interpreted_tapes};
use crate::{ModelError, Result};

fn scene_err(scene: &str, message: impl Into<String>) -> ModelError {
    ModelError::Scene {
        scene: scene.to_string(),
        message: message.into(),
    }
}

#[derive(Debug, Clone)]
enum Backend {
    Compiled {
        mass_cqd_g: MassCqdGFn,
        potential: PotentialFn,
        p: Vec<f64>,
    },
    // Boxed: a tape is several vectors, much larger than the compiled variant.
    Interpreted {
        mass_cqd_g: Box<Tape>,
        potential: Box<Tape>,
        layout: bf_codegen::robot::Layout,
        base_vars: Vec<f64>,
    },
}

/// The free-motion model of an arm (see the module docs).
#[derive(Debug, Clone)]
pub struct ArmModel {
    name: String,
    nq: usize,
    mu_v: f64,
    prismatic: Vec<bool>,
    backend: Backend,
}

impl ArmModel {
    /// The model of `scene` (any number of joints; a ball, if any, is ignored) and which
    /// kernels it runs on. Joint viscous friction μ_v is the scene's `friction.mu_v` (0 without
    /// `[friction]`).
    pub fn from_scene(scene: &Scene) -> Result<(Self, KernelSource)> {
        let nq = scene.links.len();
        let mu_v = scene.friction.as_ref().map_or(0.0, |f| f.mu_v);
        if let Some((entry, p)) = compiled_match(scene)
            && let (Some(mass_cqd_g), Some(potential)) = (entry.mass_cqd_g, entry.potential)
            && entry.nq == nq
        {
            let backend = Backend::Compiled {
                mass_cqd_g,
                potential,
                p,
            };
            let name = scene.name.clone();
            return Ok((
                ArmModel {
                    name,
                    nq,
                    mu_v,
                    prismatic: prismatic_joints(scene),
                    backend,
                },
                KernelSource::Compiled,
            ));
        }
        // Deep recursion in bf-codegen for long chains: build on a thread with a large stack.
        let backend = std::thread::scope(|s| {
            std::thread::Builder::new()
                .stack_size(256 << 20)
                .spawn_scoped(s, || interpreted(scene))
                .map_err(|e| crate::registry::thread_err(&scene.name, e))?
                .join()
                .map_err(|_| scene_err(&scene.name, "building the kernel graphs panicked"))?
        })?;
        Ok((
            ArmModel {
                name: scene.name.clone(),
                nq,
                mu_v,
                prismatic: prismatic_joints(scene),
                backend,
            },
            KernelSource::Interpreted,
        ))
    }

    /// Scene name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Which joints are prismatic (q_i in m, its force in N) rather than revolute (rad, N m),
    /// in joint order: the units of the arm's trajectory columns.
    pub fn prismatic(&self) -> &[bool] {
        &self.prismatic
    }

    /// Number of joints.
    pub fn nq(&self) -> usize {
        self.nq
    }

    /// Joint viscous friction μ_v (N m s/rad).
    pub fn mu_v(&self) -> f64 {
        self.mu_v
    }

    fn check(&self, what: &'static str, v: &[f64]) -> Result<()> {
        if v.len() != self.nq {
            return Err(scene_err(
                &self.name,
                format!(
                    "{what} has {} entries, the arm has {} joints",
                    v.len(),
                    self.nq
                ),
            ));
        }
        if !v.iter().all(|x| x.is_finite()) {
            return Err(ModelError::NonFinite { what });
        }
        Ok(())
    }

    /// M(q) and C(q, q̇) q̇ + g(q).
    pub fn mass_cqd_g(&self, q: &[f64], qd: &[f64]) -> Result<(DMatrix<f64>, DVector<f64>)> {
        self.check("joint angles", q)?;
        self.check("joint velocities", qd)?;
        let n = self.nq;
        let (m, c) = match &self.backend {
            Backend::Compiled { mass_cqd_g, p, .. } => {
                let mut m = vec![0.0; n * n];
                let mut c = vec![0.0; n];
                mass_cqd_g(q, qd, p, &mut m, &mut c);
                (m, c)
            }
            Backend::Interpreted {
                mass_cqd_g,
                layout,
                base_vars,
                ..
            } => {
                let mut v = base_vars.clone();
                for i in 0..n {
                    v[layout.q(i) as usize] = q[i];
                    v[layout.qd(i) as usize] = qd[i];
                }
                let out = mass_cqd_g.eval(&v);
                (out[..n * n].to_vec(), out[n * n..].to_vec())
            }
        };
        if !m.iter().chain(&c).all(|x| x.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "mass matrix or C q̇ + g",
            });
        }
        Ok((DMatrix::from_row_slice(n, n, &m), DVector::from_vec(c)))
    }

    /// U(q) (J).
    pub fn potential(&self, q: &[f64]) -> Result<f64> {
        self.check("joint angles", q)?;
        let u = match &self.backend {
            Backend::Compiled { potential, p, .. } => potential(q, p),
            Backend::Interpreted {
                potential,
                layout,
                base_vars,
                ..
            } => {
                let mut v = base_vars.clone();
                for (i, &x) in q.iter().enumerate() {
                    v[layout.q(i) as usize] = x;
                }
                potential.eval(&v)[0]
            }
        };
        if !u.is_finite() {
            return Err(ModelError::NonFinite {
                what: "potential energy",
            });
        }
        Ok(u)
    }

    /// q̈ from M q̈ = τ − C q̇ − g − μ_v q̇.
    pub fn accelerations(&self, q: &[f64], qd: &[f64], tau: &[f64]) -> Result<Vec<f64>> {
        self.check("joint torques", tau)?;
        let (m, cg) = self.mass_cqd_g(q, qd)?;
        let rhs = DVector::from_iterator(
            self.nq,
            (0..self.nq).map(|i| tau[i] - cg[i] - self.mu_v * qd[i]),
        );
        let chol = m
            .cholesky()
            .ok_or(ModelError::MassMatrixNotPositiveDefinite)?;
        Ok(chol.solve(&rhs).iter().copied().collect())
    }

    /// E = ½ q̇ᵀ M q̇ + U(q) (J).
    pub fn energy(&self, q: &[f64], qd: &[f64]) -> Result<f64> {
        let (m, _) = self.mass_cqd_g(q, qd)?;
        let v = DVector::from_column_slice(qd);
        Ok(0.5 * v.dot(&(&m * &v)) + self.potential(q)?)
    }

    /// dE/dt = τ·q̇ − μ_v |q̇|² (W).
    pub fn power(&self, qd: &[f64], tau: &[f64]) -> f64 {
        qd.iter()
            .zip(tau)
            .map(|(v, t)| t * v - self.mu_v * v * v)
            .sum()
    }
}

fn interpreted(scene: &Scene) -> Result<Backend> {
    let InterpretedTapes {
        tapes: [mass_cqd_g, potential],
        layout,
        base_vars,
    } = interpreted_tapes(scene, ["mass_cqd_g", "potential"])?;
    Ok(Backend::Interpreted {
        mass_cqd_g: Box::new(mass_cqd_g),
        potential: Box::new(potential),
        layout,
        base_vars,
    })
}

/// `true` for each prismatic joint of `scene`, in joint order.
fn prismatic_joints(scene: &Scene) -> Vec<bool> {
    scene
        .links
        .iter()
        .map(|l| l.joint == bf_scene::JointType::Prismatic)
        .collect()
}
