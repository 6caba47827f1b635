//! A [`bf_model::Kernels`] implementation on the bf-codegen interpreter (f64), for scenes that
//! have no compiled module (a moved ball, a scaled scene). Its tapes are the kernel definitions
//! the generator emits — `mass_cqd_g` (eq. 22a, 24), `potential` (eq. 22b), `contact`
//! (eq. 2–13) and `contact_smooth` (eq. 58–59), taken from [`bf_codegen::kernels::build_kernel`]
//! — so the model's physics and its NaN screening can be probed at states the compiled scenes
//! cannot reach (e.g. α exactly at a saturation corner) with the expressions of the compiled
//! kernels.

use anyhow::{Context, anyhow, bail};
use bf_codegen::interp::Tape;
use bf_codegen::kernels::{CONTACT_FIELDS, Dim, build_kernel};
use bf_codegen::spec::Scene;
use bf_model::{ContactGeometry, ContactVariant, Kernels};

use super::graph_eval::three_joint_model;

/// The fields [`ContactGeometry::from_arrays`] takes, in its argument order, with their lengths
/// for 3 joints.
const GEOMETRY_FIELDS: [(&str, usize); 12] = [
    ("alpha", 1),
    ("sat_alpha", 1),
    ("p_c", 3),
    ("r_c", 3),
    ("h", 1),
    ("n", 3),
    ("j_c", 9),
    ("v_c", 3),
    ("delta_v", 3),
    ("h_dot", 1),
    ("rc_dot", 3),
    ("jc_dot_qd", 3),
];

/// Offsets of [`GEOMETRY_FIELDS`] in the flat outputs of the `contact` kernels, found by name
/// in bf-codegen's [`CONTACT_FIELDS`] (the emitted `Contact` struct's layout).
fn geometry_offsets() -> anyhow::Result<[usize; 12]> {
    let mut layout = Vec::with_capacity(CONTACT_FIELDS.len());
    let mut off = 0;
    for (name, dims, _) in CONTACT_FIELDS {
        let len: usize = dims
            .iter()
            .map(|d| match d {
                Dim::Nq => 3,
                Dim::Lit(n) => *n,
            })
            .product();
        layout.push((*name, off, len));
        off += len;
    }
    let mut offsets = [0; 12];
    for (slot, (name, len)) in offsets.iter_mut().zip(GEOMETRY_FIELDS) {
        let &(_, at, n) = layout
            .iter()
            .find(|f| f.0 == name)
            .with_context(|| format!("bf-codegen's Contact has no field `{name}`"))?;
        if n != len {
            bail!("bf-codegen's Contact field `{name}` has {n} values, expected {len}");
        }
        *slot = at;
    }
    Ok(offsets)
}

/// A [`Kernels`] implementation on the interpreter (see the module documentation).
#[derive(Debug)]
pub struct InterpKernels {
    name: String,
    toml: String,
    mass_cqd_g: Tape,
    potential: Tape,
    exact: Tape,
    smooth: Tape,
    contact_offsets: [usize; 12],
    n_vars: usize,
    names: Vec<&'static str>,
    values: Vec<f64>,
}

impl InterpKernels {
    /// Build from the text of a 3-joint contact scene (`name` names it in errors); `runtime`
    /// names the constants kept as parameters (their values start at the scene's values;
    /// change them with [`InterpKernels::set`]).
    pub fn new(toml: &str, name: &str, runtime: &[&'static str]) -> anyhow::Result<Self> {
        let mut scene = Scene::from_toml_str(toml, name).map_err(|e| anyhow!("{e}"))?;
        scene.runtime_parameters = runtime.iter().map(|s| s.to_string()).collect();
        let mut m = three_joint_model(&scene)?;
        let mut tape = |kernel: &str| -> anyhow::Result<Tape> {
            let def = build_kernel(&mut m, kernel)
                .with_context(|| format!("kernel `{kernel}` of scene `{}`", scene.name))?;
            let ids: Vec<_> = def
                .outputs
                .iter()
                .flat_map(|o| o.ids.iter().copied())
                .collect();
            Ok(Tape::new(&m.g, &ids))
        };
        let mass_cqd_g = tape("mass_cqd_g")?;
        let potential = tape("potential")?;
        let exact = tape("contact")?;
        let smooth = tape("contact_smooth")?;
        Ok(InterpKernels {
            name: scene.name.clone(),
            toml: toml.to_string(),
            mass_cqd_g,
            potential,
            exact,
            smooth,
            contact_offsets: geometry_offsets()?,
            n_vars: m.layout.n_vars(),
            names: runtime.to_vec(),
            values: m.params.iter().map(|p| p.1).collect(),
        })
    }

    /// Set runtime parameter `name`; error if it is not one.
    pub fn set(&mut self, name: &str, value: f64) -> anyhow::Result<()> {
        let i = self
            .names
            .iter()
            .position(|n| *n == name)
            .with_context(|| format!("`{name}` is not a runtime parameter"))?;
        self.values[i] = value;
        Ok(())
    }

    fn vars(&self, q: &[f64; 3], qd: &[f64; 3], w: &[f64; 3], eps: f64) -> Vec<f64> {
        let mut v = vec![0.0; self.n_vars];
        v[..3].copy_from_slice(q);
        v[3..6].copy_from_slice(qd);
        v[6..9].copy_from_slice(w);
        v[9] = eps;
        v[10..].copy_from_slice(&self.values);
        v
    }
}

impl Kernels for InterpKernels {
    fn scene_name(&self) -> &str {
        &self.name
    }
    fn scene_toml(&self) -> &str {
        &self.toml
    }
    fn param_names(&self) -> &[&str] {
        &self.names
    }
    fn param_values(&self) -> &[f64] {
        &self.values
    }
    fn mass_cqd_g(&self, q: &[f64; 3], qd: &[f64; 3]) -> ([[f64; 3]; 3], [f64; 3]) {
        let v = self
            .mass_cqd_g
            .eval::<f64>(&self.vars(q, qd, &[0.0; 3], 0.0));
        let m = [[v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]];
        (m, [v[9], v[10], v[11]])
    }
    fn potential(&self, q: &[f64; 3]) -> f64 {
        self.potential
            .eval::<f64>(&self.vars(q, &[0.0; 3], &[0.0; 3], 0.0))[0]
    }
    fn contact(
        &self,
        q: &[f64; 3],
        qd: &[f64; 3],
        omega: &[f64; 3],
        variant: ContactVariant,
    ) -> ContactGeometry {
        let v = match variant {
            ContactVariant::Exact => self.exact.eval::<f64>(&self.vars(q, qd, omega, 0.0)),
            ContactVariant::Smooth(e) => self.smooth.eval::<f64>(&self.vars(q, qd, omega, e)),
        };
        let o = &self.contact_offsets;
        let a3 = |k: usize| [v[o[k]], v[o[k] + 1], v[o[k] + 2]];
        let j = o[6];
        let jc = [
            [v[j], v[j + 1], v[j + 2]],
            [v[j + 3], v[j + 4], v[j + 5]],
            [v[j + 6], v[j + 7], v[j + 8]],
        ];
        ContactGeometry::from_arrays(
            v[o[0]],
            v[o[1]],
            &a3(2),
            &a3(3),
            v[o[4]],
            &a3(5),
            &jc,
            &a3(7),
            &a3(8),
            v[o[9]],
            &a3(10),
            &a3(11),
        )
    }
}
