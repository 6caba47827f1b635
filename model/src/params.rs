//! Physical parameters used by the physics layer (not by the kernels): ball inertia I_b (eq. 25,
//! full 3×3), ball radius r (eq. 4), Coulomb μ_s (eq. 18–19) and μ_k (eq. 20), joint viscous
//! friction μ_v (eq. 24) and socket damping D (eq. 25). Always validated: a [`Params`] value
//! cannot hold NaN, negative friction, a non-positive radius or a non-SPD inertia.

use crate::linalg::{Mat3, Spd3, mat_from_rows};
use crate::{ModelError, Result};

/// Validated physical parameters of the ball and of friction.
///
/// Construct with [`Params::new`]; modify with the `with_*` methods (which re-validate).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    ball_inertia: Mat3,
    ball_inertia_inv: Mat3,
    ball_radius: f64,
    mu_s: f64,
    mu_k: f64,
    mu_v: f64,
    socket_damping: f64,
}

fn nonneg(name: &'static str, v: f64) -> Result<()> {
    if !v.is_finite() {
        return Err(ModelError::InvalidParameter {
            name,
            value: v,
            reason: "must be finite",
        });
    }
    if v < 0.0 {
        return Err(ModelError::InvalidParameter {
            name,
            value: v,
            reason: "must be >= 0",
        });
    }
    Ok(())
}

impl Params {
    /// Validate and build.
    ///
    /// - `ball_inertia`: I_b about the ball centre, world axes (kg m²); symmetric positive
    ///   definite, need not be isotropic.
    /// - `ball_radius`: r > 0 (m).
    /// - `mu_s`, `mu_k`: static / kinetic Coulomb coefficients ≥ 0.
    /// - `mu_v`: joint viscous friction ≥ 0 (N m s/rad).
    /// - `socket_damping`: D ≥ 0 (N m s), torque −D ω on the ball.
    pub fn new(
        ball_inertia: Mat3,
        ball_radius: f64,
        mu_s: f64,
        mu_k: f64,
        mu_v: f64,
        socket_damping: f64,
    ) -> Result<Self> {
        if !ball_radius.is_finite() || ball_radius <= 0.0 {
            return Err(ModelError::InvalidParameter {
                name: "ball_radius",
                value: ball_radius,
                reason: "must be finite and > 0",
            });
        }
        nonneg("mu_s", mu_s)?;
        nonneg("mu_k", mu_k)?;
        nonneg("mu_v", mu_v)?;
        nonneg("socket_damping", socket_damping)?;
        if let Some(bad) = ball_inertia.iter().find(|v| !v.is_finite()) {
            return Err(ModelError::InvalidParameter {
                name: "ball_inertia",
                value: *bad,
                reason: "entries must be finite",
            });
        }
        let scale = ball_inertia.amax();
        let asym = (ball_inertia - ball_inertia.transpose()).amax();
        if asym > 1e-12 * scale {
            return Err(ModelError::InvalidParameter {
                name: "ball_inertia",
                value: asym,
                reason: "must be symmetric (value = largest asymmetry)",
            });
        }
        let chol = Spd3::factor(&ball_inertia)
            .filter(|c| c.rcond > 1e-14)
            .ok_or(ModelError::InvalidParameter {
                name: "ball_inertia",
                value: ball_inertia.min(),
                reason: "must be positive definite",
            })?;
        let ball_inertia_inv = chol.solve_mat(&Mat3::identity());
        Ok(Self {
            ball_inertia,
            ball_inertia_inv,
            ball_radius,
            mu_s,
            mu_k,
            mu_v,
            socket_damping,
        })
    }

    /// Build from a scene's `[ball]` and `[friction]` sections (I_b defaults to (2/5) m r² 1).
    pub fn from_scene(scene: &bf_scene::Scene) -> Result<Self> {
        let err = |m: &str| ModelError::Scene {
            scene: scene.name.clone(),
            message: m.to_string(),
        };
        let c = bf_scene::Constants::of(scene).ok_or_else(|| err("no [ball] section"))?;
        if scene.friction.is_none() {
            return Err(err("no [friction] section"));
        }
        Self::from_constants(&c)
    }

