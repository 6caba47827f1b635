//! An independent reference for URDF robots: the whole kinematic tree read straight from the
//! XML (its own reader, sharing nothing with bf-scene's import or bf-codegen), every link a
//! body, and Featherstone's spatial algebra on it:
//! * Plücker transforms X_i (parent → child motion coordinates) from the joint origins
//!   (xyz, rpy = R_z R_y R_x) and the joint motion, S_i = [u; 0] (revolute, continuous) or
//!   [0; u] (prismatic);
//! * RNEA on the tree: v_i = X_i v_p + S_i q̇_i, a_i = X_i a_p + S_i q̈_i + v_i ×ₘ S_i q̇_i,
//!   f_i = I_i a_i + v_i ×* I_i v_i, τ_i = S_iᵀ f_i, f_p += X_iᵀ f_i, gravity as the base
//!   acceleration −g₀ (so RNEA(q, q̇, 0) = C q̇ + g of paper eq. 22);
//! * CRBA on the tree: I^c_i = I_i + Σ X_cᵀ I^c_c X_c, M_ij = S_iᵀ X… I^c_j S_j;
//! * forward kinematics of any link.
//!
//! Joints that are not the model's (fixed ones, and every moving joint off the chosen chain)
//! stay in the tree with q = q̇ = q̈ = 0 — no lumping — so comparing the import (which merges
//! and lumps) against this checks the lumping too.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// A URDF joint as this reference reads it.
#[derive(Debug, Clone)]
struct RefJoint {
    name: String,
    kind: String,
    parent: usize,
    child: usize,
    rot: Matrix3<f64>,
    xyz: Vector3<f64>,
    axis: Vector3<f64>,
}

/// The URDF tree with spatial inertias about each link frame's origin.
#[derive(Debug, Clone)]
pub struct UrdfTree {
    names: Vec<String>,
    inertia: Vec<Matrix6<f64>>,
    joints: Vec<RefJoint>,
    /// The joint whose child each link is (`None` for the root).
    parent_joint: Vec<Option<usize>>,
    /// Links in an order where parents come first.
    order: Vec<usize>,
}

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

fn rpy(r: f64, p: f64, y: f64) -> Matrix3<f64> {
    let ((sr, cr), (sp, cp), (sy, cy)) = (libm::sincos(r), libm::sincos(p), libm::sincos(y));
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr);
    let ry = Matrix3::new(cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp);
    let rz = Matrix3::new(cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0);
    rz * ry * rx
}

/// Rotation by `q` about the unit axis `u` (Rodrigues, via the matrix exponential form).
fn axis_angle(u: &Vector3<f64>, q: f64) -> Matrix3<f64> {
    let k = skew(u);
    Matrix3::identity() + k * libm::sin(q) + k * k * (1.0 - libm::cos(q))
}

fn numbers(s: Option<&str>, default: &[f64]) -> Vec<f64> {
    match s {
        None => default.to_vec(),
        Some(t) => t
            .split_whitespace()
            .map(|x| x.parse::<f64>().unwrap_or(f64::NAN))
            .collect(),
    }
}

fn origin(n: roxmltree::Node) -> (Matrix3<f64>, Vector3<f64>) {
    match n
        .children()
        .find(|c| c.is_element() && c.has_tag_name("origin"))
    {
        None => (Matrix3::identity(), Vector3::zeros()),
        Some(o) => {
            let x = numbers(o.attribute("xyz"), &[0.0; 3]);
            let r = numbers(o.attribute("rpy"), &[0.0; 3]);
            (rpy(r[0], r[1], r[2]), Vector3::new(x[0], x[1], x[2]))
        }
    }
}

