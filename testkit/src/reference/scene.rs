//! Building a [`Reference`] from a parsed [`Scene`]: the DH rows of Table 1 (Sect. 2.1, angles
//! in radians), the inertial data (full inertia tensors), base and tool transforms, ball and
//! contact kind, joint viscous friction μ_v; and setting a scene constant by its registry name
//! (to mirror a kernel call with runtime parameters).

use bf_codegen::spec::{Angle, ContactSpec, InertiaSpec, RotationSpec, Scene, TransformSpec};

use super::{ContactKind, Pose, RefBall, RefLink, Reference};
use crate::error::TestkitError;
use crate::small::*;

/// Angle of the scene file in radians.
pub fn angle_rad(a: &Angle) -> f64 {
    match *a {
        Angle::Radians(x) => x,
        Angle::PiMultiple { num, den } => num as f64 * std::f64::consts::PI / den as f64,
    }
}

fn rotation_of(spec: &RotationSpec) -> Result<[[f64; 3]; 3], TestkitError> {
    match spec {
        RotationSpec::Matrix(m) => Ok(*m),
        RotationSpec::Axis { axis, angle } => {
            let ax = match axis.to_ascii_lowercase().as_str() {
                "x" => 0,
                "y" => 1,
                "z" => 2,
                other => {
                    return Err(TestkitError::InvalidScene(format!(
                        "unknown rotation axis `{other}`"
                    )));
                }
            };
            Ok(axis_rotation(ax, angle_rad(angle)))
        }
    }
}

fn pose_of(spec: &TransformSpec) -> Result<Pose, TestkitError> {
    Ok(Pose {
        rotation: match &spec.rotation {
            Some(r) => rotation_of(r)?,
            None => Pose::IDENTITY.rotation,
        },
        translation: spec.translation.unwrap_or([0.0; 3]),
    })
}

fn inertia_of(spec: &InertiaSpec) -> [[f64; 3]; 3] {
    match spec {
        InertiaSpec::Diagonal([x, y, z]) => [[*x, 0.0, 0.0], [0.0, *y, 0.0], [0.0, 0.0, *z]],
        InertiaSpec::Full(m) => *m,
    }
}

fn contact_kind_of(spec: &ContactSpec) -> Result<ContactKind, TestkitError> {
    match spec.kind.as_str() {
        "segment" => Ok(ContactKind::Segment),
        "tip" => Ok(ContactKind::Tip),
        other => Err(TestkitError::InvalidScene(format!(
            "unknown contact kind `{other}`"
        ))),
    }
}
impl Reference {
    /// Build the reference model from a parsed scene.
    pub fn new(scene: &Scene) -> Result<Self, TestkitError> {
        if scene.links.is_empty() {
            return Err(TestkitError::InvalidScene("no links".into()));
        }
        let links = scene
            .links
            .iter()
            .map(|l| RefLink {
                a: l.a,
                alpha: angle_rad(&l.alpha),
                d: l.d,
                offset: l.offset.as_ref().map(angle_rad).unwrap_or(0.0),
                prismatic: l.joint == bf_codegen::spec::JointType::Prismatic,
                mass: l.mass,
                com: l.com,
                inertia: inertia_of(&l.inertia),
            })
            .collect();
        let contact_kind = match &scene.contact {
            Some(c) => Some(contact_kind_of(c)?),
            None => None,
        };
        Ok(Reference {
            convention: scene.dh,
            base: pose_of(&scene.base)?,
            tool: match &scene.tool {
                Some(t) => Some(pose_of(t)?),
                None => None,
            },
            gravity: scene.gravity,
            links,
            ball: scene.ball.as_ref().map(|b| RefBall {
                center: b.center,
                radius: b.radius,
            }),
            contact_kind,
            mu_v: scene.friction.as_ref().map(|f| f.mu_v).unwrap_or(0.0),
        })
    }

    /// Parse a scene file's text (e.g. a generated module's `SCENE_TOML`) and build the
    /// reference from it; `origin` names the text in error messages.
    pub fn from_scene_toml(text: &str, origin: &str) -> Result<Self, TestkitError> {
        let scene = Scene::from_toml_str(text, origin)
            .map_err(|e| TestkitError::InvalidScene(e.to_string()))?;
        Self::new(&scene)
    }
    /// Set a scene constant by its registry name (`Scene::constants()`, the names used in
    /// `runtime_parameters` / `PARAM_NAMES`): `gravity.x|y|z`, `base.translation.x|y|z`,
    /// `linkK.a|alpha|d|offset|mass`, `linkK.com.x|y|z`, `linkK.inertia.xx|xy|xz|yy|yz|zz`,
    /// `tool.translation.x|y|z`, `ball.radius`, `ball.center.x|y|z`, `friction.mu_v` (links
    /// numbered from 1). Constants that do not influence the reference (ball mass/inertia,
    /// μ_s, μ_k, D) are accepted and ignored.
    pub fn set_param(&mut self, name: &str, value: f64) -> Result<(), TestkitError> {
        let unknown = || TestkitError::UnknownParameter(name.to_string());
        let (xyz, sym) = (
            bf_codegen::spec::axis_index,
            bf_codegen::spec::inertia_index,
        );
        let parts: Vec<&str> = name.split('.').collect();
        match parts.as_slice() {
            ["gravity", c] => self.gravity[xyz(c).ok_or_else(unknown)?] = value,
            ["base", "translation", c] => {
                self.base.translation[xyz(c).ok_or_else(unknown)?] = value
            }
            ["tool", "translation", c] => {
                let t = self.tool.get_or_insert(Pose::IDENTITY);
                t.translation[xyz(c).ok_or_else(unknown)?] = value;
            }
            ["ball", "radius"] => self.ball.as_mut().ok_or(TestkitError::NoBall)?.radius = value,
            ["ball", "center", c] => {
                let i = xyz(c).ok_or_else(unknown)?;
                self.ball.as_mut().ok_or(TestkitError::NoBall)?.center[i] = value;
            }
            ["ball", "mass"] | ["ball", "inertia", _] => {}
            ["friction", "mu_v"] => self.mu_v = value,
            ["friction", "mu_s" | "mu_k" | "socket_damping"] => {}
            [link, rest @ ..] if link.starts_with("link") => {
                let i: usize = link[4..].parse().map_err(|_| unknown())?;
                if i == 0 || i > self.links.len() {
                    return Err(unknown());
                }
                let l = &mut self.links[i - 1];
                match rest {
                    ["a"] => l.a = value,
                    ["alpha"] => l.alpha = value,
                    ["d"] => l.d = value,
                    ["offset"] => l.offset = value,
                    ["mass"] => l.mass = value,
                    ["com", c] => l.com[xyz(c).ok_or_else(unknown)?] = value,
                    ["inertia", c] => {
                        let (r, cc) = sym(c).ok_or_else(unknown)?;
                        l.inertia[r][cc] = value;
                        l.inertia[cc][r] = value;
                    }
                    _ => return Err(unknown()),
                }
            }
            _ => return Err(unknown()),
        }
        Ok(())
    }

    /// Apply a whole runtime-parameter vector (`PARAM_NAMES`, values), e.g. to mirror a
    /// kernel call with non-default `p`.
    pub fn with_params(mut self, names: &[&str], values: &[f64]) -> Result<Self, TestkitError> {
        for (n, v) in names.iter().zip(values) {
            self.set_param(n, *v)?;
        }
        Ok(self)
    }
}