    /// Build from the scene constants (validated here).
    pub fn from_constants(c: &bf_scene::Constants) -> Result<Self> {
        Self::new(
            mat_from_rows(&c.ib),
            c.radius,
            c.mu_s,
            c.mu_k,
            c.mu_v,
            c.damping,
        )
    }

    /// I_b (kg m²).
    pub fn ball_inertia(&self) -> &Mat3 {
        &self.ball_inertia
    }
    /// I_b⁻¹ (cached).
    pub fn ball_inertia_inv(&self) -> &Mat3 {
        &self.ball_inertia_inv
    }
    /// Ball radius r (m).
    pub fn ball_radius(&self) -> f64 {
        self.ball_radius
    }
    /// Static Coulomb coefficient μ_s.
    pub fn mu_s(&self) -> f64 {
        self.mu_s
    }
    /// Kinetic Coulomb coefficient μ_k.
    pub fn mu_k(&self) -> f64 {
        self.mu_k
    }
    /// Joint viscous friction μ_v (N m s/rad).
    pub fn mu_v(&self) -> f64 {
        self.mu_v
    }
    /// Socket damping D (N m s).
    pub fn socket_damping(&self) -> f64 {
        self.socket_damping
    }

    /// Copy with another ball inertia (validated).
    pub fn with_ball_inertia(&self, ib: Mat3) -> Result<Self> {
        Self::new(
            ib,
            self.ball_radius,
            self.mu_s,
            self.mu_k,
            self.mu_v,
            self.socket_damping,
        )
    }
    /// Copy with other Coulomb coefficients (validated).
    pub fn with_coulomb(&self, mu_s: f64, mu_k: f64) -> Result<Self> {
        Self::new(
            self.ball_inertia,
            self.ball_radius,
            mu_s,
            mu_k,
            self.mu_v,
            self.socket_damping,
        )
    }
    /// Copy with other viscous coefficients μ_v and D (validated).
    pub fn with_viscous(&self, mu_v: f64, socket_damping: f64) -> Result<Self> {
        Self::new(
            self.ball_inertia,
            self.ball_radius,
            self.mu_s,
            self.mu_k,
            mu_v,
            socket_damping,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok() -> Params {
        Params::new(Mat3::identity() * 0.008, 1.0, 0.8, 0.6, 1e-3, 4e-3).unwrap()
    }

    #[test]
    fn rejects_bad_values_with_names() {
        let p = ok();
        let e = p.with_coulomb(0.8, -0.1).unwrap_err();
        assert!(
            matches!(e, ModelError::InvalidParameter { name: "mu_k", .. }),
            "{e}"
        );
        assert!(e.to_string().contains("mu_k") && e.to_string().contains(">= 0"));
        let e = Params::new(Mat3::identity(), 0.0, 0.8, 0.6, 0.0, 0.0).unwrap_err();
        assert!(matches!(
            e,
            ModelError::InvalidParameter {
                name: "ball_radius",
                ..
            }
        ));
        let e = p.with_viscous(f64::NAN, 0.0).unwrap_err();
        assert!(matches!(
            e,
            ModelError::InvalidParameter { name: "mu_v", .. }
        ));
        assert!(e.to_string().contains("finite"));
        let e = p.with_viscous(0.0, f64::INFINITY).unwrap_err();
        assert!(matches!(
            e,
            ModelError::InvalidParameter {
                name: "socket_damping",
                ..
            }
        ));
        let mut ib = Mat3::identity();
        ib[(0, 1)] = 0.5;
        let e = p.with_ball_inertia(ib).unwrap_err();
        assert!(e.to_string().contains("symmetric"));
        let e = p.with_ball_inertia(Mat3::from_diagonal(&crate::Vec3::new(1.0, -1.0, 1.0)));
        assert!(e.unwrap_err().to_string().contains("positive definite"));
        let mut ib = Mat3::identity();
        ib[(2, 2)] = f64::NAN;
        assert!(p.with_ball_inertia(ib).is_err());
    }

    #[test]
    fn inverse_inertia_is_inverse_for_anisotropic() {
        let ib = Mat3::new(2.0, 0.3, -0.1, 0.3, 1.5, 0.2, -0.1, 0.2, 1.0) * 1e-3;
        let p = ok().with_ball_inertia(ib).unwrap();
        assert!((p.ball_inertia() * p.ball_inertia_inv() - Mat3::identity()).amax() < 1e-12);
    }
}