/// Motion cross product v ×ₘ m.
fn crm(v: &Vector6<f64>, m: &Vector6<f64>) -> Vector6<f64> {
    let (w, vl) = (v.fixed_rows::<3>(0), v.fixed_rows::<3>(3));
    let (mw, mv) = (m.fixed_rows::<3>(0), m.fixed_rows::<3>(3));
    let a = w.cross(&mw);
    let b = w.cross(&mv) + vl.cross(&mw);
    Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

/// Force cross product v ×* f (f = [moment; force]).
fn crf(v: &Vector6<f64>, f: &Vector6<f64>) -> Vector6<f64> {
    let (w, vl) = (v.fixed_rows::<3>(0), v.fixed_rows::<3>(3));
    let (n, fl) = (f.fixed_rows::<3>(0), f.fixed_rows::<3>(3));
    let a = w.cross(&n) + vl.cross(&fl);
    let b = w.cross(&fl);
    Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

impl UrdfTree {
    /// Reads the tree of a URDF text (well-formed, one root; the reference trusts its input).
    pub fn parse(text: &str) -> Result<UrdfTree, String> {
        let doc = roxmltree::Document::parse(text).map_err(|e| e.to_string())?;
        let root = doc.root_element();
        let mut names = Vec::new();
        let mut inertia = Vec::new();
        for l in root.children().filter(|c| c.has_tag_name("link")) {
            names.push(l.attribute("name").unwrap_or_default().to_string());
            let mut i6 = Matrix6::zeros();
            if let Some(i) = l.children().find(|c| c.has_tag_name("inertial")) {
                let (r, c) = origin(i);
                let m = i
                    .children()
                    .find(|c| c.has_tag_name("mass"))
                    .and_then(|m| m.attribute("value"))
                    .and_then(|v| v.parse::<f64>().ok())
                    .ok_or("inertial without mass")?;
                let t = i
                    .children()
                    .find(|c| c.has_tag_name("inertia"))
                    .ok_or("inertial without inertia")?;
                let g = |a: &str| {
                    t.attribute(a)
                        .and_then(|v| v.parse::<f64>().ok())
                        .unwrap_or(0.0)
                };
                let ic = Matrix3::new(
                    g("ixx"),
                    g("ixy"),
                    g("ixz"),
                    g("ixy"),
                    g("iyy"),
                    g("iyz"),
                    g("ixz"),
                    g("iyz"),
                    g("izz"),
                );
                let ic = r * ic * r.transpose();
                let cx = skew(&c);
                let top = ic + cx * cx.transpose() * m;
                i6.fixed_view_mut::<3, 3>(0, 0).copy_from(&top);
                i6.fixed_view_mut::<3, 3>(0, 3).copy_from(&(cx * m));
                i6.fixed_view_mut::<3, 3>(3, 0)
                    .copy_from(&(cx.transpose() * m));
                i6.fixed_view_mut::<3, 3>(3, 3)
                    .copy_from(&(Matrix3::identity() * m));
            }
            inertia.push(i6);
        }
        let find = |n: &str| names.iter().position(|x| x == n);
        let mut joints = Vec::new();
        let mut parent_joint = vec![None; names.len()];
        for j in root.children().filter(|c| c.has_tag_name("joint")) {
            let link = |tag: &str| {
                j.children()
                    .find(|c| c.has_tag_name(tag))
                    .and_then(|c| c.attribute("link"))
                    .and_then(find)
                    .ok_or(format!("joint without {tag}"))
            };
            let (rot, xyz) = origin(j);
            let a = j
                .children()
                .find(|c| c.has_tag_name("axis"))
                .map_or(vec![1.0, 0.0, 0.0], |a| {
                    numbers(a.attribute("xyz"), &[1.0, 0.0, 0.0])
                });
            let axis = Vector3::new(a[0], a[1], a[2]);
            let axis = if axis.norm() > 0.0 {
                axis.normalize()
            } else {
                axis
            };
            let child = link("child")?;
            parent_joint[child] = Some(joints.len());
            joints.push(RefJoint {
                name: j.attribute("name").unwrap_or_default().to_string(),
                kind: j.attribute("type").unwrap_or_default().to_string(),
                parent: link("parent")?,
                child,
                rot,
                xyz,
                axis,
            });
        }
        let mut order: Vec<usize> = (0..names.len())
            .filter(|&l| parent_joint[l].is_none())
            .collect();
        let mut k = 0;
        while k < order.len() {
            let p = order[k];
            order.extend(joints.iter().filter(|j| j.parent == p).map(|j| j.child));
            k += 1;
        }
        Ok(UrdfTree {
            names,
            inertia,
            joints,
            parent_joint,
            order,
        })
    }

    fn link(&self, name: &str) -> usize {
        self.names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no link {name}"))
    }

    /// The moving joints on the path base → tip, in order.
    ///
    /// # Panics
    /// If a link is unknown or `tip` is not below `base` (a reference for tests: its input is
    /// the tests' own files).
    pub fn chain(&self, base: &str, tip: &str) -> Vec<String> {
        let (b, mut l) = (self.link(base), self.link(tip));
        let mut out = Vec::new();
        while l != b {
            let j = &self.joints[self.parent_joint[l].expect("tip below base")];
            if j.kind != "fixed" {
                out.push(j.name.clone());
            }
            l = j.parent;
        }
        out.reverse();
        out
    }

    /// Joint coordinate of each link's parent joint: the chain's values, 0 elsewhere.
    fn coords(&self, chain: &[String], v: &[f64]) -> Vec<f64> {
        (0..self.names.len())
            .map(|l| {
                self.parent_joint[l]
                    .and_then(|j| chain.iter().position(|c| *c == self.joints[j].name))
                    .map_or(0.0, |k| v[k])
            })
            .collect()
    }

    /// (E, p): link `l`'s frame in its parent's, at joint coordinate `q`.
    fn local(&self, j: &RefJoint, q: f64) -> (Matrix3<f64>, Vector3<f64>) {
        match j.kind.as_str() {
            "revolute" | "continuous" => (j.rot * axis_angle(&j.axis, q), j.xyz),
            "prismatic" => (j.rot, j.xyz + j.rot * j.axis * q),
            _ => (j.rot, j.xyz),
        }
    }

    /// Plücker motion transform parent → child and the motion subspace S (zero if locked).
    /// Called only for links with a parent joint (every caller checks `parent_joint` first).
    fn x_and_s(&self, l: usize, chain: &[String], q: &[f64]) -> (Matrix6<f64>, Vector6<f64>) {
        let j = &self.joints[self.parent_joint[l].expect("not the root")];
        let (e, p) = self.local(j, q[l]);
        let et = e.transpose();
        let mut x = Matrix6::zeros();
        x.fixed_view_mut::<3, 3>(0, 0).copy_from(&et);
        x.fixed_view_mut::<3, 3>(3, 3).copy_from(&et);
        x.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-et * skew(&p)));
        let moving = chain.contains(&j.name);
        let u = j.axis;
        let s = match j.kind.as_str() {
            "revolute" | "continuous" if moving => Vector6::new(u.x, u.y, u.z, 0.0, 0.0, 0.0),
            "prismatic" if moving => Vector6::new(0.0, 0.0, 0.0, u.x, u.y, u.z),
            _ => Vector6::zeros(),
        };
        (x, s)
    }

    /// τ = M(q) q̈ + C(q, q̇) q̇ + g(q) of the chain joints `chain` (names), by RNEA on the whole
    /// tree; `gravity` in the root link's coordinates (the joints above the chain's base link
    /// stay locked at 0, so the base link sits where they put it).
    pub fn rnea(
        &self,
        chain: &[String],
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: [f64; 3],
    ) -> Vec<f64> {
        let (q, qd, qdd) = (
            self.coords(chain, q),
            self.coords(chain, qd),
            self.coords(chain, qdd),
        );
        let n = self.names.len();
        let mut v = vec![Vector6::zeros(); n];
        let mut a = vec![Vector6::zeros(); n];
        let mut f = vec![Vector6::zeros(); n];
        let mut xs = vec![(Matrix6::zeros(), Vector6::zeros()); n];
        for &l in &self.order {
            match self.parent_joint[l] {
                None => {
                    a[l] = Vector6::new(0.0, 0.0, 0.0, -gravity[0], -gravity[1], -gravity[2]);
                }
                Some(j) => {
                    let p = self.joints[j].parent;
                    let (x, s) = self.x_and_s(l, chain, &q);
                    v[l] = x * v[p] + s * qd[l];
                    a[l] = x * a[p] + s * qdd[l] + crm(&v[l], &(s * qd[l]));
                    xs[l] = (x, s);
                }
            }
            f[l] = self.inertia[l] * a[l] + crf(&v[l], &(self.inertia[l] * v[l]));
        }
        let mut tau = vec![0.0; chain.len()];
        for &l in self.order.iter().rev() {
            let Some(j) = self.parent_joint[l] else {
                continue;
            };
            let (x, s) = xs[l];
            if let Some(k) = chain.iter().position(|c| *c == self.joints[j].name) {
                tau[k] = s.dot(&f[l]);
            }
            let p = self.joints[j].parent;
            let up = x.transpose() * f[l];
            f[p] += up;
        }
        tau
    }

    /// M(q) of the chain joints by the composite-rigid-body algorithm on the whole tree.
    pub fn crba(&self, chain: &[String], q: &[f64]) -> Vec<Vec<f64>> {
        let qq = self.coords(chain, q);
        let n = self.names.len();
        let mut ic = self.inertia.clone();
        let mut xs = vec![(Matrix6::zeros(), Vector6::zeros()); n];
        for &l in &self.order {
            if self.parent_joint[l].is_some() {
                xs[l] = self.x_and_s(l, chain, &qq);
            }
        }
        for &l in self.order.iter().rev() {
            if let Some(j) = self.parent_joint[l] {
                let p = self.joints[j].parent;
                let x = xs[l].0;
                let moved = x.transpose() * ic[l] * x;
                ic[p] += moved;
            }
        }
        let nq = chain.len();
        let mut m = vec![vec![0.0; nq]; nq];
        let index = |l: usize| {
            self.parent_joint[l].and_then(|j| chain.iter().position(|c| *c == self.joints[j].name))
        };
        for &l in &self.order {
            let Some(i) = index(l) else { continue };
            let mut force = ic[l] * xs[l].1;
            m[i][i] = xs[l].1.dot(&force);
            let mut k = l;
            while let Some(j) = self.parent_joint[k] {
                force = xs[k].0.transpose() * force;
                k = self.joints[j].parent;
                if let Some(jj) = index(k) {
                    m[i][jj] = xs[k].1.dot(&force);
                    m[jj][i] = m[i][jj];
                }
            }
        }
        m
    }

    /// World pose (rotation, position) of link `name` in the root link's frame.
    ///
    /// # Panics
    /// If `name` is not a link.
    pub fn pose(&self, chain: &[String], q: &[f64], name: &str) -> (Matrix3<f64>, Vector3<f64>) {
        let qq = self.coords(chain, q);
        let mut l = self.link(name);
        let (mut r, mut t) = (Matrix3::identity(), Vector3::zeros());
        while let Some(j) = self.parent_joint[l] {
            let (e, p) = self.local(&self.joints[j], qq[l]);
            t = e * t + p;
            r = e * r;
            l = self.joints[j].parent;
        }
        (r, t)
    }
}
