//! The double-double reference of the kernel probes: a scene's expression graph (the graph
//! bf-codegen emits the kernels from) compiled into one interpreter tape over M (eq. 22a),
//! C q̇ (eq. 24), g, C q̇ + g and the exact and smooth contact geometry (eq. 2–7, 58–59),
//! evaluated in f64 or in double-double ([`bf_codegen::dd::Dd`], ≈ 106 bits).

use anyhow::{anyhow, bail};
use bf_codegen::dd::Dd;
use bf_codegen::interp::{Scalar, Tape};
use bf_codegen::spec::Scene;

/// Names and lengths of the interpreter outputs, in tape order.
const GROUPS: [(&str, usize); 16] = [
    ("M", 9),
    ("Cqd", 3),
    ("g", 3),
    ("Cqd_g", 3),
    ("alpha", 1),
    ("sat", 1),
    ("p_c", 3),
    ("h", 1),
    ("J_c", 9),
    ("r_c_norm", 1),
    ("sat_s", 1),
    ("p_c_s", 3),
    ("h_s", 1),
    ("J_c_s", 9),
    ("rc_dot_s", 3),
    ("jc_dot_qd_s", 3),
];

/// A scene's graph compiled into one [`Tape`] over the fixed output groups listed at
/// [`GraphValues::get`], evaluated in f64 or in double-double: the "same graph" the generator
/// emits for `mass_matrix`, `coriolis_qd`, `gravity`, `cqd_g`, `contact` and `contact_smooth`.
pub struct GraphEval {
    tape: Tape,
    nq: usize,
    n_vars: usize,
    param_names: Vec<String>,
    param_defaults: Vec<f64>,
}

/// Outputs of [`GraphEval`] by group name.
#[derive(Debug, Clone)]
pub struct GraphValues {
    vals: Vec<f64>,
}

impl GraphValues {
    /// The values of group `name` (see the module's group list: `M`, `Cqd`, `g`, `Cqd_g`,
    /// `alpha`, `sat`, `p_c`, `h`, `J_c`, `r_c_norm`, `sat_s`, `p_c_s`, `h_s`, `J_c_s`,
    /// `rc_dot_s`, `jc_dot_qd_s`); empty for an unknown name.
    pub fn get(&self, name: &str) -> &[f64] {
        let mut off = 0;
        for (n, len) in GROUPS {
            if n == name {
                return &self.vals[off..off + len];
            }
            off += len;
        }
        &[]
    }
    /// Every value.
    pub fn all(&self) -> &[f64] {
        &self.vals
    }
}

impl GraphEval {
    /// Build the graph of a 3-joint scene with `[ball]` and `[contact]`.
    pub fn new(scene: &Scene) -> anyhow::Result<Self> {
        let mut m = three_joint_model(scene)?;
        let mass = m.mass_matrix();
        let cqd = m.coriolis_qd();
        let g = m.gravity();
        let cqd_g = m.cqd_g();
        let c = m.contact(false)?;
        let cs = m.contact(true)?;
        let mut ids = Vec::new();
        ids.extend(mass.iter().flatten().copied());
        ids.extend(cqd);
        ids.extend(g);
        ids.extend(cqd_g);
        ids.push(c.alpha);
        ids.push(c.sat_alpha);
        ids.extend(c.p_c);
        ids.push(c.h);
        ids.extend(c.j_c.iter().flatten().copied());
        // |r_c| = h + r, the scale against which the error of h is measured.
        let rr = m.g.v3_dot(c.r_c, c.r_c);
        ids.push(m.g.sqrt(rr));
        ids.push(cs.sat_alpha);
        ids.extend(cs.p_c);
        ids.push(cs.h);
        ids.extend(cs.j_c.iter().flatten().copied());
        ids.extend(cs.rc_dot);
        ids.extend(cs.jc_dot_qd);
        debug_assert_eq!(ids.len(), GROUPS.iter().map(|g| g.1).sum::<usize>());
        Ok(GraphEval {
            tape: Tape::new(&m.g, &ids),
            nq: 3,
            n_vars: m.layout.n_vars(),
            param_names: m.params.iter().map(|p| p.0.clone()).collect(),
            param_defaults: m.params.iter().map(|p| p.1).collect(),
        })
    }

    /// Runtime parameter names (scene order) and their defaults.
    pub fn params(&self) -> (&[String], &[f64]) {
        (&self.param_names, &self.param_defaults)
    }

    fn vars<S: Scalar>(
        &self,
        q: &[f64; 3],
        qd: &[f64; 3],
        w: &[f64; 3],
        eps: f64,
        p: &[f64],
    ) -> Vec<S> {
        let mut v = vec![S::from_f64(0.0); self.n_vars];
        let n = self.nq;
        for i in 0..n {
            v[i] = S::from_f64(q[i]);
            v[n + i] = S::from_f64(qd[i]);
        }
        for i in 0..3 {
            v[2 * n + i] = S::from_f64(w[i]);
        }
        v[2 * n + 3] = S::from_f64(eps);
        for (i, &pv) in p.iter().enumerate().take(self.n_vars - 2 * n - 4) {
            v[2 * n + 4 + i] = S::from_f64(pv);
        }
        v
    }

    /// Evaluate in f64 (`p`: runtime parameters; pass `params().1` for the defaults).
    pub fn eval_f64(
        &self,
        q: &[f64; 3],
        qd: &[f64; 3],
        w: &[f64; 3],
        eps: f64,
        p: &[f64],
    ) -> GraphValues {
        GraphValues {
            vals: self.tape.eval::<f64>(&self.vars(q, qd, w, eps, p)),
        }
    }

    /// Evaluate in double-double, rounded to f64.
    pub fn eval_dd(
        &self,
        q: &[f64; 3],
        qd: &[f64; 3],
        w: &[f64; 3],
        eps: f64,
        p: &[f64],
    ) -> GraphValues {
        GraphValues {
            vals: self
                .tape
                .eval::<Dd>(&self.vars(q, qd, w, eps, p))
                .into_iter()
                .map(|d| d.to_f64())
                .collect(),
        }
    }
}

/// The expression graph of `scene`, which must have the 3 joints of the contact model.
pub(super) fn three_joint_model(scene: &Scene) -> anyhow::Result<bf_codegen::SymbolicRobot> {
    let m = bf_codegen::SymbolicRobot::new(scene)?;
    if m.nq() != 3 {
        bail!(
            "scene `{}` has {} joints, the probes need 3",
            scene.name,
            m.nq()
        );
    }
    Ok(m)
}

/// The paper scene as compiled into `bf_generated::paper`.
pub(super) fn paper_scene_spec() -> anyhow::Result<Scene> {
    Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "paper").map_err(|e| anyhow!("{e}"))
}

/// The human scene as compiled into `bf_generated::human`.
pub(super) fn human_scene_spec() -> anyhow::Result<Scene> {
    Scene::from_toml_str(bf_generated::human::SCENE_TOML, "human").map_err(|e| anyhow!("{e}"))
}
